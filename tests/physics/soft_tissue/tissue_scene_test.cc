// The soft-tissue scene's physics in the World: the kidney settles on its support, the probe the
// user moves presses it (force along the beam, a local force model for the haptic loop), the
// skinned tet mesh and fiducials follow, a bad pose is ignored, and it recovers after release.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "anatomy/organ/kidney_phantom.h"
#include "physics/pbd/pbd_cuda_solver.h"
#include "physics/soft_tissue/tissue_scene.h"
#include "physics/world.h"

namespace pcisim::physics {
namespace {

using Eigen::Vector3d;

const anatomy::Organ& kidney() {
  static const anatomy::Organ organ = [] {
    anatomy::KidneySpec spec;
    spec.ct_spacing_mm = 4.0;  // the CT is not used here
    return anatomy::kidney_organ(anatomy::make_kidney_phantom(spec));
  }();
  return organ;
}

WorldSpec tissue_spec() {
  WorldSpec s;
  s.step_s = 1.0 / 30.0;
  s.soft_tissue.emplace();
  s.soft_tissue->model.particle_radius_m = 4e-3;  // coarse: seconds in Release and under ASan
  s.probe_contact.emplace();
  return s;
}

// the probe as scenes/kidney.json holds it: face toward +y (posterior), lateral along S
InstrumentInput probe_at(double y_m) {
  InstrumentInput in;
  in.probe_present = true;
  in.probe_position_m = {0.0, y_m, 0.0};
  in.probe_orientation_wxyz = {0.5, -0.5, -0.5, -0.5};
  return in;
}

TEST(TissueScene, TheStartRotationPutsTheBeamPosteriorAndTheLateralAxisAlongS) {
  const soft_tissue::ProbeContactParams p;
  const Eigen::Matrix3d r = p.start_rotation.toRotationMatrix();
  EXPECT_LT((r * Vector3d::UnitZ() - Vector3d::UnitY()).norm(), 1e-12);
  EXPECT_LT((r * Vector3d::UnitX() - Vector3d::UnitZ()).norm(), 1e-12);
}

TEST(TissueScene, TheTransducerFaceIsAtTheProbesOrigin) {
  soft_tissue::ProbeContactParams p;
  const soft_tissue::ProbePose pose{Vector3d(0.01, 0.02, 0.03), p.start_rotation};
  const soft_tissue::ConvexProbe probe = soft_tissue::transducer(p, pose);
  const Vector3d beam = p.start_rotation * Vector3d::UnitZ();
  auto inside = [&](const Vector3d& x_world) {
    const Vector3d x = pose.rotation.inverse() * (x_world - pose.position_m);
    for (const auto& f : probe.faces)
      if (f.normal.dot(x) > f.offset_m) return false;
    return true;
  };
  EXPECT_FALSE(inside(pose.position_m + 1e-3 * beam));   // in front of the face: tissue side
  EXPECT_TRUE(inside(pose.position_m - 1e-3 * beam));    // behind it: the block
  EXPECT_FALSE(inside(pose.position_m - 31e-3 * beam));  // beyond its 30 mm height
}

TEST(TissueScene, TheForceModelIsTheSecantAlongTheBeamAndZeroOutOfContact) {
  soft_tissue::ProbeContactParams p;
  p.max_stiffness_n_per_m = 500.0;
  soft_tissue::ProbeForceModel m(p);
  const Vector3d beam = Vector3d::UnitY();
  // out of contact: nothing
  LocalForceModel a = m.update(Vector3d(0, -0.02, 0), beam, Vector3d::Zero(), 0.1, 1.0 / 30);
  EXPECT_EQ(a.f0_n, 0.0);
  EXPECT_EQ(a.k_n_per_m, 0.0);
  EXPECT_GT(a.valid_for_us, 0);
  // 1 mm deeper, the tissue pushes 0.2 N back (along -beam): K = 200 N/m
  LocalForceModel b = m.update(Vector3d(0, -0.019, 0), beam, Vector3d(0, -0.2, 0), 0.2, 1.0 / 30);
  EXPECT_NEAR(b.f0_n, 0.2, 1e-12);
  EXPECT_NEAR(b.x0_m, -0.019, 1e-12);
  EXPECT_NEAR(b.k_n_per_m, 200.0, 1e-9);
  // 1 mm more and 1 N more: 1000 N/m, clamped to 500
  LocalForceModel c = m.update(Vector3d(0, -0.018, 0), beam, Vector3d(0, -1.2, 0), 0.3, 1.0 / 30);
  EXPECT_EQ(c.k_n_per_m, 500.0);
  // a depth change under 0.1 mm keeps the last K
  LocalForceModel d = m.update(Vector3d(0, -0.01795, 0), beam, Vector3d(0, -1.3, 0), 0.4, 1.0 / 30);
  EXPECT_EQ(d.k_n_per_m, 500.0);
}

TEST(TissueScene, WorldRefusesWhatCannotBeBuilt) {
  WorldSpec s = tissue_spec();
  // no organ
  EXPECT_THROW(World(s, anatomy::VesselTree{}), std::invalid_argument);
  // the wire does not go with it
  WorldSpec w = tissue_spec();
  w.guidewire.emplace();
  try {
    World(w, anatomy::VesselTree{}, nullptr, {}, {}, &kidney());
    FAIL() << "a tissue scene with a guidewire was built";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("soft_tissue"), std::string::npos) << e.what();
  }
  // a probe without tissue
  WorldSpec p;
  p.probe_contact.emplace();
  EXPECT_THROW(World{p}, std::invalid_argument);
  // a particle radius out of range names the field
  WorldSpec r = tissue_spec();
  r.soft_tissue->model.particle_radius_m = 50e-3;
  try {
    World(r, anatomy::VesselTree{}, nullptr, {}, {}, &kidney());
    FAIL() << "a 50 mm particle radius was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("soft_tissue.particle_radius_m"), std::string::npos) << e.what();
  }
}

// a press of 8 mm and back: force along -beam, a force model, snapshots that follow, recovery
TEST(TissueScene, TheProbePressesTheKidneyAndItRecovers) {
  World world(tissue_spec(), anatomy::VesselTree{}, nullptr, {}, {}, &kidney());
  ASSERT_NE(world.tissue_state(), nullptr);
  ASSERT_EQ(world.effect_costs().size(), 1u);
  EXPECT_EQ(world.effect_costs()[0].name, "soft_tissue");
  WorldSnapshot rest;
  world.step(probe_at(-0.0225));  // 5 mm above the anterior skin (y = -17.5 mm)
  world.write_snapshot(rest);
  const Eigen::Matrix3Xd particles_at_rest = world.tissue_state()->body().positions_m();
  ASSERT_FALSE(rest.tissue_tet_vertices_m.empty());
  ASSERT_EQ(rest.fiducials_m.size(), kidney().fiducials_m.size());
  EXPECT_TRUE(rest.probe_present);
  EXPECT_LT(rest.probe_force_n.norm(), 1e-9);  // not touching
  EXPECT_EQ(world.force_model().f0_n, 0.0);

  // press to 8 mm below the skin over 1 s, hold 0.5 s
  double peak_force_n = 0.0, peak_model_k = 0.0, last_free_y_m = -0.0225;
  WorldSnapshot snap;
  for (int i = 1; i <= 45; ++i) {
    const double y = -0.0225 + 0.013 * std::min(1.0, i / 30.0);
    world.step(probe_at(y));
    world.write_snapshot(snap);
    const Vector3d beam = snap.probe_rotation.col(2);
    peak_force_n = std::max(peak_force_n, -snap.probe_force_n.dot(beam));
    peak_model_k = std::max(peak_model_k, world.force_model().k_n_per_m);
    if (-snap.probe_force_n.dot(beam) <= 0.0) last_free_y_m = y;
    ASSERT_TRUE(snap.probe_force_n.allFinite());
  }
  const LocalForceModel pressed = world.force_model();
  EXPECT_GT(pressed.f0_n, 0.1) << "the kidney pushes the probe back";
  EXPECT_NEAR(pressed.x0_m, -0.0095, 1e-9) << "depth along the beam (+y)";
  // the haptic K (the secant between steps) against two estimates made without it. (1) The held
  // force over the indentation since the probe last felt nothing (0.55 N over 6.5 mm: 85 N/m,
  // measured after 0.5 s of holding, at rest): a contact whose area grows as it is pressed
  // (f ~ d^n, n from 1 for a flat punch to 2 for a cone; 1.5 for Hertz) stiffens to n f / d, so
  // the largest secant lies between 1 and 2 times it (measured 130 N/m, 1.5 x). (2) A flat 40 x
  // 12 mm punch on an elastic half-space, K = 2 E a / (1 - nu^2) with a = sqrt(A / pi) = 12.4 mm
  // and the 5 kPa, nu 0.45 of the FEM the compliance was calibrated against (docs/soft-tissue.md):
  // 155 N/m; the organ is finite (softer) and sits on its support (stiffer), so within 2 x
  const double settled_secant = pressed.f0_n / (pressed.x0_m - last_free_y_m);
  EXPECT_GE(peak_model_k, settled_secant);
  EXPECT_LE(peak_model_k, 2.0 * settled_secant);
  const double punch_k = 2.0 * 5e3 * std::sqrt(0.040 * 0.012 / M_PI) / (1.0 - 0.45 * 0.45);
  EXPECT_GT(peak_model_k, 0.5 * punch_k);
  EXPECT_LT(peak_model_k, 2.0 * punch_k);
  EXPECT_LE(peak_model_k, soft_tissue::ProbeContactParams{}.max_stiffness_n_per_m);
  // the skin under the probe went with it (the organ is squeezed against its support), and the
  // coarse tet mesh the image maps through follows it
  const double deepest_particle_m = (world.tissue_state()->body().positions_m() - particles_at_rest).row(1).maxCoeff();
  EXPECT_GT(deepest_particle_m, 5e-3);
  double deepest_tet_m = 0.0;
  for (size_t v = 0; v < snap.tissue_tet_vertices_m.size(); ++v)
    deepest_tet_m = std::max(deepest_tet_m, snap.tissue_tet_vertices_m[v].y() - rest.tissue_tet_vertices_m[v].y());
  EXPECT_GT(deepest_tet_m, 1e-3);
  std::printf(
      "8 mm press at 4 mm particles: force %.2f N along the beam (peak %.2f), K %.0f N/m (largest %.0f; held force "
      "over the indentation %.0f N/m, flat punch %.0f N/m), deepest particle move %.1f mm, deepest tet vertex %.1f "
      "mm\n",
      pressed.f0_n, peak_force_n, pressed.k_n_per_m, peak_model_k, settled_secant, punch_k, deepest_particle_m * 1e3,
      deepest_tet_m * 1e3);

  // a NaN pose is ignored: the probe stays where it was
  InstrumentInput bad = probe_at(std::numeric_limits<double>::quiet_NaN());
  world.step(bad);
  world.write_snapshot(snap);
  EXPECT_NEAR(snap.probe_position_m.y(), -0.0095, 1e-12);
  EXPECT_TRUE(snap.probe_force_n.allFinite());

  // release and wait 1.5 s: back to rest within a millimetre, the probe feels nothing
  for (int i = 0; i < 45; ++i) world.step(probe_at(-0.0225));
  world.write_snapshot(snap);
  double worst_m = 0.0;
  for (size_t v = 0; v < snap.tissue_tet_vertices_m.size(); ++v)
    worst_m = std::max(worst_m, (snap.tissue_tet_vertices_m[v] - rest.tissue_tet_vertices_m[v]).norm());
  EXPECT_LT(worst_m, 1e-3);
  EXPECT_EQ(world.force_model().f0_n, 0.0);
  std::printf("recovered to %.3f mm of rest\n", worst_m * 1e3);
}

// the scene's device "cuda" (effects.soft_tissue): the world steps the organ on the GPU as its
// CPU twin (solver "jacobi") does, the probe pressing through the world's input (issue #31 item 4)
TEST(TissueScene, TheWorldStepsTheOrganOnTheGpuAsItsCpuTwin) {
  std::string why;
  if (!pbd::pbd_cuda_available(&why)) GTEST_SKIP() << "no usable CUDA device (" << why << ")";
  WorldSpec cpu_spec = tissue_spec(), gpu_spec = tissue_spec();
  cpu_spec.soft_tissue->params.solver = pbd::SolverKind::kJacobi;
  gpu_spec.soft_tissue->params.solver = pbd::SolverKind::kJacobiCuda;
  World cpu(cpu_spec, anatomy::VesselTree{}, nullptr, {}, {}, &kidney());
  World gpu(gpu_spec, anatomy::VesselTree{}, nullptr, {}, {}, &kidney());
  double gap_m = 0.0;
  for (int k = 0; k < 45; ++k) {
    const double y = -0.0225 + 0.010 * std::min(1.0, k / 30.0);  // 5 mm above the skin to 5 mm into it
    cpu.step(probe_at(y));
    gpu.step(probe_at(y));
    gap_m = std::max(gap_m, (cpu.tissue_state()->body().positions_m() - gpu.tissue_state()->body().positions_m())
                                .colwise()
                                .norm()
                                .maxCoeff());
  }
  std::printf("[ measured ] the world's organ, CPU vs GPU over 45 steps: %.3g m; probe force %.3g N\n", gap_m,
              gpu.tissue_state()->probe_force_n().norm());
  EXPECT_GT(gpu.tissue_state()->body().contacts().probe_contacts(), 0);
  EXPECT_LE(gap_m, 1e-9);
}

}  // namespace
}  // namespace pcisim::physics
