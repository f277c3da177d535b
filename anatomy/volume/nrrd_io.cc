// NRRD reader and writer, the subset CT volumes use: 3D, short or float, raw or gzip encoding,
// attached or detached data, space directions and origin in LPS (RAS is converted); and 4-D
// sequences of such volumes whose 4th axis is time (x fastest, time slowest).
// Reference: http://teem.sourceforge.net/nrrd/format.html
#include <Eigen/LU>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fmt/format.h>
#include <map>
#include <vector>

#include "anatomy/volume/io_text.h"
#include "anatomy/volume/volume_io.h"

namespace pcisim::anatomy {
namespace {

[[noreturn]] void fail(const std::string& file, std::string_view field, const std::string& what) {
  throw VolumeIoError(fmt::format("{}: {}: {}", io::base_name(file), field, what));
}

// the file's bytes and its header's fields (lower-case name -> value); the data starts after the
// blank line that ends the header (or at the end when there is none)
struct Header {
  std::string text;
  std::map<std::string, std::string> fields;
  size_t data_start = 0;

  const std::string* get(const char* k) const {
    const auto it = fields.find(k);
    return it == fields.end() ? nullptr : &it->second;
  }
};

Header read_header(const std::string& path) {
  Header h;
  h.text = io::read_file(path);
  const std::string& text = h.text;
  if (text.size() < 8 || text.compare(0, 7, "NRRD000") != 0 || text[7] < '1' || text[7] > '5') {
    fail(path, "magic", "the file does not start with NRRD0001..NRRD0005");
  }
  size_t pos = text.find('\n');
  pos = pos == std::string::npos ? text.size() : pos + 1;
  h.data_start = text.size();
  while (pos < text.size()) {
    size_t eol = text.find('\n', pos);
    if (eol == std::string::npos) eol = text.size();
    std::string_view line(text.data() + pos, eol - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos = std::min(eol + 1, text.size());
    if (line.empty()) {  // the blank line ends the header; attached data follows
      h.data_start = pos;
      break;
    }
    if (line.front() == '#') continue;
    if (line.find(":=") != std::string_view::npos) continue;  // key/value pairs carry nothing we use
    const size_t colon = line.find(": ");
    if (colon == std::string_view::npos) {
      fail(path, "header", fmt::format("line '{}' is not 'field: value'", line.substr(0, 60)));
    }
    h.fields[io::lower(io::trim(line.substr(0, colon)))] = std::string(io::trim(line.substr(colon + 2)));
  }
  return h;
}

// the entries of a per-axis field, split at blanks outside parentheses: "(1, 0,0) none" gives
// "(1, 0,0)" and "none"
std::vector<std::string> axis_entries(std::string_view v) {
  std::vector<std::string> out;
  size_t i = 0;
  auto blank = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  while (i < v.size()) {
    while (i < v.size() && blank(v[i])) ++i;
    if (i == v.size()) break;
    const size_t start = i;
    if (v[i] == '(') {
      const size_t close = v.find(')', i);
      i = close == std::string_view::npos ? v.size() : close + 1;
    } else {
      while (i < v.size() && !blank(v[i])) ++i;
    }
    out.emplace_back(v.substr(start, i - start));
  }
  return out;
}

// what the header says before any voxel is read: one frame's grid (dims, spacing, origin,
// direction, type; no voxels), the number of frames (0: a 3-D volume) and how the voxels are stored
struct Layout {
  Volume grid;
  int64_t frames = 0;
  bool gzip = false, big_endian = false;
  int64_t byte_skip = 0;
};

// sequence: the file must be 4-D (x y z time), else 3-D; each refusal names the field
Layout parse_layout(const std::string& path, const Header& h, bool require_spacing, bool sequence) {
  auto require = [&](const char* k) -> const std::string& {
    const std::string* v = h.get(k);
    if (!v) fail(path, k, "missing");
    return *v;
  };
  Layout out;
  Volume& vol = out.grid;
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
    const bool is_int = io::parse_int64s(v, 1, &n);
    if (!sequence) {
      if (is_int && n == 4) {
        fail(path, "dimension",
             fmt::format("expected 3, got '{}': a 4-D file holds a sequence of volumes (x y z time); read it with "
                         "read_nrrd_sequence (pcisim-model motion --sequence FILE)",
                         v));
      }
      if (!is_int || n != 3) fail(path, "dimension", fmt::format("expected 3, got '{}'", v));
    } else {
      if (is_int && n == 3) {
        fail(path, "dimension",
             fmt::format("expected 4 (x y z time), got '{}': a 3-D file holds one volume, not a sequence (read it "
                         "with read_nrrd; give a sequence of 3-D files as a folder or one file per frame)",
                         v));
      }
      if (!is_int || n != 4) fail(path, "dimension", fmt::format("expected 4 (x y z time), got '{}'", v));
    }
  }
  {
    const std::string& v = require("sizes");
    int64_t d[4] = {0, 0, 0, 1};
    const int n = sequence ? 4 : 3;
    if (!io::parse_int64s(v, n, d) || d[0] <= 0 || d[1] <= 0 || d[2] <= 0 || d[3] <= 0) {
      fail(path, "sizes",
           sequence ? fmt::format("expected 4 positive integers (x y z time), got '{}'", v)
                    : fmt::format("expected 3 positive integers, got '{}'", v));
    }
    if (sequence && d[3] < 2) {
      fail(path, "sizes",
           fmt::format("the time axis has {} frame: a sequence needs at least 2 (one volume belongs in a 3-D file)",
                       d[3]));
    }
    vol.dims = {d[0], d[1], d[2]};
    if (sequence) {
      out.frames = d[3];
      // the whole sequence is read as one block: its count checked here, before any product can
      // overflow, with the 4-D sizes in the message
      int64_t count = 1;
      for (const int64_t s : d) {
        if (s > io::kMaxVoxels || count > io::kMaxVoxels / s) {
          fail(path, "sizes",
               fmt::format("{} x {} x {} voxels x {} frames: over the {} voxel limit", d[0], d[1], d[2], d[3],
                           io::kMaxVoxels));
        }
        count *= s;
      }
    }
  }
  if (const auto* v = h.get("kinds"); v && sequence) {
    // x, y, z first and the frames last; anything else (a vector-valued volume, time first) is
    // another layout that would be read as the wrong voxels
    std::vector<std::string> k = axis_entries(*v);
    if (k.size() != 4) fail(path, "kinds", fmt::format("expected 4 kinds (x y z time), got '{}'", *v));
    for (std::string& s : k) s = io::lower(s);
    for (int a = 0; a < 3; ++a) {
      if (k[a] != "domain" && k[a] != "space") {
        fail(path, "kinds",
             fmt::format("axis {} is '{}' in '{}': a sequence has x, y, z first (domain or space) and time last", a,
                         k[a], *v));
      }
    }
    if (k[3] != "time" && k[3] != "list" && k[3] != "none" && k[3] != "???") {
      fail(path, "kinds", fmt::format("axis 3 is '{}' in '{}': expected time, list or none (the frames)", k[3], *v));
    }
  }
  const std::string encoding = io::lower(require("encoding"));
  out.gzip = encoding == "gzip" || encoding == "gz";
  if (encoding != "raw" && !out.gzip) {
    fail(path, "encoding", fmt::format("unsupported '{}' (expected raw or gzip)", encoding));
  }
  if (out.gzip && !volume_io_has_gzip()) {
    fail(path, "encoding", "gzip needs zlib, which this build lacks; re-save the volume with raw encoding");
  }
  if (const auto* v = h.get("endian")) {
    const std::string e = io::lower(*v);
    if (e != "little" && e != "big") fail(path, "endian", fmt::format("expected little or big, got '{}'", *v));
    out.big_endian = e == "big";
  }
  Eigen::Matrix3d flip = Eigen::Matrix3d::Identity();  // space -> LPS
  if (const auto* v = h.get("space")) {
    const std::string s = io::lower(*v);
    if (s == "right-anterior-superior" || s == "ras") {
      flip.diagonal() << -1, -1, 1;
    } else if (s != "left-posterior-superior" && s != "lps") {
      fail(path, "space",
           fmt::format("unsupported '{}' (expected left-posterior-superior or "
                       "right-anterior-superior)",
                       *v));
    }
  } else if (const auto* v = h.get("space dimension")) {
    int64_t n = 0;
    if (!io::parse_int64s(*v, 1, &n) || n != 3) fail(path, "space dimension", fmt::format("expected 3, got '{}'", *v));
  }
  if (const auto* v = h.get("space directions")) {
    double m[9];
    if (!sequence) {
      if (!io::parse_doubles(*v, 9, m, /*loose=*/true)) {
        fail(path, "space directions", fmt::format("expected three vectors (x,y,z), got '{}'", *v));
      }
    } else {
      // three vectors, then none for the time axis
      const std::vector<std::string> e = axis_entries(*v);
      if (e.size() != 4) {
        fail(path, "space directions", fmt::format("expected (x,y,z) (x,y,z) (x,y,z) none, got '{}'", *v));
      }
      if (io::lower(e[3]) != "none") {
        fail(path, "space directions",
             fmt::format("the 4th (time) axis has the direction '{}': a sequence's time axis has none (expected "
                         "'none' last)",
                         e[3]));
      }
      for (int c = 0; c < 3; ++c) {
        if (!io::parse_doubles(e[c], 3, m + 3 * c, /*loose=*/true)) {
          fail(path, "space directions", fmt::format("axis {} is '{}', expected a vector (x,y,z)", c, e[c]));
        }
      }
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
  } else if (const auto* v = h.get("spacings")) {
    double s[4];
    // a sequence's time axis has a spacing too (NaN by the spec, or the frame period): not used
    if (!io::parse_doubles(*v, sequence ? 4 : 3, s) || !(s[0] > 0 && s[1] > 0 && s[2] > 0)) {
      fail(path, "spacings",
           sequence ? fmt::format("expected 3 positive numbers and the time axis's (nan or a number), got '{}'", *v)
                    : fmt::format("expected 3 positive numbers, got '{}'", *v));
    }
    vol.spacing_mm = Eigen::Vector3d(s[0], s[1], s[2]);
  } else if (require_spacing) {
    // a CT without its voxel size would be simulated at a made-up scale
    fail(path, "space directions", "missing (neither 'space directions' nor 'spacings': a CT needs its voxel spacing)");
  }
  if (const auto* v = h.get("space origin")) {
    double o[3];
    if (!io::parse_doubles(*v, 3, o, /*loose=*/true) || !Eigen::Vector3d(o[0], o[1], o[2]).allFinite()) {
      fail(path, "space origin", fmt::format("expected (x,y,z), got '{}'", *v));
    }
    vol.origin_mm = flip * Eigen::Vector3d(o[0], o[1], o[2]);
  }
  if (const auto* v = h.get("line skip"); v && *v != "0") fail(path, "line skip", "only 0 is supported");
  if (const auto* v = h.get("byte skip")) {
    if (!io::parse_int64s(*v, 1, &out.byte_skip) || out.byte_skip < -1) {
      fail(path, "byte skip", fmt::format("expected an integer >= -1, got '{}'", *v));
    }
    if (out.byte_skip == -1 && out.gzip) fail(path, "byte skip", "-1 is only allowed with raw encoding");
  }
  return out;
}

// the voxels: a 3-D volume, or a sequence's frames stacked along z (frame t is slices t Z .. t Z + Z - 1,
// which is the file's order: x fastest, time slowest)
Volume load_block(const std::string& path, const Header& h, const Layout& layout, DataFileScope data_files) {
  Volume block = layout.grid;
  if (layout.frames > 0) block.dims[2] *= layout.frames;  // parse_layout checked the product
  std::string external;
  const char* bytes = h.text.data() + h.data_start;
  int64_t available = static_cast<int64_t>(h.text.size() - h.data_start);
  std::string data_name = path;
  const std::string* data_file = h.get("data file");
  if (!data_file) data_file = h.get("datafile");
  if (data_file) {
    if (data_file->empty()) fail(path, "data file", "empty (expected a file name)");
    if (data_file->find(' ') != std::string::npos || io::lower(*data_file).rfind("list", 0) == 0) {
      fail(path, "data file", fmt::format("only one file name is supported, got '{}'", *data_file));
    }
    external = io::read_data_file(path, *data_file, data_files, "data file", &data_name);
    bytes = external.data();
    available = static_cast<int64_t>(external.size());
  }
  const Volume& g = layout.grid;
  if (layout.frames > 0 && !layout.gzip && layout.byte_skip >= 0 && layout.byte_skip <= available &&
      available - layout.byte_skip != block.data_bytes()) {
    // load_voxels would say the same of the stacked block; this names the frames
    fail(path, "sizes",
         fmt::format("{}x{}x{} {} voxels x {} frames need {} bytes but the data ({}) holds {}", g.dims[0], g.dims[1],
                     g.dims[2], voxel_type_name(g.type), layout.frames, block.data_bytes(), io::base_name(data_name),
                     available - layout.byte_skip));
  }
  try {
    io::load_voxels(path,
                    {.bytes = bytes,
                     .available = available,
                     .skip = layout.byte_skip,
                     .compressed = layout.gzip,
                     .big_endian = layout.big_endian,
                     .data_name = data_name,
                     .size_field = "sizes",
                     .skip_field = "byte skip",
                     .compression_field = "encoding"},
                    block);
  } catch (const VolumeIoError& e) {
    if (layout.frames == 0) throw;
    throw VolumeIoError(fmt::format("{} (the {} frames of {}x{}x{} read as one {}x{}x{} block: frame = k / {})",
                                    e.what(), layout.frames, g.dims[0], g.dims[1], g.dims[2], block.dims[0],
                                    block.dims[1], block.dims[2], g.dims[2]));
  }
  return block;
}

// the header write_nrrd and write_nrrd_sequence write: frames 0 for a 3-D volume, else the 4th
// axis (time, no direction)
std::string header_text(const Volume& v, int64_t frames, bool gzip) {
  std::string h = "NRRD0004\n# written by pcisim\n";
  h += fmt::format("type: {}\ndimension: {}\nspace: left-posterior-superior\n",
                   v.type == VoxelType::kInt16 ? "short" : "float", frames > 0 ? 4 : 3);
  h += fmt::format("sizes: {} {} {}", v.dims[0], v.dims[1], v.dims[2]);
  if (frames > 0) h += fmt::format(" {}", frames);
  h += "\nspace directions:";
  for (int c = 0; c < 3; ++c) {
    const Eigen::Vector3d a = v.direction.col(c) * v.spacing_mm[c];
    h += fmt::format(" ({:.17g},{:.17g},{:.17g})", a.x(), a.y(), a.z());
  }
  if (frames > 0) h += " none";
  h += frames > 0 ? "\nkinds: domain domain domain time" : "\nkinds: domain domain domain";
  h += "\nendian: little\n";
  h += fmt::format("encoding: {}\n", gzip ? "gzip" : "raw");
  h += fmt::format("space origin: ({:.17g},{:.17g},{:.17g})\n\n", v.origin_mm.x(), v.origin_mm.y(), v.origin_mm.z());
  return h;
}

void write_data(const std::string& path, const std::string& header, const void* data, int64_t bytes, bool gzip) {
  if (gzip) {
    std::string packed;
    if (!io::deflate_gzip(data, bytes, &packed)) {
      throw VolumeIoError(fmt::format("{}: encoding: gzip compression failed", io::base_name(path)));
    }
    io::write_file(path, header, packed.data(), static_cast<int64_t>(packed.size()));
  } else {
    io::write_file(path, header, data, bytes);
  }
}

}  // namespace

bool volume_io_has_gzip() {
#ifdef PCISIM_ANATOMY_HAVE_ZLIB
  return true;
#else
  return false;
#endif
}

Volume read_nrrd(const std::string& path, bool require_spacing, DataFileScope data_files) {
  const Header h = read_header(path);
  return load_block(path, h, parse_layout(path, h, require_spacing, /*sequence=*/false), data_files);
}

std::vector<Volume> read_nrrd_sequence(const std::string& path, bool require_spacing, DataFileScope data_files) {
  const Header h = read_header(path);
  const Layout layout = parse_layout(path, h, require_spacing, /*sequence=*/true);
  const Volume block = load_block(path, h, layout, data_files);
  const Volume& g = layout.grid;
  const int64_t frame_bytes = g.data_bytes();
  std::vector<Volume> frames;
  frames.reserve(static_cast<size_t>(layout.frames));
  for (int64_t t = 0; t < layout.frames; ++t) {
    Volume f = Volume::make(g.dims, g.spacing_mm, g.origin_mm, g.type);
    f.direction = g.direction;
    std::memcpy(f.data(), static_cast<const char*>(block.data()) + t * frame_bytes, static_cast<size_t>(frame_bytes));
    frames.push_back(std::move(f));
  }
  return frames;
}

void write_nrrd(const Volume& v, const std::string& path, bool gzip) {
  if (const std::string bad = validate(v); !bad.empty()) {
    throw VolumeIoError(fmt::format("{}: volume: {}", io::base_name(path), bad));
  }
  if (gzip && !volume_io_has_gzip()) {
    throw VolumeIoError(fmt::format("{}: encoding: gzip needs zlib, which this build lacks", io::base_name(path)));
  }
  write_data(path, header_text(v, 0, gzip), v.data(), v.data_bytes(), gzip);
}

void write_nrrd_sequence(const std::vector<Volume>& frames, const std::string& path, bool gzip) {
  const std::string name = io::base_name(path);
  if (frames.size() < 2) {
    throw VolumeIoError(fmt::format("{}: frames: a sequence needs at least 2, got {}", name, frames.size()));
  }
  if (gzip && !volume_io_has_gzip()) {
    throw VolumeIoError(fmt::format("{}: encoding: gzip needs zlib, which this build lacks", name));
  }
  const Volume& f0 = frames[0];
  for (size_t f = 0; f < frames.size(); ++f) {
    const Volume& v = frames[f];
    if (const std::string bad = validate(v); !bad.empty()) {
      throw VolumeIoError(fmt::format("{}: frame {}: {}", name, f, bad));
    }
    auto differs = [&](const char* what) {
      throw VolumeIoError(fmt::format("{}: frame {}: {} from frame 0's (a sequence has one grid)", name, f, what));
    };
    if (v.dims != f0.dims) {
      differs(fmt::format("dims {}x{}x{} differ", v.dims[0], v.dims[1], v.dims[2]).c_str());
    }
    if (v.type != f0.type) differs("voxel type differs");
    if (v.spacing_mm != f0.spacing_mm) differs("spacing differs");
    if (v.origin_mm != f0.origin_mm) differs("origin differs");
    if (v.direction != f0.direction) differs("direction differs");
  }
  // the reader's limit, so that what is written can be read back
  const int64_t n = static_cast<int64_t>(frames.size());
  if (f0.voxel_count() > io::kMaxVoxels / n) {
    throw VolumeIoError(fmt::format("{}: sizes: {} x {} x {} voxels x {} frames: over the {} voxel limit", name,
                                    f0.dims[0], f0.dims[1], f0.dims[2], n, io::kMaxVoxels));
  }
  const int64_t frame_bytes = f0.data_bytes();
  std::string data(static_cast<size_t>(frame_bytes * n), '\0');
  for (int64_t f = 0; f < n; ++f) std::memcpy(data.data() + f * frame_bytes, frames[f].data(), frame_bytes);
  write_data(path, header_text(f0, n, gzip), data.data(), static_cast<int64_t>(data.size()), gzip);
}

Volume read_volume(const std::string& path, bool require_spacing, DataFileScope data_files) {
  const std::string l = io::lower(path);
  auto ends = [&l](const char* s) {
    const size_t n = std::strlen(s);
    return l.size() >= n && l.compare(l.size() - n, n, s) == 0;
  };
  if (ends(".mha") || ends(".mhd")) return read_metaimage(path, require_spacing, data_files);
  if (ends(".nrrd") || ends(".nhdr")) return read_nrrd(path, require_spacing, data_files);
  throw VolumeIoError(fmt::format("{}: file name: expected .mha, .mhd, .nrrd or .nhdr", io::base_name(path)));
}

}  // namespace pcisim::anatomy
