// NRRD reader and writer, the subset CT volumes use: 3D, short or float, raw or gzip encoding,
// attached or detached data, space directions and origin in LPS (RAS is converted).
// Reference: http://teem.sourceforge.net/nrrd/format.html
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

}  // namespace

bool volume_io_has_gzip() {
#ifdef PCISIM_ANATOMY_HAVE_ZLIB
  return true;
#else
  return false;
#endif
}

Volume read_nrrd(const std::string& path, bool require_spacing) {
  const std::string text = io::read_file(path);
  if (text.size() < 8 || text.compare(0, 7, "NRRD000") != 0 || text[7] < '1' || text[7] > '5') {
    fail(path, "magic", "the file does not start with NRRD0001..NRRD0005");
  }
  std::map<std::string, std::string> fields;  // lower-case field -> value
  size_t pos = text.find('\n');
  pos = pos == std::string::npos ? text.size() : pos + 1;
  size_t data_start = text.size();
  while (pos < text.size()) {
    size_t eol = text.find('\n', pos);
    if (eol == std::string::npos) eol = text.size();
    std::string_view line(text.data() + pos, eol - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos = std::min(eol + 1, text.size());
    if (line.empty()) {  // the blank line ends the header; attached data follows
      data_start = pos;
      break;
    }
    if (line.front() == '#') continue;
    if (line.find(":=") != std::string_view::npos) continue;  // key/value pairs carry nothing we use
    const size_t colon = line.find(": ");
    if (colon == std::string_view::npos) {
      fail(path, "header", fmt::format("line '{}' is not 'field: value'", line.substr(0, 60)));
    }
    fields[io::lower(io::trim(line.substr(0, colon)))] = std::string(io::trim(line.substr(colon + 2)));
  }
  auto get = [&](const char* k) -> const std::string* {
    const auto it = fields.find(k);
    return it == fields.end() ? nullptr : &it->second;
  };
  auto require = [&](const char* k) -> const std::string& {
    const std::string* v = get(k);
    if (!v) fail(path, k, "missing");
    return *v;
  };

  Volume vol;
  {
    const std::string t = io::lower(require("type"));
    if (t == "short" || t == "signed short" || t == "short int" || t == "signed short int" || t == "int16" ||
        t == "int16_t") {
      vol.type = VoxelType::kInt16;
    } else if (t == "float") {
      vol.type = VoxelType::kFloat32;
    } else {
      fail(path, "type", fmt::format("unsupported '{}' (expected short or float)", t));
    }
  }
  {
    int64_t n = 0;
    const std::string& v = require("dimension");
    if (!io::parse_int64s(v, 1, &n) || n != 3) fail(path, "dimension", fmt::format("expected 3, got '{}'", v));
  }
  {
    const std::string& v = require("sizes");
    int64_t d[3];
    if (!io::parse_int64s(v, 3, d) || d[0] <= 0 || d[1] <= 0 || d[2] <= 0) {
      fail(path, "sizes", fmt::format("expected 3 positive integers, got '{}'", v));
    }
    vol.dims = {d[0], d[1], d[2]};
  }
  const std::string encoding = io::lower(require("encoding"));
  const bool gzip = encoding == "gzip" || encoding == "gz";
  if (encoding != "raw" && !gzip) {
    fail(path, "encoding", fmt::format("unsupported '{}' (expected raw or gzip)", encoding));
  }
  if (gzip && !volume_io_has_gzip()) {
    fail(path, "encoding", "gzip needs zlib, which this build lacks; re-save the volume with raw encoding");
  }
  bool big_endian = false;
  if (const auto* v = get("endian")) {
    const std::string e = io::lower(*v);
    if (e != "little" && e != "big") fail(path, "endian", fmt::format("expected little or big, got '{}'", *v));
    big_endian = e == "big";
  }
  Eigen::Matrix3d flip = Eigen::Matrix3d::Identity();  // space -> LPS
  if (const auto* v = get("space")) {
    const std::string s = io::lower(*v);
    if (s == "right-anterior-superior" || s == "ras") {
      flip.diagonal() << -1, -1, 1;
    } else if (s != "left-posterior-superior" && s != "lps") {
      fail(path, "space",
           fmt::format("unsupported '{}' (expected left-posterior-superior or "
                       "right-anterior-superior)",
                       *v));
    }
  } else if (const auto* v = get("space dimension")) {
    int64_t n = 0;
    if (!io::parse_int64s(*v, 1, &n) || n != 3) fail(path, "space dimension", fmt::format("expected 3, got '{}'", *v));
  }
  if (const auto* v = get("space directions")) {
    double m[9];
    if (!io::parse_doubles(*v, 9, m, /*loose=*/true)) {
      fail(path, "space directions", fmt::format("expected three vectors (x,y,z), got '{}'", *v));
    }
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d axis = flip * Eigen::Vector3d(m[3 * c], m[3 * c + 1], m[3 * c + 2]);
      const double len = axis.norm();
      if (!(len > 0) || !std::isfinite(len))
        fail(path, "space directions", fmt::format("axis {} has zero or non-finite length", c));
      vol.spacing_mm[c] = len;
      vol.direction.col(c) = axis / len;
    }
    if (std::abs(vol.direction.determinant()) < 1e-6) fail(path, "space directions", "the axes are linearly dependent");
  } else if (const auto* v = get("spacings")) {
    double s[3];
    if (!io::parse_doubles(*v, 3, s) || !(s[0] > 0 && s[1] > 0 && s[2] > 0)) {
      fail(path, "spacings", fmt::format("expected 3 positive numbers, got '{}'", *v));
    }
    vol.spacing_mm = Eigen::Vector3d(s[0], s[1], s[2]);
  } else if (require_spacing) {
    // a CT without its voxel size would be simulated at a made-up scale
    fail(path, "space directions", "missing (neither 'space directions' nor 'spacings': a CT needs its voxel spacing)");
  }
  if (const auto* v = get("space origin")) {
    double o[3];
    if (!io::parse_doubles(*v, 3, o, /*loose=*/true) || !Eigen::Vector3d(o[0], o[1], o[2]).allFinite()) {
      fail(path, "space origin", fmt::format("expected (x,y,z), got '{}'", *v));
    }
    vol.origin_mm = flip * Eigen::Vector3d(o[0], o[1], o[2]);
  }
  if (const auto* v = get("line skip"); v && *v != "0") fail(path, "line skip", "only 0 is supported");
  int64_t byte_skip = 0;
  if (const auto* v = get("byte skip")) {
    if (!io::parse_int64s(*v, 1, &byte_skip) || byte_skip < -1) {
      fail(path, "byte skip", fmt::format("expected an integer >= -1, got '{}'", *v));
    }
    if (byte_skip == -1 && gzip) fail(path, "byte skip", "-1 is only allowed with raw encoding");
  }

  std::string external;
  const char* bytes = text.data() + data_start;
  int64_t available = static_cast<int64_t>(text.size() - data_start);
  std::string data_name = path;
  const std::string* data_file = get("data file");
  if (!data_file) data_file = get("datafile");
  if (data_file) {
    if (data_file->find(' ') != std::string::npos || io::lower(*data_file).rfind("list", 0) == 0) {
      fail(path, "data file", fmt::format("only one file name is supported, got '{}'", *data_file));
    }
    data_name = data_file->front() == '/' ? *data_file : io::folder_of(path) + *data_file;
    try {
      external = io::read_file(data_name);
    } catch (const VolumeIoError& e) {
      fail(path, "data file", fmt::format("cannot open '{}' ({})", data_name, e.what()));
    }
    bytes = external.data();
    available = static_cast<int64_t>(external.size());
  }
  io::load_voxels(path,
                  {.bytes = bytes,
                   .available = available,
                   .skip = byte_skip,
                   .compressed = gzip,
                   .big_endian = big_endian,
                   .data_name = data_name,
                   .size_field = "sizes",
                   .skip_field = "byte skip",
                   .compression_field = "encoding"},
                  vol);
  return vol;
}

