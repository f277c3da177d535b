#pragma once
// Triangle meshes from and to files: STL (binary and ASCII), PLY (ASCII and binary little-endian)
// and OBJ. Files hold lengths in a unit the caller names (pcisim's case files: millimetres, LPS);
// the mesh in memory is in metres. Errors throw MeshIoError "<file>: <what>".
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

#include "anatomy/mesh/triangle_mesh.h"

namespace pcisim::anatomy {

struct MeshIoError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// metres per file unit: 1e-3 for millimetre files (what users bring, what Slicer writes). A
// millimetre coordinate in text (PLY, OBJ) becomes metres by moving its decimal exponent, then
// one rounding to double; binary values are multiplied by 1e-3
inline constexpr double kMillimetre = 1e-3;

// the largest mesh file read: a lumen of a million triangles is 50 MB as binary STL, ~250 MB as
// ASCII; a larger file is refused (naming its size and this limit) before it is read
inline constexpr int64_t kMaxMeshFileBytes = int64_t{512} << 20;

// no bound on a mesh's triangles but the file's size (a case names its own: anatomy/case/case_limits.h)
inline constexpr int64_t kNoTriangleLimit = INT64_MAX;

// by extension (.stl, .ply, .obj, any case). STL has no shared vertices: corners at the same
// position are welded into one vertex, in order of first appearance. A mesh of more than
// max_triangles triangles (or more vertices than they could use, 3 each) is refused as soon as a
// header or the count read so far says so, before the rest is parsed or allocated.
TriangleMesh read_mesh(const std::string& path, double metres_per_unit = kMillimetre,
                       int64_t max_triangles = kNoTriangleLimit);
// the same from a file's bytes, parsed in place (never copied); `format` is ".stl", ".ply" or
// ".obj", `name` what errors say
TriangleMesh parse_mesh(const std::string& name, const std::string& format, std::string_view bytes,
                        double metres_per_unit = kMillimetre, int64_t max_triangles = kNoTriangleLimit);

// binary STL in millimetres; the 80-byte header says "SPACE=LPS" (3D Slicer reads the space from
// it) and "units=mm". Coordinates are float32: write_stl then read_mesh gives the mesh rounded to
// float, and a mesh already at float precision (round_to_float_mm) comes back bit for bit.
void write_stl(const TriangleMesh& mesh, const std::string& path, const std::string& title = "pcisim");

// ASCII PLY in millimetres, vertices shared as in the mesh, with a comment "SPACE=LPS" (3D Slicer
// reads the space from a PLY's comments). Each coordinate is the shortest decimal of its metre
// value with the exponent moved by 3, and read_mesh (kMillimetre) moves it back before rounding,
// so write_ply_mm then read_mesh gives the same doubles, bit for bit
void write_ply_mm(const TriangleMesh& mesh, const std::string& path, const std::string& title = "pcisim");

// every vertex rounded to the float32 millimetre value an STL file stores
void round_to_float_mm(TriangleMesh& mesh);

// "" when every edge is shared by exactly two triangles running it in opposite directions (the
// surface is closed, manifold and consistently oriented) and no triangle is degenerate; otherwise
// the first problem found, e.g. "open: 12 edges belong to one triangle only (first: vertices 3-7)"
std::string check_closed_manifold(const TriangleMesh& mesh);

}  // namespace pcisim::anatomy
