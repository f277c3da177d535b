#pragma once
// A deformed tetrahedral mesh as plain data, the ultrasound renderer's view of the soft tissue
// (DESIGN.md: imaging sees geometry snapshots, never physics). In CT coordinates (LPS, mm): the
// physics' tet_vertices_m (metres) times 1000 for rest, its skinned vertices for current.
#include <Eigen/Core>
#include <array>
#include <vector>

namespace pcisim::ultrasound {

struct TetSnapshot {
  Eigen::Matrix3Xd rest_mm;     // vertex positions in the undeformed CT
  Eigen::Matrix3Xd current_mm;  // the same vertices now (same column count)
  std::vector<std::array<int, 4>> tets;
};

}  // namespace pcisim::ultrasound