void write_nrrd(const Volume& v, const std::string& path, bool gzip) {
  if (const std::string bad = validate(v); !bad.empty()) {
    throw VolumeIoError(fmt::format("{}: volume: {}", io::base_name(path), bad));
  }
  if (gzip && !volume_io_has_gzip()) {
    throw VolumeIoError(fmt::format("{}: encoding: gzip needs zlib, which this build lacks", io::base_name(path)));
  }
  std::string h = "NRRD0004\n# written by pcisim\n";
  h += fmt::format("type: {}\ndimension: 3\nspace: left-posterior-superior\n",
                   v.type == VoxelType::kInt16 ? "short" : "float");
  h += fmt::format("sizes: {} {} {}\n", v.dims[0], v.dims[1], v.dims[2]);
  h += "space directions:";
  for (int c = 0; c < 3; ++c) {
    const Eigen::Vector3d a = v.direction.col(c) * v.spacing_mm[c];
    h += fmt::format(" ({:.17g},{:.17g},{:.17g})", a.x(), a.y(), a.z());
  }
  h += "\nkinds: domain domain domain\nendian: little\n";
  h += fmt::format("encoding: {}\n", gzip ? "gzip" : "raw");
  h += fmt::format("space origin: ({:.17g},{:.17g},{:.17g})\n\n", v.origin_mm.x(), v.origin_mm.y(), v.origin_mm.z());
  if (gzip) {
    std::string packed;
    if (!io::deflate_gzip(v.data(), v.data_bytes(), &packed)) {
      throw VolumeIoError(fmt::format("{}: encoding: gzip compression failed", io::base_name(path)));
    }
    io::write_file(path, h, packed.data(), static_cast<int64_t>(packed.size()));
  } else {
    io::write_file(path, h, v.data(), v.data_bytes());
  }
}

Volume read_volume(const std::string& path, bool require_spacing) {
  const std::string l = io::lower(path);
  auto ends = [&l](const char* s) {
    const size_t n = std::strlen(s);
    return l.size() >= n && l.compare(l.size() - n, n, s) == 0;
  };
  if (ends(".mha") || ends(".mhd")) return read_metaimage(path, require_spacing);
  if (ends(".nrrd") || ends(".nhdr")) return read_nrrd(path, require_spacing);
  throw VolumeIoError(fmt::format("{}: file name: expected .mha, .mhd, .nrrd or .nhdr", io::base_name(path)));
}

}  // namespace pcisim::anatomy
