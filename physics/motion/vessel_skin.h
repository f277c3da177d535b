#pragma once
// The coronary tree skinned to the epicardium (heart paper, section 3: the vessels are attached
// to the template heart). Every centerline point is bound to its nearest epicardial triangle in
// that triangle's affine frame (two edges and the unit normal), so it follows the triangle as
// the heart moves; points far from the heart (the aortic root) fade to standing still.
// Any other rest-frame point (the wire inside a lumen) is carried by a blend of the centerline
// points around it. Built once; update() and the queries allocate nothing.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <span>
#include <vector>

#include "physics/motion/vessel_motion_params.h"
#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::physics {

// throws std::invalid_argument naming the field ("vessel_motion.attach_distance_m: ...") when out of range
void validate(const VesselMotionParams& params);

class VesselSkin {
 public:
  // surface_m: the epicardial particles at rest (columns); triangles index them. Throws like
  // validate(), or when a triangle indexes past the surface
  VesselSkin(const anatomy::VesselTree& rest_tree, const Eigen::Matrix3Xd& rest_surface_m,
             std::span<const std::array<int, 3>> triangles, const VesselMotionParams& params);

  // moves every centerline point with the surface's current positions (same columns as at rest)
  void update(const Eigen::Matrix3Xd& surface_m);

  // centerline points in tree order (branch 0's points, then branch 1's, ...)
  int point_count() const { return static_cast<int>(rest_.size()); }
  std::span<const Eigen::Vector3d> rest_points_m() const { return rest_; }
  std::span<const Eigen::Vector3d> points_m() const { return now_; }
  // first flat index of each branch, then the total
  std::span<const int> branch_offsets() const { return offsets_; }

  // displacement of a rest-frame point now: the blend of the centerline points near it; zero
  // far from every vessel
  Eigen::Vector3d displacement_m(const Eigen::Vector3d& rest_p_m) const { return displacement_m(rest_p_m, 1.0); }
  // the same a fraction a through the last update: the blend of the centerline points moved
  // linearly from where the update before left them (a = 0) to where they are now (a = 1)
  Eigen::Vector3d displacement_m(const Eigen::Vector3d& rest_p_m, double a) const;
  Eigen::Vector3d to_world(const Eigen::Vector3d& rest_p_m) const { return rest_p_m + displacement_m(rest_p_m); }
  // whether a rest-frame point lies within the blend radius of some centerline point (beyond
  // them all, displacement_m is zero because nothing carries it)
  bool carries(const Eigen::Vector3d& rest_p_m) const;
  // a vector at a rest-frame point (a force on a node) carried to the world: turned as the
  // epicardial triangles the nearby centerline points ride turned since rest (each as much as the
  // point rides the heart; blended like the displacement), its length kept, whichever way it
  // points (a wall's push is across the vessel); a zero or non-finite vector, or one far from
  // every vessel, comes back as it is
  Eigen::Vector3d turn_to_world(const Eigen::Vector3d& rest_p_m, const Eigen::Vector3d& v) const;
  // the rest-frame point that maps to world_p (fixed-point iteration from the nearest moved
  // centerline point; linear in the tree's size, for tests and benchmarks, not per-node loops)
  Eigen::Vector3d to_rest(const Eigen::Vector3d& world_p_m) const;

  // how fully point i rides the heart, 1 on the epicardium, 0 far from it
  double ride_weight(int i) const { return weight_[i]; }

 private:
  struct Binding {
    int tri = -1;
    Eigen::Vector3d coords = Eigen::Vector3d::Zero();                // along edge 1, edge 2, unit normal
    Eigen::Matrix3d rest_orientation = Eigen::Matrix3d::Identity();  // the triangle's, orthonormal
  };
  Eigen::Vector3d skinned(const Binding& b, const Eigen::Matrix3Xd& surface_m) const;
  // calls f(i, w) for each centerline point i within the blend radius of rest point p, with its
  // weight (inverse squared distance, softened, fading to zero at the radius); returns their sum
  template <class F>
  double blend(const Eigen::Vector3d& p, F&& f) const;

  VesselMotionParams params_;
  std::vector<std::array<int, 3>> triangles_;
  std::vector<Eigen::Vector3d> rest_, now_, before_;  // before_: now_ before the last update
  std::vector<int> offsets_;
  std::vector<Binding> binding_;
  std::vector<double> weight_;
  std::vector<Eigen::Quaterniond> turn_;  // each point's triangle's turn since rest (times its ride weight)

  // rest-frame grid of centerline points: cell -> [cell_start_[c], cell_start_[c + 1]) in cell_points_
  Eigen::Vector3d grid_origin_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector3i grid_dims_ = Eigen::Vector3i::Zero();
  double cell_m_ = 0.0;
  std::vector<int> cell_start_, cell_points_;
};

}  // namespace pcisim::physics
