#include "anatomy/mesh/mesh_io.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <unordered_map>

#include "anatomy/volume/io_text.h"

namespace pcisim::anatomy {
namespace {

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw MeshIoError(path + ": " + what);
}

std::string extension_of(const std::string& path) {
  const auto dot = path.find_last_of('.');
  return dot == std::string::npos ? "" : io::lower(path.substr(dot));
}

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

// a whole word as a number, as `>>` reads one (a leading '+' allowed); false for anything else,
// trailing characters included. A float out of float's range is parsed as a double and rounded
// (1e-50 -> 0, 1e50 -> inf: the callers refuse what is not finite).
template <class T>
bool parse_number(std::string_view w, T& out) {
  if (w.size() > 1 && w[0] == '+' && w[1] != '-' && w[1] != '+') w.remove_prefix(1);
  const char* end = w.data() + w.size();
  std::from_chars_result r = std::from_chars(w.data(), end, out);
  if constexpr (std::is_same_v<T, float>) {
    if (r.ec == std::errc::result_out_of_range) {
      double d = 0;
      r = std::from_chars(w.data(), end, d);
      out = static_cast<float>(d);
    }
  }
  return r.ec == std::errc() && r.ptr == end;
}

// a length in file units as metres. Millimetres move the word's decimal exponent by 3 before its
// one rounding to double: parsing and then x 1e-3 rounds twice, and about 1 value in 7 came back
// an ulp off, so a surface written in millimetres (write_ply_mm) would not read back bit for bit
bool parse_length(std::string_view w, double metres_per_unit, double& out_m) {
  double v = 0;
  if (!parse_number(w, v)) return false;
  out_m = v * metres_per_unit;
  if (metres_per_unit != kMillimetre || !std::isfinite(v)) return true;
  const size_t e = w.find_first_of("eE");
  int exponent = 0;
  if (e != std::string_view::npos && !parse_number(w.substr(e + 1), exponent)) return true;
  if (exponent < -100000 || exponent > 100000) return true;  // "0e-2147483648": no overflow below
  const std::string_view mantissa = w.substr(0, e);
  char buf[64];
  if (mantissa.size() + 16 > sizeof buf) return true;  // a word that long keeps the rounded product
  const auto r = fmt::format_to_n(buf, sizeof buf, "{}e{}", mantissa, exponent - 3);
  double exact = 0;
  if (parse_number(std::string_view(buf, r.size), exact)) out_m = exact;
  return true;
}

// the whitespace-separated words of a file's bytes, read in place (the file is never copied into
// a stream: a 500 MB ASCII mesh stays 500 MB)
class Words {
 public:
  explicit Words(std::string_view text) : text_(text) {}
  bool next(std::string_view& word) {
    while (pos_ < text_.size() && is_space(text_[pos_])) ++pos_;
    if (pos_ == text_.size()) return false;
    const size_t start = pos_;
    while (pos_ < text_.size() && !is_space(text_[pos_])) ++pos_;
    word = text_.substr(start, pos_ - start);
    return true;
  }
  template <class T>
  bool number(T& out) {
    std::string_view w;
    return next(w) && parse_number(w, out);
  }
  bool length(double metres_per_unit, double& out_m) {
    std::string_view w;
    return next(w) && parse_length(w, metres_per_unit, out_m);
  }

 private:
  std::string_view text_;
  size_t pos_ = 0;
};

// the lines of a file's bytes, in place ('\n' ends a line; a '\r' before it is whitespace)
class Lines {
 public:
  explicit Lines(std::string_view text) : text_(text) {}
  bool next(std::string_view& line) {
    if (pos_ >= text_.size()) return false;
    const size_t end = std::min(text_.find('\n', pos_), text_.size());
    line = text_.substr(pos_, end - pos_);
    pos_ = end + 1;
    return true;
  }

