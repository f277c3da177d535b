#pragma once
// The heart's motion carried into the CT's frame (heart paper §4: the motion moves the heart; here
// it also moves the CT behind the fluoroscopy). Input: scattered samples of one cardiac cycle,
// the heart's particles and the coronary centerline at rest and at each phase bin (plain
// geometry, from physics through the server). Output, per bin: a smooth displacement field on a
// coarse lattice over the CT voxels around the heart, and the change of attenuation it makes,
//   dmu_b(x) = mu(x - v_b(x)) - mu(x),   x - v_b(x) + u_b(x - v_b(x)) = x,
// where u_b moves a rest point to bin b and v_b is its inverse (fixed-point iteration). Zero
// outside the box, so the spine and everything else far from the heart stays exactly still.
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "xray/projectors/attenuation_volume.h"

namespace pcisim::xray {

// one cycle, bin b at phase b / bins (0 = end-diastole); points in the CT's physical frame (mm)
struct BeatSamples {
  std::vector<Eigen::Vector3d> rest_mm;
  std::vector<std::vector<Eigen::Vector3d>> at_bin_mm;  // bins entries, each as long as rest_mm
  int bins() const { return static_cast<int>(at_bin_mm.size()); }
};

// empty when usable (>= 2 bins, >= 1 point, equal lengths, finite), otherwise what is wrong
std::string validate(const BeatSamples& samples);

// samples from columns in metres (physics::World::sample_beat_cycle's rest_m and at_bin_m), in mm
BeatSamples beat_samples_from_m(const Eigen::Matrix3Xd& rest_m, const std::vector<Eigen::Matrix3Xd>& at_bin_m);

// every second (or k-th) bin: the same cycle at fewer phases; bins must be a multiple of k
BeatSamples every_kth_bin(const BeatSamples& samples, int k);

struct HeartWarpParams {
  double kernel_mm = 4.0;  // Gaussian sigma of the blend of nearby samples
  double reach_mm = 12.0;  // samples count within this; the displacement fades to 0 from kernel to reach
  double grid_mm = 3.0;    // lattice spacing of the displacement field (rounded to whole voxels)
  int inverse_iterations = 4;
};

// empty when usable, otherwise the field and its range
std::string validate(const HeartWarpParams& params);

class HeartWarp {
 public:
  // builds every bin's field (a fraction of a second for a heart of a few thousand samples);
  // throws std::invalid_argument when the samples or params are bad or miss the CT entirely
  HeartWarp(const AttenuationVolume& ct, const BeatSamples& samples, const HeartWarpParams& params = {});

  int bins() const { return bins_; }
  // the CT voxels the warp may change: [box_lo, box_hi) per axis (volume indices)
  const std::array<int, 3>& box_lo() const { return box_lo_; }
  const std::array<int, 3>& box_hi() const { return box_hi_; }

  // where bin b's field moves a rest point (mm): u_b(p); zero outside the box
  Eigen::Vector3d displacement_mm(int bin, const Eigen::Vector3d& rest_mm) const;

  // a zeroed volume over the box, same spacing and axes as the CT, values mu per mm
  AttenuationVolume make_change_volume() const;
  // bin b's change of attenuation over the box into `change` (from make_change_volume); the
  // bricks are rebuilt; allocates nothing
  void write_change(int bin, AttenuationVolume* change) const;
  // bin b's warped attenuation, mu(x - v_b(x)), over the box of `ct_copy`: a volume the size of
  // the CT holding the static mu (outside the box it is left as it is); the bricks are rebuilt.
  // Re-projecting it whole is what the phase-bin cache is measured against.
  void write_warped(int bin, AttenuationVolume* ct_copy) const;

 private:
  void write_box(int bin, AttenuationVolume* out, bool minus_static) const;
  Eigen::Vector3f field_at(const std::vector<Eigen::Vector3f>& field, const Eigen::Vector3f& node) const;

  const AttenuationVolume& ct_;
  HeartWarpParams params_;
  int bins_ = 0;
  std::array<int, 3> box_lo_{}, box_hi_{};
  std::array<int, 3> stride_{1, 1, 1};  // lattice spacing in voxels, per axis (~grid_mm each)
  std::array<int, 3> nodes_{};          // lattice nodes per axis, node n at voxel box_lo + stride n
  // per bin, per node: forward u (rest -> moved) and inverse v, both in voxel index units
  std::vector<std::vector<Eigen::Vector3f>> forward_, inverse_;
  Eigen::Matrix3d index_from_physical_;
};

}  // namespace pcisim::xray
