#pragma once
// Finds the deformed tetrahedron holding a point and carries the point to the undeformed CT
// through its barycentric coordinates (soft-tissue paper, "Weighted matrix blending": the image
// plane expressed barycentrically in the embedded tetrahedra, mapped back to the initial CT).
// A uniform grid over the deformed tets' bounding box (cell count fixed by the topology) finds
// candidates. build() allocates; refit() re-bins for new current positions and allocates only
// when the tets cover more cells than ever before (capacity is reserved at twice the rest count).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "ultrasound/mapping/tet_lookup.h"
#include "ultrasound/mapping/tet_snapshot.h"

namespace pcisim::ultrasound {

class TetLocator {
 public:
  // throws std::invalid_argument on a snapshot whose sizes or indices disagree
  void build(const TetSnapshot& mesh);
  // new current positions, same topology as build() (checked by vertex and tet count)
  void refit(const TetSnapshot& mesh);
  // true and the rest-space point when p (current configuration) lies in a tet
  bool to_rest(const Eigen::Vector3d& p, Eigen::Vector3d* rest) const;
  // the same, trying the tet in *hint first (the last one found: a scanline's next sample is
  // mostly in its predecessor's tet) and leaving the one found there (-1: none yet)
  bool to_rest(const Eigen::Vector3d& p, Eigen::Vector3d* rest, int* hint) const;
  bool empty() const { return tet_count_ == 0; }
  long entries_capacity() const { return static_cast<long>(entries_.capacity()); }
  // the arrays as the lookup (tet_lookup.h) reads them; valid until the next build() or refit()
  LocatorView view() const;
  // how many grid cells and entries view() holds
  int cell_count() const { return dims_.prod(); }
  int entry_count() const { return static_cast<int>(entries_.size()); }

 private:
  int tet_count_ = 0;
  int vertex_count_ = 0;
  std::vector<Eigen::Matrix3d> inv_current_;  // per tet: [v1-v0 v2-v0 v3-v0]^-1, current
  std::vector<Eigen::Vector3d> v0_current_;
  std::vector<Eigen::Matrix3d> edges_rest_;  // per tet: [r1-r0 r2-r0 r3-r0]
  std::vector<Eigen::Vector3d> v0_rest_;
  std::vector<unsigned char> valid_;          // not degenerate in the current configuration
  std::vector<Eigen::AlignedBox3d> tet_box_;  // current bounds per tet
  Eigen::Vector3i dims_{1, 1, 1};
  Eigen::Vector3d lo_ = Eigen::Vector3d::Zero(), inv_cell_ = Eigen::Vector3d::Ones();
  std::vector<int> cell_start_;  // CSR: tets of cell i are entries_[cell_start_[i] .. cell_start_[i+1])
  std::vector<int> entries_;
  std::vector<int> fill_;  // per cell, while binning
};

}  // namespace pcisim::ultrasound