 private:
  std::string_view text_;
  size_t pos_ = 0;
};

// one vertex per distinct position, in order of first appearance (STL repeats every corner)
class Welder {
 public:
  explicit Welder(TriangleMesh& mesh) : mesh_(mesh) {}
  int add(const std::array<float, 3>& p, double scale) {
    auto [it, fresh] = index_.try_emplace(p, static_cast<int>(mesh_.vertices_m.size()));
    if (fresh) mesh_.vertices_m.emplace_back(p[0] * scale, p[1] * scale, p[2] * scale);
    return it->second;
  }

 private:
  TriangleMesh& mesh_;
  std::map<std::array<float, 3>, int> index_;
};

void check_finite(const std::string& path, const Eigen::Vector3d& v, size_t index) {
  if (!v.allFinite()) fail(path, fmt::format("vertex {} is not finite", index));
}

// the caller's bound on a mesh's size (kNoTriangleLimit: the file's size alone bounds it)
struct MeshLimit {
  int64_t triangles;
  // a mesh's triangles use at most 3 vertices each: more can only be padding
  int64_t vertices() const { return triangles > INT64_MAX / 4 ? INT64_MAX : 3 * triangles + 3; }
};

[[noreturn]] void too_many(const std::string& path, const char* field, int64_t n, const char* what, int64_t limit) {
  if (n < 0) fail(path, fmt::format("{}: more than {} {} (the limit for this mesh)", field, limit, what));
  fail(path, fmt::format("{}: {} {}, more than {} (the limit for this mesh)", field, n, what, limit));
}

TriangleMesh read_stl(const std::string& path, std::string_view bytes, double scale, MeshLimit limit) {
  TriangleMesh mesh;
  Welder weld(mesh);
  // binary: 80-byte header, uint32 count, 50 bytes per triangle; anything else is ASCII
  if (bytes.size() >= 84) {
    uint32_t n = 0;
    std::memcpy(&n, bytes.data() + 80, 4);
    if (bytes.size() == 84 + uint64_t{50} * n) {
      if (n > limit.triangles) too_many(path, "triangle count", n, "triangles", limit.triangles);
      mesh.triangles.reserve(n);
      for (uint32_t t = 0; t < n; ++t) {
        const char* rec = bytes.data() + 84 + size_t{50} * t + 12;  // skip the normal
        std::array<int, 3> tri{};
        for (int c = 0; c < 3; ++c) {
          std::array<float, 3> p{};
          std::memcpy(p.data(), rec + 12 * c, 12);
          if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
            fail(path, fmt::format("triangle {}: a corner is not finite", t));
          tri[c] = weld.add(p, scale);
        }
        mesh.triangles.push_back(tri);
      }
      return mesh;
    }
  }
  if (bytes.substr(0, 5) != "solid")
    fail(path, fmt::format("neither binary STL (size {} bytes does not match its triangle count) nor ASCII "
                           "STL (no 'solid')",
                           bytes.size()));
  Words in(bytes);
  std::string_view word;
  std::array<int, 3> tri{};
  int corner = 0;
  while (in.next(word)) {
    if (word != "vertex") continue;
    std::array<float, 3> p{};
    if (!in.number(p[0]) || !in.number(p[1]) || !in.number(p[2]) || !std::isfinite(p[0]) || !std::isfinite(p[1]) ||
        !std::isfinite(p[2]))
      fail(path, fmt::format("triangle {}: a vertex is not three finite numbers", mesh.triangles.size()));
    tri[corner++] = weld.add(p, scale);
    if (corner == 3) {
      if (static_cast<int64_t>(mesh.triangles.size()) >= limit.triangles)
        too_many(path, "facets", -1, "triangles", limit.triangles);
      mesh.triangles.push_back(tri);
      corner = 0;
    }
  }
  if (corner != 0) fail(path, "ends inside a facet");
  return mesh;
}

// PLY: vertex x y z (float or double, other properties skipped) and faces as index lists
TriangleMesh read_ply(const std::string& path, std::string_view bytes, double scale, MeshLimit limit) {
  struct Property {
    std::string name, type, count_type;  // count_type set for a list
  };
  struct Element {
    std::string name;
    int64_t count = 0;
    std::vector<Property> props;
  };
  const auto end = bytes.find("end_header");
  if (bytes.substr(0, 3) != "ply" || end == std::string_view::npos)
    fail(path, "not a PLY file (no 'ply' ... 'end_header')");
  Lines header(bytes.substr(0, end));
  std::string_view line;
  std::string format;
  std::vector<Element> elements;
  while (header.next(line)) {
    Words w(line);
    std::string_view key, word;
    w.next(key);
    // the next word as a string ("" when the line has no more)
    auto next_word = [&w, &word]() { return w.next(word) ? std::string(word) : std::string(); };
    if (key == "format") {
      format = next_word();
    } else if (key == "element") {
      Element e;
      e.name = next_word();
      if (e.name.empty() || !w.number(e.count) || e.count < 0)
        fail(path, fmt::format("header: bad element line '{}'", line.substr(0, 200)));
      elements.push_back(e);
    } else if (key == "property") {
      if (elements.empty()) fail(path, "header: property before any element");
      Property p;
      p.type = next_word();
      if (p.type == "list") {
        p.count_type = next_word();
        p.type = next_word();
      }
      p.name = next_word();
      elements.back().props.push_back(p);
    }
  }
  const bool ascii = format == "ascii";
  if (!ascii && format != "binary_little_endian")
    fail(path, "format: '" + format + "' is not supported (ascii or binary_little_endian)");
  size_t pos = bytes.find('\n', end);
  if (pos == std::string_view::npos) fail(path, "nothing after end_header");
  ++pos;
  Words text(ascii ? bytes.substr(pos) : std::string_view());
  auto size_of = [&](const std::string& t) -> int {
    if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
    if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
    if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32") return 4;
    if (t == "double" || t == "float64") return 8;
    fail(path, "header: unknown property type '" + t + "'");
  };
  // one scalar of type t, from text or little-endian bytes
  auto scalar = [&](const std::string& t) -> double {
    if (ascii) {
      double v = 0;
      std::string_view word;
      if (!text.next(word)) fail(path, "data ends early");
      if (!parse_number(word, v)) fail(path, fmt::format("data: '{}' is not a number", word.substr(0, 40)));
      return v;
    }
    const int n = size_of(t);
    if (pos + n > bytes.size()) fail(path, "data ends early");
    const char* p = bytes.data() + pos;
    pos += n;
    auto get = [p](auto v) {
      std::memcpy(&v, p, sizeof v);
      return static_cast<double>(v);
    };
    if (t == "char" || t == "int8") return get(int8_t{});
    if (t == "uchar" || t == "uint8") return get(uint8_t{});
    if (t == "short" || t == "int16") return get(int16_t{});
    if (t == "ushort" || t == "uint16") return get(uint16_t{});
    if (t == "int" || t == "int32") return get(int32_t{});
    if (t == "uint" || t == "uint32") return get(uint32_t{});
    if (t == "float" || t == "float32") return get(float{});
    return get(double{});
  };
  // a vertex coordinate in metres (text: through parse_length, exact for millimetres)
  auto length = [&](const std::string& t) -> double {
    if (!ascii) return scalar(t) * scale;
    std::string_view word;
    double m = 0;
    if (!text.next(word)) fail(path, "data ends early");
    if (!parse_length(word, scale, m)) fail(path, fmt::format("data: '{}' is not a number", word.substr(0, 40)));
    return m;
  };
  TriangleMesh mesh;
  // every row of every element takes at least one byte of the file: a count the file cannot hold,
  // or rows of no properties (which would loop without reading), is refused before the loop
  const size_t data_bytes = bytes.size() - pos;
  for (const auto& e : elements) {
    if (e.count > 0 && e.props.empty())
      fail(path, fmt::format("element {}: {} rows of no properties", e.name, e.count));
    if (static_cast<uint64_t>(e.count) > data_bytes)
      fail(path,
           fmt::format("element {}: {} rows cannot fit in the {} bytes after the header", e.name, e.count, data_bytes));
    // each face is at least one triangle
    if (e.name == "face" && e.count > limit.triangles)
      too_many(path, "element face", e.count, "faces", limit.triangles);
    if (e.name == "vertex" && e.count > limit.vertices())
      too_many(path, "element vertex", e.count, "vertices", limit.vertices());
  }
  for (const auto& e : elements) {
    for (const auto& p : e.props) size_of(p.type);
    if (e.name == "vertex") {
      // every vertex takes at least 2 bytes of the file (a digit and a space, or more in binary):
      // a header claiming more than the file can hold is refused before anything is allocated
      if (e.count > static_cast<int64_t>(bytes.size() - pos) / 2)
        fail(path, fmt::format("element vertex: {} vertices cannot fit in the {} bytes after the header", e.count,
                               bytes.size() - pos));
      mesh.vertices_m.reserve(e.count);
    }
    for (int64_t i = 0; i < e.count; ++i) {
      Eigen::Vector3d v = Eigen::Vector3d::Zero();
      for (const auto& p : e.props) {
        if (!p.count_type.empty()) {
          const double n = scalar(p.count_type);
          if (!(n >= 0 && n <= 1024)) fail(path, fmt::format("{} {}: list length {} out of range", e.name, i, n));
          std::vector<int> idx(static_cast<size_t>(n));
          for (auto& k : idx) {
            // an index is checked before it becomes an int (a uint or a float can hold anything)
            const double v = scalar(p.type);
            if (!(v >= 0 && v <= std::numeric_limits<int>::max()))
              fail(path, fmt::format("{} {}: vertex index {} out of range", e.name, i, v));
            k = static_cast<int>(v);
          }
          if (e.name == "face" && (p.name == "vertex_indices" || p.name == "vertex_index")) {
            if (idx.size() < 3) fail(path, fmt::format("face {}: fewer than 3 vertices", i));
            if (static_cast<int64_t>(mesh.triangles.size() + idx.size() - 2) > limit.triangles)
              too_many(path, "element face", -1, "triangles", limit.triangles);
            for (size_t k = 1; k + 1 < idx.size(); ++k) mesh.triangles.push_back({idx[0], idx[k], idx[k + 1]});
          }
          continue;
        }
        const bool coordinate = e.name == "vertex" && (p.name == "x" || p.name == "y" || p.name == "z");
        const double x = coordinate ? length(p.type) : scalar(p.type);
        if (coordinate) v[p.name[0] - 'x'] = x;
      }
      if (e.name == "vertex") {
        check_finite(path, v, mesh.vertices_m.size());
        mesh.vertices_m.push_back(v);
      }
    }
  }
  return mesh;
}

// OBJ: "v x y z" and "f a b c ..." (a/b/c forms, negative indices from the end); polygons fanned
TriangleMesh read_obj(const std::string& path, std::string_view bytes, double scale, MeshLimit limit) {
  TriangleMesh mesh;
  Lines in(bytes);
  std::string_view line;
  int64_t line_no = 0;
  std::vector<int> idx;
  while (in.next(line)) {
    ++line_no;
    Words w(line);
    std::string_view key;
    w.next(key);
    if (key == "v") {
      Eigen::Vector3d v;
      if (!w.length(scale, v.x()) || !w.length(scale, v.y()) || !w.length(scale, v.z()) || !v.allFinite())
        fail(path, fmt::format("line {}: a vertex needs three finite numbers", line_no));
      if (static_cast<int64_t>(mesh.vertices_m.size()) >= limit.vertices())
        too_many(path, fmt::format("line {}", line_no).c_str(), -1, "vertices", limit.vertices());
      mesh.vertices_m.push_back(v);
    } else if (key == "f") {
      idx.clear();
      std::string_view corner;
      while (w.next(corner)) {
        long k = 0;
        if (!parse_number(corner.substr(0, corner.find('/')), k))
          fail(path, fmt::format("line {}: bad face corner '{}'", line_no, corner.substr(0, 100)));
        const long n = static_cast<long>(mesh.vertices_m.size());
        const long zero_based = k > 0 ? k - 1 : n + k;
        if (k == 0 || zero_based < 0 || zero_based >= n)
          fail(path, fmt::format("line {}: vertex {} does not exist (there are {} so far)", line_no, k, n));
        idx.push_back(static_cast<int>(zero_based));
      }
      if (idx.size() < 3) fail(path, fmt::format("line {}: a face needs 3 vertices", line_no));
      if (static_cast<int64_t>(mesh.triangles.size() + idx.size() - 2) > limit.triangles)
        too_many(path, fmt::format("line {}", line_no).c_str(), -1, "triangles", limit.triangles);
      for (size_t k = 1; k + 1 < idx.size(); ++k) mesh.triangles.push_back({idx[0], idx[k], idx[k + 1]});
    }
  }
  return mesh;
}

}  // namespace

