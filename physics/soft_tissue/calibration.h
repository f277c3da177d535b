#pragma once
// The paper's calibration protocol (issue #16 item 5; soft-tissue paper, "Calibration"): the
// probe presses the organ in stages, and the PBD model's fiducials are compared at each stage
// with the truth. No porcine CT ships with pcisim, so the truth is an independent model: a
// static neo-Hookean FEM of the same organ (physics/fem) under the same probe, support and
// gravity, with known material parameters. Both sides: the support glued (sticking friction in
// PBD; in the FEM a node that reaches the support is fixed where it touched, and stays: unlike
// friction it would also hold in tension, which a press from above does not ask of it), the probe
// frictionless.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "anatomy/organ/kidney_phantom.h"
#include "anatomy/organ/organ.h"
#include "physics/fem/static_fem.h"
#include "physics/soft_tissue/soft_tissue_spec.h"

namespace pcisim::physics::soft_tissue {

struct CalibrationSetup {
  anatomy::Organ organ;
  ProbeContactParams probe;            // the transducer; start_position_m: just above the skin
  std::vector<double> stage_depths_m;  // how far the probe has moved along its beam at each stage
  // the reference's material (a soft organ's order of magnitude) and mesh
  double young_pa = 5e3;
  double poisson = 0.45;
  double density_kg_per_m3 = 1050.0;
  double fem_spacing_m = 3e-3;
  Eigen::Vector3d gravity_m_per_s2{0.0, 9.81, 0.0};
  // the PBD side, as the paper runs it [soft-tissue, "Calibration"]: 120 steps of warm-up, then
  // the probe interpolated over 90 steps per stage, 1/60 s steps
  double step_s = 1.0 / 60.0;
  int warmup_steps = 120;
  int steps_per_stage = 90;
};

// the setup for the kidney phantom's organ: the probe from anterior (its default pose) 1 mm
// above the skin, stages 3, 6, 9 and 12 mm
CalibrationSetup kidney_calibration_setup(const anatomy::Organ& organ);

// The two kidneys of the calibration: the one it is tuned on (the phantom's defaults, seed 1) and
// a held-out one it never sees while tuning (another shape and bead placement: 10 % longer, 9 %
// flatter, a deeper hilum, seed 2), to show whether the calibration transfers.
enum class CalibrationOrgan { kTuning, kHeldOut };
anatomy::KidneySpec calibration_kidney(CalibrationOrgan which);

struct FemReference {
  std::vector<Eigen::Matrix3Xd> fiducials_m;  // [0]: at rest under gravity, then one per stage
  std::vector<fem::FemSolveReport> solves;
  int nodes = 0, tets = 0;
  double seconds = 0.0;
};
// the reference on `mesh` (a tetrahedral mesh of the organ, metres: e.g. TetGen's, body-fitted),
// or on the voxel mesh of the organ at setup.fem_spacing_m (Kuhn tets, stair-stepped surface)
FemReference solve_fem_reference(const CalibrationSetup& setup, fem::FemMesh mesh);
FemReference solve_fem_reference(const CalibrationSetup& setup);
fem::FemMesh voxel_reference_mesh(const CalibrationSetup& setup);

// A reference as text, so that a test or a search can use a converged reference without solving
// it again (a body-fitted 5 mm reference takes minutes; pcisim-calibrate --solve-references keeps
// them in docs/benchmarks/soft-tissue-reference-*.txt; the callers read and write the files).
// Plain text: a header (the mesh in words, the material, gravity, the probe, the support, the
// stages, whether each solve converged), the organ's fiducials unloaded (to check that the text
// belongs to the organ it is used with), then each stage's fiducials.
// fem_reference_text throws std::invalid_argument when the reference does not have one result of
// the organ's fiducials per stage; parse_fem_reference throws std::runtime_error naming `source`
// on malformed text, and std::invalid_argument naming what differs when the text's material,
// gravity, probe, support, stages or fiducials are not the setup's.
std::string fem_reference_text(const CalibrationSetup& setup, const FemReference& reference,
                               const std::string& mesh_description);
FemReference parse_fem_reference(const std::string& text, const CalibrationSetup& setup, const std::string& source,
                                 std::string* mesh_description = nullptr);

struct StageError {
  double depth_m = 0.0;  // the probe's travel at this stage
  double mean_m = 0.0, std_m = 0.0, max_m = 0.0;
  double mean_displacement_m = 0.0;  // how far the reference's fiducials moved from rest
  // where the fields part (issue #31 item 1; compare_fields below)
  Eigen::Vector3d mean_error_m = Eigen::Vector3d::Zero();
  double shape_error_m = 0.0, response_ratio = 0.0;
  double reference_from_unloaded_m = 0.0, model_from_unloaded_m = 0.0;
};

// The two fields compared, not only their mean distance (every argument one column per fiducial):
//   mean_error_m     the mean of the error vectors model - reference: what a rigid shift of the
//                    model would take away
//   shape_error_m    the mean error once that shift is taken off
//   response_ratio   the model's motion from its rest along the reference's, over the reference's:
//                    sum d_model . d_ref / sum |d_ref|^2 (1: as far; < 1: stiffer); 0 at rest
//   *_from_unloaded  each side's mean fiducial displacement from the unloaded organ (at rest: the
//                    sag under gravity, the error of a model that does not sag)
// Fills those fields of `e`; throws std::invalid_argument on mismatched sizes.
void compare_fields(const Eigen::Matrix3Xd& model_m, const Eigen::Matrix3Xd& reference_m,
                    const Eigen::Matrix3Xd& model_rest_m, const Eigen::Matrix3Xd& reference_rest_m,
                    const Eigen::Matrix3Xd& unloaded_m, StageError* e);

struct PbdRun {
  std::vector<StageError> stages;   // [0]: rest
  double mean_over_stages_m = 0.0;  // the mean over the pressed stages (pcisim-calibrate's objective adds rest)
  std::vector<double> step_ms;      // wall time of each step after the warm-up
  std::vector<Eigen::Matrix3Xd> fiducials_m;  // the model's fiducials at each stage ([0]: rest)
};

// the PBD model of `spec` through the protocol; its fiducials against the reference's
PbdRun run_pbd_protocol(const CalibrationSetup& setup, const SoftTissueSpec& spec, const FemReference& reference);

}  // namespace pcisim::physics::soft_tissue
