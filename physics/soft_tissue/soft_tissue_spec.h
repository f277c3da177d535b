#pragma once
// What a scene asks of the soft-tissue effects (scene keys: effects.soft_tissue, .probe_contact;
// docs/scenes.md): the organ's particle model and solver, and the probe that presses it.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "physics/soft_tissue/tissue_model.h"
#include "physics/soft_tissue/tissue_params.h"

namespace pcisim::physics::soft_tissue {

struct SoftTissueSpec {
  TissueModelSpec model;  // particle radius, clusters, the coarse tet mesh
  TissueParams params;    // mass, stiffness, substeps, iterations, solver, friction
  // the organ settles on its support this long while the scene is built, so the first frame
  // shows it resting rather than falling; [0, 5]
  double settle_s = 0.5;
};

// the transducer: a cuboid whose face (probe z = 0, normal +z) touches the tissue. Probe frame:
// x lateral (the image's width), y elevation, z into the tissue; the pose is the face's centre
struct ProbeContactParams {
  double face_width_m = 0.040;      // along x; (0, 0.2]
  double face_thickness_m = 0.012;  // along y; (0, 0.1]
  double height_m = 0.030;          // behind the face, along -z; (0, 0.3]
  // where the probe is before any probe sample arrives: anterior of the kidney phantom, face
  // toward +y (posterior), lateral along S (z). R maps probe x -> scene z, y -> x, z -> y
  Eigen::Vector3d start_position_m{0.0, -0.030, 0.0};
  Eigen::Quaterniond start_rotation{0.5, -0.5, -0.5, -0.5};
  // the haptic model's stiffness along the beam is the secant of the last two steps' force over
  // depth, clamped to this (N/m); [0, 1e5]
  double max_stiffness_n_per_m = 2000.0;
  double damping_n_s_per_m = 0.0;  // along the beam, for the haptic model; [0, 1000]
};

// the ranges, once: validate() and the scene loader use them. The paper's particle radii are
// 2.2-3.3 mm [soft-tissue, Table 2]; below 1.5 mm a kidney has tens of thousands of particles (no
// real-time step on 2 cores), above 20 mm a handful
inline constexpr ParamRange kTissueParticleRadiusM{1.5e-3, 20e-3};
inline constexpr ParamRange kTissueVoxelM{0.25e-3, 5e-3};  // and at most the particle radius
inline constexpr ParamRange kTissueClusterSpacingFactor{1.0, 8.0};
inline constexpr ParamRange kTissueClusterOverlap{0.0, 1.0};
inline constexpr ParamRange kTissueTetSpacingFactor{1.0, 16.0};
inline constexpr ParamRange kTissueSettleS{0.0, 5.0};
inline constexpr ParamRange kProbeFaceWidthM{1e-3, 0.2};
inline constexpr ParamRange kProbeFaceThicknessM{1e-3, 0.1};
inline constexpr ParamRange kProbeHeightM{1e-3, 0.3};
inline constexpr ParamRange kProbeMaxStiffnessNPerM{0.0, 1e5};
inline constexpr ParamRange kProbeDampingNSPerM{0.0, 1000.0};

// throw std::invalid_argument naming the field ("soft_tissue.particle_radius_m: ...")
void validate(const SoftTissueSpec& spec);
void validate(const ProbeContactParams& probe);

}  // namespace pcisim::physics::soft_tissue