TriangleMesh read_mesh(const std::string& path, double metres_per_unit, int64_t max_triangles) {
  const std::string ext = extension_of(path);
  if (ext != ".stl" && ext != ".ply" && ext != ".obj") fail(path, "unknown mesh format (expected .stl, .ply or .obj)");
  std::string bytes;
  try {
    bytes = io::read_file(path, kMaxMeshFileBytes);  // refused unread when larger
  } catch (const std::exception& e) {
    throw MeshIoError(e.what());
  }
  return parse_mesh(path, ext, bytes, metres_per_unit, max_triangles);
}

TriangleMesh parse_mesh(const std::string& path, const std::string& format, std::string_view bytes,
                        double metres_per_unit, int64_t max_triangles) {
  if (format != ".stl" && format != ".ply" && format != ".obj") fail(path, "unknown mesh format '" + format + "'");
  if (static_cast<int64_t>(bytes.size()) > kMaxMeshFileBytes)
    fail(path, fmt::format("{} bytes, over the {} byte limit for a mesh file", bytes.size(), kMaxMeshFileBytes));
  const MeshLimit limit{std::max<int64_t>(max_triangles, 1)};
  TriangleMesh mesh = format == ".stl"   ? read_stl(path, bytes, metres_per_unit, limit)
                      : format == ".ply" ? read_ply(path, bytes, metres_per_unit, limit)
                                         : read_obj(path, bytes, metres_per_unit, limit);
  const int n = static_cast<int>(mesh.vertices_m.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k : mesh.triangles[t])
      if (k < 0 || k >= n) fail(path, fmt::format("triangle {}: vertex {} does not exist ({} vertices)", t, k, n));
  if (mesh.triangles.empty()) fail(path, "no triangles");
  return mesh;
}

