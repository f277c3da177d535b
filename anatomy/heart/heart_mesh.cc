#include "anatomy/heart/heart_mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <cstdio>
#include <map>
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace pcisim::anatomy {
namespace {

// the data lines of a TetGen file: '#' starts a comment, blank lines are skipped
class Lines {
 public:
  explicit Lines(const TetgenText& t) : t_(t) {}
  // the next data line split into tokens; false at the end of the text
  bool next(std::vector<std::string_view>* tokens) {
    while (pos_ < t_.text.size()) {
      const size_t end = std::min(t_.text.find('\n', pos_), t_.text.size());
      std::string_view line = t_.text.substr(pos_, end - pos_);
      pos_ = end + 1;
      ++line_;
      if (const size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
      tokens->clear();
      size_t i = 0;
      while (i < line.size()) {
        while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
        const size_t start = i;
        while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
        if (i > start) tokens->push_back(line.substr(start, i - start));
      }
      if (!tokens->empty()) return true;
    }
    return false;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw std::invalid_argument(t_.name + " line " + std::to_string(line_) + ": " + what);
  }
  [[noreturn]] void fail_at_end(const std::string& what) const {
    throw std::invalid_argument(t_.name + ": " + what + " (file ends at line " + std::to_string(line_) + ")");
  }
  long integer(std::string_view token, const char* field) const {
    long v = 0;
    const auto [p, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
    if (ec != std::errc() || p != token.data() + token.size())
      fail(std::string(field) + " must be an integer, got '" + std::string(token) + "'");
    return v;
  }
  double real(std::string_view token, const char* field) const {
    double v = 0;
    const auto [p, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
    if (ec != std::errc() || p != token.data() + token.size() || !std::isfinite(v))
      fail(std::string(field) + " must be a finite number, got '" + std::string(token) + "'");
    return v;
  }
  // the header: its first token, a count, and the whole token list for the caller to check
  void need(const std::vector<std::string_view>& tokens, size_t n, const char* what) const {
    if (tokens.size() < n)
      fail(std::string(what) + ": expected at least " + std::to_string(n) + " fields, got " +
           std::to_string(tokens.size()));
  }

 private:
  TetgenText t_;
  size_t pos_ = 0;
  int line_ = 0;
};

}  // namespace

namespace {

// .node: "<count> 3 <attributes> <markers>", then "<index> x y z ..."; *first_index gets 0 or 1
Eigen::Matrix3Xd parse_nodes(const TetgenText& node, double scale_to_m, long* first_index) {
  std::vector<std::string_view> tok;
  Lines nl(node);
  if (!nl.next(&tok)) nl.fail_at_end("no header");
  nl.need(tok, 2, "header");
  const long n_nodes = nl.integer(tok[0], "node count");
  if (n_nodes < 4) nl.fail("node count must be >= 4");
  if (nl.integer(tok[1], "dimension") != 3) nl.fail("dimension must be 3");
  // a node takes more than one character of the text: a count the text cannot hold is refused
  // before anything is allocated for it
  if (static_cast<size_t>(n_nodes) > node.text.size())
    nl.fail("node count " + std::to_string(n_nodes) + " is more than the file's " + std::to_string(node.text.size()) +
            " bytes can hold");
  Eigen::Matrix3Xd v(3, n_nodes);
  for (long i = 0; i < n_nodes; ++i) {
    if (!nl.next(&tok)) nl.fail_at_end("expected " + std::to_string(n_nodes) + " nodes, got " + std::to_string(i));
    nl.need(tok, 4, "node");
    const long index = nl.integer(tok[0], "node index");
    if (i == 0) {
      if (index != 0 && index != 1) nl.fail("the first node index must be 0 or 1");
      *first_index = index;
    }
    if (index != *first_index + i) nl.fail("node index must be " + std::to_string(*first_index + i));
    for (int k = 0; k < 3; ++k) v(k, i) = scale_to_m * nl.real(tok[1 + k], "node coordinate");
  }
  return v;
}

}  // namespace

Eigen::Matrix3Xd parse_tetgen_nodes(const TetgenText& node, double scale_to_m) {
  long first_index = 0;
  return parse_nodes(node, scale_to_m, &first_index);
}

void write_tetgen_nodes(const Eigen::Matrix3Xd& vertices_m, std::ostream& out) {
  out << vertices_m.cols() << "  3  0  0\n";
  char line[128];
  for (Eigen::Index i = 0; i < vertices_m.cols(); ++i) {
    std::snprintf(line, sizeof line, "%ld %.17g %.17g %.17g\n", static_cast<long>(i), 1e3 * vertices_m(0, i),
                  1e3 * vertices_m(1, i), 1e3 * vertices_m(2, i));
    out << line;
  }
}

HeartMesh parse_tetgen_mesh(const TetgenText& node, const TetgenText& ele, const TetgenText& face, double scale_to_m) {
  HeartMesh m;
  std::vector<std::string_view> tok;
  long first_index = 0;
  m.vertices_m = parse_nodes(node, scale_to_m, &first_index);
  const long n_nodes = m.vertices_m.cols();

  auto vertex = [&](const Lines& l, std::string_view token) {
    const long v = l.integer(token, "vertex index") - first_index;
    if (v < 0 || v >= n_nodes) l.fail("vertex index " + std::string(token) + " is not a node");
    return static_cast<int>(v);
  };

  // .ele: "<count> 4 <attributes>", then "<index> a b c d"
  Lines el(ele);
  if (!el.next(&tok)) el.fail_at_end("no header");
  el.need(tok, 2, "header");
  const long n_tets = el.integer(tok[0], "tet count");
  if (n_tets < 1) el.fail("tet count must be >= 1");
  if (el.integer(tok[1], "nodes per tet") != 4) el.fail("nodes per tet must be 4 (linear tets)");
  m.tets.reserve(n_tets);
  for (long i = 0; i < n_tets; ++i) {
    if (!el.next(&tok)) el.fail_at_end("expected " + std::to_string(n_tets) + " tets, got " + std::to_string(i));
    el.need(tok, 5, "tet");
    std::array<int, 4> t;
    for (int k = 0; k < 4; ++k) t[k] = vertex(el, tok[1 + k]);
    const Eigen::Vector3d a = m.vertices_m.col(t[0]);
    const double vol6 = (m.vertices_m.col(t[1]) - a).cross(m.vertices_m.col(t[2]) - a).dot(m.vertices_m.col(t[3]) - a);
    if (!(std::abs(vol6) > 0.0)) el.fail("tet " + std::string(tok[0]) + " is degenerate (zero volume)");
    m.tets.push_back(t);
  }

  // which tet (and its fourth vertex) each triangle bounds
  std::map<std::array<int, 3>, int> opposite;
  for (const auto& t : m.tets)
    for (int k = 0; k < 4; ++k) {
      std::array<int, 3> f = {t[(k + 1) % 4], t[(k + 2) % 4], t[(k + 3) % 4]};
      std::sort(f.begin(), f.end());
      opposite[f] = t[k];
    }

  // .face: "<count> <markers 0|1>", then "<index> a b c [marker]"
  Lines fl(face);
  if (!fl.next(&tok)) fl.fail_at_end("no header");
  fl.need(tok, 1, "header");
  const long n_faces = fl.integer(tok[0], "face count");
  if (n_faces < 4) fl.fail("face count must be >= 4");
  const bool has_markers = tok.size() > 1 && fl.integer(tok[1], "boundary marker flag") != 0;
  for (long i = 0; i < n_faces; ++i) {
    if (!fl.next(&tok)) fl.fail_at_end("expected " + std::to_string(n_faces) + " faces, got " + std::to_string(i));
    fl.need(tok, has_markers ? 5 : 4, "face");
    std::array<int, 3> f;
    for (int k = 0; k < 3; ++k) f[k] = vertex(fl, tok[1 + k]);
    std::array<int, 3> key = f;
    std::sort(key.begin(), key.end());
    const auto it = opposite.find(key);
    if (it == opposite.end()) fl.fail("face " + std::string(tok[0]) + " bounds no tet");
    const Eigen::Vector3d a = m.vertices_m.col(f[0]);
    const Eigen::Vector3d n = (m.vertices_m.col(f[1]) - a).cross(m.vertices_m.col(f[2]) - a);
    if (n.dot(m.vertices_m.col(it->second) - a) > 0.0) std::swap(f[1], f[2]);  // point away from the tissue
    m.faces.push_back(f);
    m.face_markers.push_back(has_markers ? static_cast<int>(fl.integer(tok[4], "face marker")) : 0);
  }
  return m;
}

std::vector<int> marked_surface_vertices(const HeartMesh& mesh, int marker) {
  std::vector<char> on(mesh.vertices_m.cols(), 0);
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    if (mesh.face_markers[f] == marker)
      for (int v : mesh.faces[f]) on[v] = 1;
  std::vector<int> out;
  for (size_t v = 0; v < on.size(); ++v)
    if (on[v]) out.push_back(static_cast<int>(v));
  return out;
}

HeartMesh read_tetgen_mesh(const std::string& stem) {
  auto slurp = [](const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::invalid_argument(path + ": cannot open");
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  };
  const std::string node = slurp(stem + ".node"), ele = slurp(stem + ".ele"), face = slurp(stem + ".face");
  return parse_tetgen_mesh({node, stem + ".node"}, {ele, stem + ".ele"}, {face, stem + ".face"}, 1e-3);
}

}  // namespace pcisim::anatomy
