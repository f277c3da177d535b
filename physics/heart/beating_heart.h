#pragma once
// The 4D heart (heart paper, section 4): elastic spheres at the vertices of the template heart's
// tetrahedra, joined by springs for stretch, bend and twist, plus global shape matching; the
// ventricle particles follow the motion sequence exactly and the rest follow by PBD.
// Frame: patient LPS metres, heart centre at the origin (the coronary phantom's frame).
#include <Eigen/Core>
#include <array>
#include <memory>
#include <span>
#include <vector>

#include "physics/heart/heart_params.h"
#include "physics/pbd/pbd_system.h"

namespace pcisim::physics {

class HeartMotion;
struct HeartMesh;

class BeatingHeart {
 public:
  // the built-in template heart and, unless params name a file, the built-in synthetic motion.
  // Throws std::invalid_argument naming the field when params or the motion file are bad.
  explicit BeatingHeart(const HeartBeatParams& params);
  ~BeatingHeart();
  BeatingHeart(const BeatingHeart&) = delete;
  BeatingHeart& operator=(const BeatingHeart&) = delete;

  // one physics step: the phase advances by dt * rate / 60, driven particles move to the motion
  // sequence's positions at the new phase, the rest are projected. Allocates nothing.
  void step(double dt_s);

  double phase() const;    // [0, 1) of the cardiac cycle; 0 = end-diastole
  double time_s() const;

  // one entry per particle (= tet vertex)
  const Eigen::Matrix3Xd& positions_m() const;
  const Eigen::Matrix3Xd& rest_positions_m() const;
  // outer (epicardial) surface triangles, indices into the particles, counter-clockwise seen
  // from outside
  std::span<const std::array<int, 3>> epicardium() const;
  // particles the motion sequence drives (the ventricles' myocardium)
  std::span<const int> driven() const;

  const pbd::PbdSystem& system() const;
  pbd::PbdSystem& system();  // hard-case tests poke it
  const HeartBeatParams& params() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pcisim::physics