void write_stl(const TriangleMesh& mesh, const std::string& path, const std::string& title) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw MeshIoError(path + ": cannot open for writing");
  char header[80] = {};
  const std::string h = fmt::format("{} SPACE=LPS units=mm", title).substr(0, 79);
  std::memcpy(header, h.data(), h.size());
  out.write(header, 80);
  const uint32_t n = static_cast<uint32_t>(mesh.triangles.size());
  out.write(reinterpret_cast<const char*>(&n), 4);
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices_m[t[0]], b = mesh.vertices_m[t[1]], c = mesh.vertices_m[t[2]];
    const Eigen::Vector3d normal = (b - a).cross(c - a).normalized();
    std::array<float, 12> rec{};
    for (int k = 0; k < 3; ++k) rec[k] = static_cast<float>(normal[k]);
    for (int v = 0; v < 3; ++v)
      for (int k = 0; k < 3; ++k) rec[3 + 3 * v + k] = static_cast<float>(mesh.vertices_m[t[v]][k] * 1e3);
    out.write(reinterpret_cast<const char*>(rec.data()), 48);
    const uint16_t attributes = 0;
    out.write(reinterpret_cast<const char*>(&attributes), 2);
  }
  out.flush();
  if (!out) throw MeshIoError(path + ": write failed");
}

