// MetaImage (ITK MetaIO) reader and writer. Format: "Key = Value" lines, ElementDataFile last;
// TransformMatrix lists the physical direction of index axis i, then j, then k (as ITK writes it).
// Reference: https://itk.org/Wiki/ITK/MetaIO/Documentation
#include <Eigen/LU>
#include <algorithm>
#include <cstring>
#include <fmt/format.h>
#include <map>

#include "anatomy/volume/io_text.h"
#include "anatomy/volume/volume_io.h"

namespace pcisim::anatomy {
namespace {

[[noreturn]] void fail(const std::string& file, std::string_view field, const std::string& what) {
  throw VolumeIoError(fmt::format("{}: {}: {}", io::base_name(file), field, what));
}

bool parse_bool(std::string_view v, bool* out) {
  const std::string l = io::lower(v);
  if (l == "true" || l == "1") return *out = true, true;
  if (l == "false" || l == "0") return *out = false, true;
  return false;
}

}  // namespace

Volume read_metaimage(const std::string& path, bool require_spacing, DataFileScope data_files) {
  const std::string text = io::read_file(path);
  std::map<std::string, std::string> keys;  // lower-case key -> value
  std::map<std::string, std::string> spelled;
  size_t pos = 0;
  size_t data_start = std::string::npos;
  while (pos < text.size()) {
    size_t eol = text.find('\n', pos);
    if (eol == std::string::npos) eol = text.size();
    const std::string_view line = io::trim(std::string_view(text).substr(pos, eol - pos));
    pos = eol + 1;
    if (line.empty()) continue;
    const size_t eq = line.find('=');
    if (eq == std::string_view::npos) {
      fail(path, "header", fmt::format("line '{}' is not 'Key = Value'", line.substr(0, 60)));
    }
    const std::string key(io::trim(line.substr(0, eq)));
    const std::string value(io::trim(line.substr(eq + 1)));
    if (key.empty()) fail(path, "header", "a line has an empty key");
    keys[io::lower(key)] = value;
    spelled[io::lower(key)] = key;
    if (io::lower(key) == "elementdatafile") {
      data_start = std::min(pos, text.size());
      break;
    }
  }
  if (data_start == std::string::npos) fail(path, "ElementDataFile", "missing (it must be the last key)");
  auto get = [&](const char* k) -> const std::string* {
    const auto it = keys.find(io::lower(k));
    return it == keys.end() ? nullptr : &it->second;
  };
  auto require = [&](const char* k) -> const std::string& {
    const std::string* v = get(k);
    if (!v) fail(path, k, "missing");
    return *v;
  };

  if (const auto* v = get("ObjectType"); v && io::lower(*v) != "image") {
    fail(path, "ObjectType", fmt::format("expected 'Image', got '{}'", *v));
  }
  {
    int64_t ndims = 0;
    const std::string& v = require("NDims");
    if (!io::parse_int64s(v, 1, &ndims) || ndims != 3) {
      fail(path, "NDims", fmt::format("expected 3, got '{}'", v));
    }
  }
  if (const auto* v = get("ElementNumberOfChannels")) {
    int64_t c = 0;
    if (!io::parse_int64s(*v, 1, &c) || c != 1) {
      fail(path, "ElementNumberOfChannels", fmt::format("expected 1, got '{}'", *v));
    }
  }
  Volume vol;
  {
    const std::string& v = require("DimSize");
    int64_t d[3];
    if (!io::parse_int64s(v, 3, d) || d[0] <= 0 || d[1] <= 0 || d[2] <= 0) {
      fail(path, "DimSize", fmt::format("expected 3 positive integers, got '{}'", v));
    }
    vol.dims = {d[0], d[1], d[2]};
  }
  {
    const std::string& v = require("ElementType");
    if (v == "MET_SHORT") {
      vol.type = VoxelType::kInt16;
    } else if (v == "MET_FLOAT") {
      vol.type = VoxelType::kFloat32;
    } else {
      fail(path, "ElementType", fmt::format("unsupported '{}' (expected MET_SHORT or MET_FLOAT)", v));
    }
  }
  // a CT without its voxel size would be simulated at a made-up scale
  if (require_spacing && !get("ElementSpacing") && !get("ElementSize"))
    fail(path, "ElementSpacing", "missing (a CT needs its voxel spacing)");
  for (const char* k : {"ElementSpacing", "ElementSize"}) {
    if (const auto* v = get(k)) {
      double s[3];
      if (!io::parse_doubles(*v, 3, s) || !(s[0] > 0 && s[1] > 0 && s[2] > 0)) {
        fail(path, k, fmt::format("expected 3 positive numbers, got '{}'", *v));
      }
      vol.spacing_mm = Eigen::Vector3d(s[0], s[1], s[2]);
      break;
    }
  }
  for (const char* k : {"Offset", "Origin", "Position"}) {
    if (const auto* v = get(k)) {
      double o[3];
      if (!io::parse_doubles(*v, 3, o) || !Eigen::Vector3d(o[0], o[1], o[2]).allFinite()) {
        fail(path, k, fmt::format("expected 3 numbers, got '{}'", *v));
      }
      vol.origin_mm = Eigen::Vector3d(o[0], o[1], o[2]);
      break;
    }
  }
  for (const char* k : {"TransformMatrix", "Rotation", "Orientation"}) {
    if (const auto* v = get(k)) {
      double m[9];
      if (!io::parse_doubles(*v, 9, m)) fail(path, k, fmt::format("expected 9 numbers, got '{}'", *v));
      for (int c = 0; c < 3; ++c) vol.direction.col(c) = Eigen::Vector3d(m[3 * c], m[3 * c + 1], m[3 * c + 2]);
      if (!vol.direction.allFinite() || std::abs(vol.direction.determinant()) < 1e-6) {
        fail(path, k, "the direction matrix is singular");
      }
      break;
    }
  }
  bool msb = false;
  for (const char* k : {"BinaryDataByteOrderMSB", "ElementByteOrderMSB"}) {
    if (const auto* v = get(k); v && !parse_bool(*v, &msb)) {
      fail(path, k, fmt::format("expected True or False, got '{}'", *v));
    }
  }
  if (const auto* v = get("BinaryData")) {
    bool binary = true;
    if (!parse_bool(*v, &binary) || !binary) fail(path, "BinaryData", "only binary data is supported");
  }
  bool compressed = false;
  if (const auto* v = get("CompressedData"); v && !parse_bool(*v, &compressed)) {
    fail(path, "CompressedData", fmt::format("expected True or False, got '{}'", *v));
  }
  if (compressed && !volume_io_has_gzip()) {
    fail(path, "CompressedData", "compressed data needs zlib, which this build lacks");
  }
  int64_t header_size = 0;
  if (const auto* v = get("HeaderSize"); v && (!io::parse_int64s(*v, 1, &header_size) || header_size < -1)) {
    fail(path, "HeaderSize", fmt::format("expected an integer >= -1, got '{}'", *v));
  }

  // the data: inline after the header, or in a file beside the header
  const std::string& data_file = require("ElementDataFile");
  std::string external;
  const char* bytes = nullptr;
  int64_t available = 0;
  std::string data_name = path;
  if (io::lower(data_file) == "local") {
    bytes = text.data() + data_start;
    available = static_cast<int64_t>(text.size() - data_start);
  } else {
    if (data_file.find(' ') != std::string::npos || data_file.find('%') != std::string::npos ||
        io::lower(data_file) == "list") {
      fail(path, "ElementDataFile", fmt::format("only LOCAL or one file name is supported, got '{}'", data_file));
    }
    external = io::read_data_file(path, data_file, data_files, "ElementDataFile", &data_name);
    bytes = external.data();
    available = static_cast<int64_t>(external.size());
  }
  // a compressed file's HeaderSize -1 has no meaning (its size is not the voxels'): ignored
  io::load_voxels(path,
                  {.bytes = bytes,
                   .available = available,
                   .skip = header_size == -1 && compressed ? 0 : header_size,
                   .compressed = compressed,
                   .big_endian = msb,
                   .data_name = data_name,
                   .size_field = "DimSize",
                   .skip_field = "HeaderSize",
                   .compression_field = "CompressedData"},
                  vol);
  return vol;
}

void write_metaimage(const Volume& v, const std::string& path) {
  if (const std::string bad = validate(v); !bad.empty()) {
    throw VolumeIoError(fmt::format("{}: volume: {}", io::base_name(path), bad));
  }
  const std::string ext = io::lower(path.size() >= 4 ? path.substr(path.size() - 4) : path);
  if (ext != ".mha" && ext != ".mhd") {
    throw VolumeIoError(fmt::format("{}: file name: expected .mha or .mhd", io::base_name(path)));
  }
  const bool inline_data = ext == ".mha";
  const std::string raw_path = path.substr(0, path.size() - 4) + ".raw";
  const Eigen::Matrix3d& d = v.direction;
  std::string h;
  h += "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n";
  h += "CompressedData = False\n";
  h += fmt::format("TransformMatrix = {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g}\n",
                   d(0, 0), d(1, 0), d(2, 0), d(0, 1), d(1, 1), d(2, 1), d(0, 2), d(1, 2), d(2, 2));
  h += fmt::format("Offset = {:.17g} {:.17g} {:.17g}\n", v.origin_mm.x(), v.origin_mm.y(), v.origin_mm.z());
  // ITK's "RAI" names the same frame as DICOM LPS
  h += "AnatomicalOrientation = RAI\n";
  h += fmt::format("ElementSpacing = {:.17g} {:.17g} {:.17g}\n", v.spacing_mm.x(), v.spacing_mm.y(), v.spacing_mm.z());
  h += fmt::format("DimSize = {} {} {}\n", v.dims[0], v.dims[1], v.dims[2]);
  h += fmt::format("ElementType = {}\n", v.type == VoxelType::kInt16 ? "MET_SHORT" : "MET_FLOAT");
  if (inline_data) {
    h += "ElementDataFile = LOCAL\n";
    io::write_file(path, h, v.data(), v.data_bytes());
  } else {
    h += fmt::format("ElementDataFile = {}\n", io::base_name(raw_path));
    io::write_file(path, h, nullptr, 0);
    io::write_file(raw_path, std::string(), v.data(), v.data_bytes());
  }
}

}  // namespace pcisim::anatomy
