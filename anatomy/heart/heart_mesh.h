#pragma once
// A tetrahedral heart mesh as TetGen writes it (.node/.ele/.face), read from text with errors that
// name the file and line. The built-in template comes from scenes/heart/ (embedded at build time).
#include <Eigen/Core>
#include <array>
#include <iosfwd>
#include <string>
#include <string_view>
#include <vector>

namespace pcisim::anatomy {

struct HeartMesh {
  Eigen::Matrix3Xd vertices_m;            // patient LPS
  std::vector<std::array<int, 4>> tets;   // indices into vertices_m
  std::vector<std::array<int, 3>> faces;  // boundary faces, ccw seen from outside the tissue
  std::vector<int> face_markers;          // HeartSurfaceMarker per face (0 when unmarked)
};

// one TetGen text file and the name its errors use
struct TetgenText {
  std::string_view text;
  std::string name;
};

// parses the three files; vertex coordinates are multiplied by scale_to_m (files in mm: 1e-3).
// Throws std::invalid_argument "<name> line <n>: <what is wrong>". Faces are re-oriented so their
// normals point away from the tet they bound; a face that bounds no tet is an error.
HeartMesh parse_tetgen_mesh(const TetgenText& node, const TetgenText& ele, const TetgenText& face, double scale_to_m);

// a fitted rest shape (a case's heart.node) keeps every vertex within this distance of the
// template's, in the template's frame: a fit moves the surface by millimetres, never by a heart's
// size (the reader refuses more; the CTA pipeline does not write more)
constexpr double kMaxFittedHeartMoveMm = 40.0;

// only the vertices of a .node file (a fitted rest shape over the template's tets, heart_vertices)
Eigen::Matrix3Xd parse_tetgen_nodes(const TetgenText& node, double scale_to_m);
// writes vertices (metres) as a .node file in millimetres, indices from 0, full precision
void write_tetgen_nodes(const Eigen::Matrix3Xd& vertices_m, std::ostream& out);

// reads <stem>.node, <stem>.ele, <stem>.face from disk (millimetres)
HeartMesh read_tetgen_mesh(const std::string& stem);

// the vertices of the faces carrying `marker` (HeartSurfaceMarker: kEpicardium, ...), ascending
std::vector<int> marked_surface_vertices(const HeartMesh& mesh, int marker);

// the committed template (scenes/heart/template_heart.*), parsed once
const HeartMesh& template_heart_mesh();

}  // namespace pcisim::anatomy
