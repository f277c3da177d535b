#pragma once
// The probe (ultrasound transducer): a kinematic convex rigid body given as an intersection of
// half-spaces, as the paper's FleX "dynamic convex mesh" [soft-tissue, "Collision and data
// preparation": a cuboid, the intersection of three pairs of parallel half-spaces].
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "physics/soft_tissue/contact_plane.h"

namespace pcisim::physics::soft_tissue {

// inside: normal . x <= offset_m, in the probe frame (normal unit)
struct HalfSpace {
  Eigen::Vector3d normal;
  double offset_m = 0.0;
};

// a rigid pose: world = rotation * local + position
struct ProbePose {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
};

struct ConvexProbe {
  std::vector<HalfSpace> faces;  // none: no probe
  ProbePose pose;                // where it starts
};

// a cuboid centred on the probe frame's origin, faces +-x, +-y, +-z
ConvexProbe box_probe(const Eigen::Vector3d& half_extent_m, const ProbePose& pose = {});

// throws std::invalid_argument when a face's normal is not finite and non-zero or an offset is
// not finite; returns the probe with unit normals
ConvexProbe normalised(const ConvexProbe& probe);

// the pose a fraction t in [0, 1] of the way from a to b (position on the line, rotation slerped)
ProbePose interpolate(const ProbePose& a, const ProbePose& b, double t);

// face i of the probe at a pose, as a world contact plane (its outward normal, its offset)
ContactPlane world_face(const HalfSpace& face, const ProbePose& pose);

}  // namespace pcisim::physics::soft_tissue