namespace {

// a coordinate in metres as millimetre text: the shortest decimal that reads back to the double
// (to_chars' round-trip guarantee) with its exponent moved by 3, which parse_length reverses
// before its one rounding
void write_mm(std::ostream& out, double m) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, m, std::chars_format::scientific);
  const std::string_view text(buf, static_cast<size_t>(r.ptr - buf));
  const size_t e = text.find('e');
  int exponent = 0;
  parse_number(text.substr(e + 1), exponent);
  out << text.substr(0, e) << 'e' << exponent + 3;
}

}  // namespace

void write_ply_mm(const TriangleMesh& mesh, const std::string& path, const std::string& title) {
  std::ofstream out(path);
  if (!out) throw MeshIoError(path + ": cannot open for writing");
  out << "ply\nformat ascii 1.0\ncomment " << title << "\ncomment SPACE=LPS units=mm\n"
      << "element vertex " << mesh.vertices_m.size() << "\nproperty double x\nproperty double y\nproperty double z\n"
      << "element face " << mesh.triangles.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const Eigen::Vector3d& v : mesh.vertices_m) {
    for (int k = 0; k < 3; ++k) {
      if (k > 0) out << ' ';
      write_mm(out, v[k]);
    }
    out << '\n';
  }
  for (const auto& t : mesh.triangles) out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
  out.flush();
  if (!out) throw MeshIoError(path + ": write failed");
}

