// The calibration protocol. The FEM reference converges at every stage on a coarse kidney and its
// beads go deeper as the probe does; a reference kept as text reads back exactly and is refused
// for another organ, material, probe, support or stages; and against the converged body-fitted reference
// pcisim-calibrate solved (docs/benchmarks/soft-tissue-reference-*.txt), the calibrated PBD model beats a much stiffer
// and a much softer one, and beats standing still (the reference's own bead motion) at the last stage, on the kidney it
// was tuned on and on the held-out one.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "anatomy/organ/kidney_phantom.h"
#include "physics/soft_tissue/calibration.h"

namespace pcisim::physics::soft_tissue {
namespace {

CalibrationSetup setup_for(CalibrationOrgan which) {
  CalibrationSetup s =
      kidney_calibration_setup(anatomy::kidney_organ(anatomy::make_kidney_phantom(calibration_kidney(which))));
  // fewer steps than the paper's 120 + 90: the press is quasi-static (measured at 5 mm particles,
  // compliance 3e-5: 1.94, 1.94 and 1.96 mm mean error over the stages with 10 + 5, 20 + 10 and
  // 10 + 10 steps; at 7 mm 2.43 with 20 + 10 and 120 + 90)
  s.warmup_steps = 10;
  s.steps_per_stage = 5;
  return s;
}

std::string stored_reference_path(CalibrationOrgan which) {
  return std::string(PCISIM_SOURCE_DIR) + "/docs/benchmarks/soft-tissue-reference-" +
         (which == CalibrationOrgan::kTuning ? "tuning" : "held-out") + ".txt";
}

// the coarse voxel reference: seconds, not minutes, and stair-stepped (docs/soft-tissue.md: it is
// not converged, so only the pipeline is checked on it, never the PBD)
const FemReference& coarse_reference() {
  static const FemReference ref = [] {
    CalibrationSetup s = setup_for(CalibrationOrgan::kTuning);
    s.fem_spacing_m = 6e-3;
    return solve_fem_reference(s);
  }();
  return ref;
}

TEST(Calibration, TheReferenceConvergesAndItsBeadsGoDeeper) {
  const FemReference& ref = coarse_reference();
  ASSERT_EQ(ref.fiducials_m.size(), setup_for(CalibrationOrgan::kTuning).stage_depths_m.size() + 1);
  for (const auto& r : ref.solves) EXPECT_TRUE(r.converged) << "residual " << r.residual_n;
  // deeper stages move the beads further (mean displacement from rest, strictly increasing)
  double last = 0.0;
  for (size_t k = 1; k < ref.fiducials_m.size(); ++k) {
    const double d = (ref.fiducials_m[k] - ref.fiducials_m[0]).colwise().norm().mean();
    EXPECT_GT(d, last) << "stage " << k;
    last = d;
  }
  EXPECT_GT(last, 1e-3) << "a 12 mm press moves the beads by a millimetre or more on average";
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

FemReference stored_reference(CalibrationOrgan which) {
  return parse_fem_reference(read_text(stored_reference_path(which)), setup_for(which), stored_reference_path(which));
}

TEST(Calibration, AReferenceAsTextReadsBackAndIsRefusedForAnotherSetup) {
  const CalibrationSetup tuning = setup_for(CalibrationOrgan::kTuning);
  const std::string text = fem_reference_text(tuning, coarse_reference(), "voxel tets of 6 mm");
  std::string words;
  const FemReference back = parse_fem_reference(text, tuning, "test", &words);
  EXPECT_EQ(words, "voxel tets of 6 mm");
  ASSERT_EQ(back.fiducials_m.size(), coarse_reference().fiducials_m.size());
  for (size_t k = 0; k < back.fiducials_m.size(); ++k) {
    EXPECT_EQ((back.fiducials_m[k] - coarse_reference().fiducials_m[k]).cwiseAbs().maxCoeff(), 0.0) << "stage " << k;
    EXPECT_EQ(back.solves[k].converged, coarse_reference().solves[k].converged);
  }
  // another organ, material, probe, support or stages
  EXPECT_THROW(parse_fem_reference(text, setup_for(CalibrationOrgan::kHeldOut), "test"), std::invalid_argument);
  auto refused = [&](auto change) {
    CalibrationSetup other = tuning;
    change(other);
    try {
      parse_fem_reference(text, other, "test");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(refused([](CalibrationSetup& s) { s.young_pa *= 2.0; }).find("material"), std::string::npos);
  EXPECT_NE(refused([](CalibrationSetup& s) { s.probe.face_width_m = 0.05; }).find("probe"), std::string::npos);
  EXPECT_NE(refused([](CalibrationSetup& s) { s.organ.support_offset_m += 1e-3; }).find("support"), std::string::npos);
  EXPECT_NE(refused([](CalibrationSetup& s) { s.stage_depths_m.pop_back(); }).find("stages"), std::string::npos);
  // malformed: cut short, another version, text after the last stage
  EXPECT_THROW(parse_fem_reference(text.substr(0, text.size() / 2), tuning, "test"), std::runtime_error);
  EXPECT_THROW(parse_fem_reference("pcisim-fem-reference 1\n" + text.substr(text.find('\n') + 1), tuning, "test"),
               std::runtime_error);
  EXPECT_THROW(parse_fem_reference(text + "stage 5\n", tuning, "test"), std::runtime_error);
  // a reference without one result per stage is not written
  FemReference short_ref = coarse_reference();
  short_ref.fiducials_m.pop_back();
  short_ref.solves.pop_back();
  EXPECT_THROW(fem_reference_text(tuning, short_ref, "x"), std::invalid_argument);
  // the committed references belong to their organs
  EXPECT_NO_THROW(stored_reference(CalibrationOrgan::kTuning));
  EXPECT_NO_THROW(stored_reference(CalibrationOrgan::kHeldOut));
}

// pcisim-calibrate's optimum at 3.3 mm particles, the kidney scene's
// (docs/benchmarks/soft-tissue-calibration.md)
constexpr double kRadiusM = 3.3e-3;
constexpr double kCalibratedComplianceS2 = 2e-5;
constexpr double kCalibratedBulkPa = 100e3;

PbdRun run_at(CalibrationOrgan which, double compliance_s2) {
  static const FemReference tuning_ref = stored_reference(CalibrationOrgan::kTuning);
  static const FemReference held_out_ref = stored_reference(CalibrationOrgan::kHeldOut);
  SoftTissueSpec spec;
  spec.model.particle_radius_m = kRadiusM;
  spec.params.cluster_compliance_s2 = compliance_s2;
  spec.params.bulk_modulus_pa = kCalibratedBulkPa;
  return run_pbd_protocol(setup_for(which), spec, which == CalibrationOrgan::kTuning ? tuning_ref : held_out_ref);
}

double mean_over_stages(const PbdRun& r) {
  double sum = 0.0;
  for (const StageError& e : r.stages) sum += e.mean_m;
  return sum / static_cast<double>(r.stages.size());
}

TEST(Calibration, TheCalibratedStiffnessBeatsAStifferAndASofterOne) {
  // calibrated, 20 x stiffer, 50 x softer
  const PbdRun cal = run_at(CalibrationOrgan::kTuning, kCalibratedComplianceS2);
  const PbdRun stiff = run_at(CalibrationOrgan::kTuning, 1e-6), soft = run_at(CalibrationOrgan::kTuning, 1e-3);
  for (const PbdRun* r : {&cal, &stiff, &soft}) {
    ASSERT_EQ(r->stages.size(), 5u);
    EXPECT_EQ(r->step_ms.size(), 4u * 5u);
  }
  std::printf("mean error over the stages at 3.3 mm: compliance %.0e %.2f mm, 1e-6 %.2f mm, 1e-3 %.2f mm\n",
              kCalibratedComplianceS2, mean_over_stages(cal) * 1e3, mean_over_stages(stiff) * 1e3,
              mean_over_stages(soft) * 1e3);
  // measured 0.74 mm calibrated against 1.46 mm stiffer and 7.99 mm softer
  EXPECT_LT(mean_over_stages(cal), mean_over_stages(stiff) - 0.2e-3);
  EXPECT_LT(mean_over_stages(cal), 0.5 * mean_over_stages(soft));
}

// The no-deformation baseline: a model that did not move at all would be off at the last stage by
// the reference's own mean bead displacement; the calibrated model must explain at least 40 % of
// that motion, on the kidney it was tuned on and on the held-out one it never saw
TEST(Calibration, TheCalibratedModelBeatsStandingStillAtTheLastStage) {
  for (CalibrationOrgan which : {CalibrationOrgan::kTuning, CalibrationOrgan::kHeldOut}) {
    const StageError last = run_at(which, kCalibratedComplianceS2).stages.back();
    std::printf("%s kidney at %.0f mm travel: %.2f mm off, the reference's beads moved %.2f mm\n",
                which == CalibrationOrgan::kTuning ? "tuning" : "held-out", last.depth_m * 1e3, last.mean_m * 1e3,
                last.mean_displacement_m * 1e3);
    // measured 1.17 mm off where the beads moved 2.67 mm (tuning), 1.42 of 2.74 mm (held out); the
    // paper's model (shape matching alone) 2.17 of 2.67 mm at its optimum: it fails this
    EXPECT_LT(last.mean_m, 0.6 * last.mean_displacement_m)
        << "at " << last.depth_m * 1e3 << " mm travel: " << last.mean_m * 1e3 << " mm off, the reference's beads moved "
        << last.mean_displacement_m * 1e3 << " mm";
  }
}

// compare_fields on fields with exact truth: a model that is the reference shifted rigidly has
// all its error in the mean vector and none in the shape; one that moves half as far from its
// rest as the reference has a response ratio of 0.5; the sag from the unloaded organ per side
TEST(Calibration, TheFieldComparisonSplitsAShiftFromAShapeAndMeasuresTheResponse) {
  Eigen::Matrix3Xd unloaded(3, 4), rest(3, 4), pressed(3, 4);
  unloaded << 0, 10, 0, 0,  //
      0, 0, 10, 0,          //
      0, 0, 0, 10;
  unloaded *= 1e-3;
  rest = unloaded.colwise() + Eigen::Vector3d(0, 2e-3, 0);  // sagged 2 mm
  pressed = rest;
  pressed.row(1) += Eigen::RowVector4d(1, 2, 3, 4) * 1e-3;  // pressed 1-4 mm along y

  const Eigen::Vector3d shift(0.3e-3, -0.1e-3, 0.2e-3);
  StageError e;
  compare_fields(pressed.colwise() + shift, pressed, rest.colwise() + shift, rest, unloaded, &e);
  EXPECT_LT((e.mean_error_m - shift).norm(), 1e-15);
  EXPECT_LT(e.shape_error_m, 1e-15);
  EXPECT_NEAR(e.response_ratio, 1.0, 1e-12) << "shifted, it moves as far";
  EXPECT_NEAR(e.reference_from_unloaded_m, (3e-3 + 4e-3 + 5e-3 + 6e-3) / 4, 1e-15);

  const Eigen::Matrix3Xd half = rest + 0.5 * (pressed - rest);
  compare_fields(half, pressed, rest, rest, unloaded, &e);
  EXPECT_NEAR(e.response_ratio, 0.5, 1e-12);
  EXPECT_NEAR(e.model_from_unloaded_m, (2.5e-3 + 3e-3 + 3.5e-3 + 4e-3) / 4, 1e-15);
  // its mean vector is the mean of the half-presses missed (along y), the rest is shape
  EXPECT_NEAR(e.mean_error_m.y(), -0.5 * 2.5e-3, 1e-15);
  EXPECT_EQ(e.mean_error_m.x(), 0.0);
  EXPECT_EQ(e.mean_error_m.z(), 0.0);
  EXPECT_NEAR(e.shape_error_m, (0.75e-3 + 0.25e-3 + 0.25e-3 + 0.75e-3) / 4, 1e-15);

  // moved as far but across the reference's motion: no response; against it: -1
  Eigen::Matrix3Xd across = rest;
  across.row(0) += Eigen::RowVector4d(1, 2, 3, 4) * 1e-3;
  compare_fields(across, pressed, rest, rest, unloaded, &e);
  EXPECT_NEAR(e.response_ratio, 0.0, 1e-15);
  compare_fields(rest - (pressed - rest), pressed, rest, rest, unloaded, &e);
  EXPECT_NEAR(e.response_ratio, -1.0, 1e-12);

  EXPECT_THROW(compare_fields(half.leftCols(3), pressed, rest, rest, unloaded, &e), std::invalid_argument);
}

}  // namespace
}  // namespace pcisim::physics::soft_tissue
