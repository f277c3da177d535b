#pragma once
// The 4D heart (heart paper, section 4): elastic spheres at the vertices of the template heart's
// tetrahedra, joined by springs for stretch, bend and twist, plus global shape matching; the
// ventricle particles follow the motion sequence exactly and the rest follow by PBD.
// Frame: patient LPS metres, heart centre at the origin (the coronary phantom's frame).
#include <Eigen/Core>
#include <array>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "physics/heart/heart_params.h"
#include "physics/pbd/pbd_system.h"

namespace pcisim::anatomy {
struct HeartMesh;
class HeartMotion;
}  // namespace pcisim::anatomy

namespace pcisim::physics {

// build-time material variation by rest position (hard-case tests, studies): a particle's mass is
// scaled by mass_scale, a spring's compliance by the larger compliance_scale of its particles
struct HeartTissueScaling {
  std::function<double(const Eigen::Vector3d& rest_m)> mass_scale;        // empty: 1
  std::function<double(const Eigen::Vector3d& rest_m)> compliance_scale;  // empty: 1
};

class BeatingHeart {
 public:
  // the built-in template heart and, unless params name a file, the built-in synthetic motion.
  // Throws std::invalid_argument naming the field when params or the motion file are bad.
  explicit BeatingHeart(const HeartBeatParams& params);
  BeatingHeart(const HeartBeatParams& params, const HeartTissueScaling& scaling);
  // another tetrahedral heart in the template's frame and markers (e.g. the template fitted under
  // a tree, heart_fit.h)
  BeatingHeart(const HeartBeatParams& params, const anatomy::HeartMesh& mesh, const HeartTissueScaling& scaling = {});
  ~BeatingHeart();
  BeatingHeart(const BeatingHeart&) = delete;
  BeatingHeart& operator=(const BeatingHeart&) = delete;

  // one physics step: the phase advances by dt * rate / 60, driven particles move to the motion
  // sequence's positions at the new phase, the rest are projected. Allocates nothing.
  void step(double dt_s);

  // a new heart rate from the next step on (the phase carries on); throws like the constructor
  void set_rate_bpm(double rate_bpm);

  double phase() const;  // [0, 1) of the cardiac cycle; 0 = end-diastole
  double time_s() const;

  // one entry per particle (= tet vertex)
  const Eigen::Matrix3Xd& positions_m() const;
  const Eigen::Matrix3Xd& rest_positions_m() const;
  // outer (epicardial) surface triangles, indices into the particles, counter-clockwise seen
  // from outside
  std::span<const std::array<int, 3>> epicardium() const;
  // particles the motion sequence drives (the ventricles' myocardium)
  std::span<const int> driven() const;

  // the particles the sequence does not drive (atria, aortic root): they follow by PBD
  std::span<const int> free_particles() const;
  // tetrahedra over the particles (the template mesh's, compacted to the particles)
  std::span<const std::array<int, 4>> tets() const;
  // LV endocardium triangles, normals into the cavity (for volumes and ejection fraction)
  std::span<const std::array<int, 3>> lv_endocardium() const;
  const anatomy::HeartMotion& motion() const;
  // where driven particle i is at phase: rest + the sequence's displacement
  Eigen::Vector3d driven_position_m(int i, double phase) const;

  const pbd::PbdSystem& system() const;
  pbd::PbdSystem& system();  // hard-case tests poke it
  const HeartBeatParams& params() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pcisim::physics