void round_to_float_mm(TriangleMesh& mesh) {
  // the value read back is float(mm) * 1e-3 computed in double, exactly as read_stl does. The
  // float goes through a volatile: without it one Release build returned a vertex unrounded. The
  // cause is not pinned down (no -ffast-math here, and the conversions may not be folded away;
  // a stale object is possible): the volatile makes the rounding explicit whatever it was
  for (auto& v : mesh.vertices_m)
    for (int k = 0; k < 3; ++k) {
      volatile float mm = static_cast<float>(v[k] * 1e3);
      v[k] = mm * kMillimetre;
    }
}

std::string check_closed_manifold(const TriangleMesh& mesh) {
  if (mesh.triangles.empty()) return "no triangles";
  // each directed edge once; its reverse exactly once
  std::unordered_map<uint64_t, int> directed;
  directed.reserve(mesh.triangles.size() * 3);
  auto key = [](int a, int b) { return (uint64_t(uint32_t(a)) << 32) | uint32_t(b); };
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2])
      return fmt::format("triangle {} repeats a vertex (degenerate)", t);
    for (int e = 0; e < 3; ++e) {
      if (++directed[key(tri[e], tri[(e + 1) % 3])] > 1)
        return fmt::format(
            "non-manifold or inconsistently oriented: edge {}-{} is run the same way by two triangles "
            "(second: triangle {})",
            tri[e], tri[(e + 1) % 3], t);
    }
  }
  int open = 0;
  std::string first;
  for (const auto& tri : mesh.triangles) {
    for (int e = 0; e < 3; ++e) {
      if (directed.contains(key(tri[(e + 1) % 3], tri[e]))) continue;
      if (open++ == 0) first = fmt::format("{}-{}", tri[e], tri[(e + 1) % 3]);
    }
  }
  if (open > 0) return fmt::format("open: {} edges belong to one triangle only (first: vertices {})", open, first);
  return "";
}

}  // namespace pcisim::anatomy
