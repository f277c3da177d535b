// The kidney's whole step on a CUDA device (TissueParams::solver kJacobiCuda: the clusters, their
// volumes, the support's and the probe's contacts with stabilisation and friction) against its CPU
// twin kJacobi, step by step, while the organ sags onto its support (9 mm at its top with this
// Jacobi setting) and a probe comes down past its rest top and holds (issue #31 item 4). Target
// (issue #31): positions within 1e-9 m after 100 steps. The contacts run the same rules
// (pbd/device_contacts.h), so the forces (summed by blocks on the device: 1e-9 of their size), the
// contact counts and the stabilisation agree too. Where the model itself is sensitive (a deep
// press) the reference is how far two CPU runs part. Skips without a device, except the refusal.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "anatomy/organ/kidney_phantom.h"
#include "physics/pbd/pbd_cuda_solver.h"
#include "physics/soft_tissue/tissue_body.h"

namespace pcisim::physics::soft_tissue {
namespace {

using Eigen::Vector3d;

constexpr double kDt = 1.0 / 30.0;  // the kidney scene's physics rate

const TissueModel& kidney_model() {
  static const TissueModel m = [] {
    anatomy::KidneySpec spec;
    spec.ct_spacing_mm = 4.0;  // the CT is not used here
    const anatomy::KidneyPhantom phantom = anatomy::make_kidney_phantom(spec);
    TissueModelSpec ms;
    ms.particle_radius_m = 3.3e-3;  // the kidney scene's
    return build_tissue_model(phantom.surface, {}, ms);
  }();
  return m;
}

// the kidney scene's calibrated setting (scenes/kidney.json) on the given solver; 27 iterations
// and SOR w 1.5 are scenes/kidney-gpu.json's
TissueParams params(pbd::SolverKind solver, int iterations = 9, double sor_w = 1.0) {
  TissueParams p;
  p.solver = solver;
  p.iterations = iterations;
  p.sor_w = sor_w;
  p.cluster_compliance_s2 = 2e-5;
  p.bulk_modulus_pa = 1e5;
  return p;
}

// a 20 x 30 x 40 mm cuboid above the organ (LPS: +y is down), its bottom face at bottom_y_m
const Vector3d kProbeHalf_m(10e-3, 15e-3, 20e-3);
ProbePose probe_at(double bottom_y_m) {
  ProbePose p;
  p.position_m = Vector3d(0, bottom_y_m - kProbeHalf_m.y(), 0);
  return p;
}

TissueBody make_body(pbd::SolverKind solver, int iterations = 9, double sor_w = 1.0) {
  const TissueModel& m = kidney_model();
  const double top_y_m = m.rest_m.row(1).minCoeff();
  // the table just under the organ's lowest contact sphere
  const ContactPlane table{Vector3d(0, -1, 0), -(m.rest_m.row(1).maxCoeff() + 0.5 * 3.3e-3)};
  return TissueBody(m, params(solver, iterations, sor_w), table, box_probe(kProbeHalf_m, probe_at(top_y_m - 3e-3)));
}

TEST(TissueCuda, WithoutADeviceTheSolverIsNamedInTheError) {
  if (pbd::pbd_cuda_available()) GTEST_SKIP() << "a CUDA device is here: the error path is not reachable";
  TissueBody body = make_body(pbd::SolverKind::kJacobiCuda);
  try {
    body.step(kDt);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("kJacobiCuda"), std::string::npos) << e.what();
  }
}

// how far two bodies part over 100 steps at 30 Hz while the probe comes down from 3 mm above the
// organ's rest top to press_m past it over 2 s (60 steps) and holds
struct Apart {
  double position_m = 0.0, force = 0.0, stabilisation_m = 0.0;
  int count = 0, most_probe_contacts = 0;
  double most_probe_force_n = 0.0;
};

Apart step_side_by_side(TissueBody& a, TissueBody& b, double press_m) {
  const double top_y_m = kidney_model().rest_m.row(1).minCoeff();
  Apart out;
  for (int k = 1; k <= 100; ++k) {
    const double bottom_y_m = top_y_m - 3e-3 + (press_m + 3e-3) * std::min(1.0, k / 60.0);
    for (TissueBody* t : {&a, &b}) {
      t->set_probe_pose(probe_at(bottom_y_m));
      t->step(kDt);
    }
    out.position_m = std::max(out.position_m, (a.positions_m() - b.positions_m()).colwise().norm().maxCoeff());
    const double scale_n = std::max(1e-3, a.probe_force_n().norm() + a.support_force_n().norm());
    out.force = std::max(out.force, ((a.probe_force_n() - b.probe_force_n()).norm() +
                                     (a.support_force_n() - b.support_force_n()).norm()) /
                                        scale_n);
    out.count = std::max({out.count, std::abs(a.contacts().probe_contacts() - b.contacts().probe_contacts()),
                          std::abs(a.contacts().support_contacts() - b.contacts().support_contacts())});
    out.stabilisation_m = std::max(out.stabilisation_m,
                                   std::abs(a.contacts().stabilisation_max_m() - b.contacts().stabilisation_max_m()));
    out.most_probe_contacts = std::max(out.most_probe_contacts, b.contacts().probe_contacts());
    out.most_probe_force_n = std::max(out.most_probe_force_n, b.probe_force_n().norm());
  }
  return out;
}

void print(const char* what, const Apart& g, int particles) {
  std::printf(
      "[ measured ] %s, kidney r 3.3 mm, %d particles, 100 steps: max |x_a - x_b| = %.3g m, forces %.3g of their "
      "size, contact counts differ by %d, stabilisation by %.3g m; the probe met %d particles, pushed %.3g N\n",
      what, particles, g.position_m, g.force, g.count, g.stabilisation_m, g.most_probe_contacts, g.most_probe_force_n);
}

// the organ sags 9 mm at its top with this Jacobi setting, so an 8 mm press barely dents it: the
// run stays where two CPU runs apart by 1e-15 m stay within 1e-12 m, and the twin is held to 1e-9 m
TEST(TissueCuda, TheGpuStepWithItsContactsIsTheCpuJacobiStep) {
  std::string why;
  if (!pbd::pbd_cuda_available(&why)) GTEST_SKIP() << "no usable CUDA device (" << why << ")";
  TissueBody cpu = make_body(pbd::SolverKind::kJacobi), gpu = make_body(pbd::SolverKind::kJacobiCuda);
  const Apart g = step_side_by_side(cpu, gpu, 8e-3);
  print("CPU vs GPU, 8 mm press", g, gpu.particle_count());
  EXPECT_GT(g.most_probe_contacts, 10);  // the probe met the organ
  EXPECT_GT(g.most_probe_force_n, 1e-4);
  EXPECT_GT(gpu.support_force_n().norm(), 0.5);  // it rests on its support (~1 N)
  EXPECT_LE(g.position_m, 1e-9);
  EXPECT_LE(g.force, 1e-9);
  EXPECT_EQ(g.count, 0);
  EXPECT_LE(g.stabilisation_m, 1e-9);
}

// the GPU scene's solver (scenes/kidney-gpu.json: 27 iterations, SOR w 1.5) is stiffer and
// converges further, and it is sensitive as soon as the probe pushes: two CPU runs 1e-15 m apart
// part by 1.5e-9 m over a 5 mm press (0.09 N) and 1.8e-4 m over an 8 mm one (0.46 N; H200 host,
// 2026-12-02). So the twin is held to ten times what the CPU parts from itself, and never looser
// than 1e-9 m (1e-8 of the forces): sagging with the probe held above (4.5e-15 m measured),
// pressed 5 mm (7.2e-9 m against 1.5e-8) and 8 mm (1.3e-4 m against 1.8e-3: there a wrong rule
// below a millimetre would pass, so the contacts must also match one for one)
TEST(TissueCuda, TheGpuScenesStepIsItsCpuTwin) {
  std::string why;
  if (!pbd::pbd_cuda_available(&why)) GTEST_SKIP() << "no usable CUDA device (" << why << ")";
  for (double press_m : {-3e-3, 5e-3, 8e-3}) {
    TissueBody cpu = make_body(pbd::SolverKind::kJacobi, 27, 1.5), nudged = cpu,
               gpu = make_body(pbd::SolverKind::kJacobiCuda, 27, 1.5);
    nudged.system().particles().position_m.array() += 1e-15;
    const Apart g = step_side_by_side(cpu, gpu, press_m);
    TissueBody again = make_body(pbd::SolverKind::kJacobi, 27, 1.5);
    const Apart self = step_side_by_side(again, nudged, press_m);
    const std::string what = "27 iterations, w 1.5, press " + std::to_string(press_m * 1e3) + " mm";
    print(("CPU vs GPU, " + what).c_str(), g, gpu.particle_count());
    print(("CPU vs CPU nudged 1e-15 m, " + what).c_str(), self, gpu.particle_count());
    EXPECT_GT(gpu.support_force_n().norm(), 0.5) << what;
    if (press_m > 0.0) EXPECT_GT(g.most_probe_contacts, 10) << what;
    EXPECT_LE(g.position_m, std::max(1e-9, 10.0 * self.position_m)) << what;
    EXPECT_LE(g.force, std::max(1e-8, 10.0 * self.force)) << what;
    EXPECT_EQ(g.count, 0) << what;
    EXPECT_LE(g.stabilisation_m, 1e-9) << what;
  }
}

// pressed 14 mm past its rest top the model itself is sensitive: two CPU runs whose positions
// start 1e-15 m apart end ~1e-5 m apart (measured 1.5e-5 m, 2026-12-02). There the GPU is held to
// ten times what the CPU's own runs part by, so a wrong rule (mm) still fails; the strict 1e-9 m
// holds only if the run is not sensitive
TEST(TissueCuda, PressedDeepTheGpuStaysAsCloseAsTheCpuToItself) {
  std::string why;
  if (!pbd::pbd_cuda_available(&why)) GTEST_SKIP() << "no usable CUDA device (" << why << ")";
  TissueBody cpu = make_body(pbd::SolverKind::kJacobi), nudged = cpu, gpu = make_body(pbd::SolverKind::kJacobiCuda);
  nudged.system().particles().position_m.array() += 1e-15;
  TissueBody cpu_again = cpu;
  const Apart self = step_side_by_side(cpu, nudged, 14e-3);
  const Apart g = step_side_by_side(cpu_again, gpu, 14e-3);
  print("CPU vs CPU nudged 1e-15 m, 14 mm press", self, gpu.particle_count());
  print("CPU vs GPU, 14 mm press", g, gpu.particle_count());
  EXPECT_GT(g.most_probe_force_n, 0.1);  // pressed: ~0.25 N
  EXPECT_EQ(g.count, 0);
  EXPECT_LE(g.position_m, std::max(1e-9, 10.0 * self.position_m));
  EXPECT_LE(g.force, std::max(1e-9, 10.0 * self.force));
}

}  // namespace
}  // namespace pcisim::physics::soft_tissue
