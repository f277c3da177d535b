#include "physics/soft_tissue/calibration.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "physics/fem/voxel_mesh.h"
#include "physics/soft_tissue/tissue_scene.h"

namespace pcisim::physics::soft_tissue {
namespace {

using Clock = std::chrono::steady_clock;

ProbePose stage_pose(const CalibrationSetup& s, double depth_m) {
  const Eigen::Quaterniond q = s.probe.start_rotation.normalized();
  return {s.probe.start_position_m + depth_m * (q * Eigen::Vector3d::UnitZ()), q};
}

// the transducer at a pose as the FEM's penalty body (the same faces the PBD contacts use)
fem::FemConvexBody probe_body(const CalibrationSetup& s, const ProbePose& pose) {
  fem::FemConvexBody body;
  for (const HalfSpace& f : transducer(s.probe, pose).faces) {
    const ContactPlane w = world_face(f, pose);
    body.faces.push_back({w.normal, w.offset_m});
  }
  return body;
}

}  // namespace

CalibrationSetup kidney_calibration_setup(const anatomy::Organ& organ) {
  CalibrationSetup s;
  s.organ = organ;
  // the anterior skin on the beam through the probe's default face centre
  double skin_y = 0.0;
  for (const Eigen::Vector3d& v : organ.surface.vertices_m) skin_y = std::min(skin_y, v.y());
  s.probe.start_position_m = Eigen::Vector3d(0.0, skin_y - 1e-3, 0.0);
  s.stage_depths_m = {4e-3, 7e-3, 10e-3, 13e-3};  // 3, 6, 9 and 12 mm into the skin
  return s;
}

anatomy::KidneySpec calibration_kidney(CalibrationOrgan which) {
  anatomy::KidneySpec k;
  k.ct_spacing_mm = 4.0;  // the calibration never reads the CT
  if (which == CalibrationOrgan::kHeldOut) {
    k.semi_axes_mm = {31.0, 16.0, 60.0};
    k.hilum_depth = 0.5;
    k.seed = 2;
  }
  return k;
}

fem::FemMesh voxel_reference_mesh(const CalibrationSetup& s) {
  TissueModelSpec voxels;
  voxels.voxel_m = s.fem_spacing_m;
  voxels.particle_radius_m = s.fem_spacing_m;
  const TissueModel grid = build_tissue_model(s.organ.surface, {}, voxels);
  return fem::voxel_tet_mesh(grid.interior_voxels_m, s.fem_spacing_m);
}

FemReference solve_fem_reference(const CalibrationSetup& s) {
  return solve_fem_reference(s, voxel_reference_mesh(s));
}

FemReference solve_fem_reference(const CalibrationSetup& s, fem::FemMesh mesh) {
  const auto t0 = Clock::now();
  const fem::StaticFem fem(std::move(mesh), fem::neo_hookean_from_young(s.young_pa, s.poisson));
  const int n = fem.node_count();
  std::vector<fem::Embedding> beads;
  for (const Eigen::Vector3d& f : s.organ.fiducials_m) beads.push_back(fem::embed(fem.mesh(), f));

  // the support: the organ's own plane, frictionless penalty contact plus sticking (the PBD
  // side's friction sticks). Nodes within kTouch_m of it at rest, and at least the nearest, start
  // glued; after each solve the nodes the penalty holds inside it are glued where they are and
  // the solve repeated, until none is new: the contact patch grows as the organ sags or is
  // pressed, the same whatever the mesh
  constexpr double kTouch_m = 0.5e-3;
  const Eigen::Vector3d n_support = s.organ.support_normal.normalized();
  const double offset = s.organ.support_offset_m;
  fem::FemBoundary bc{std::vector<uint8_t>(3 * n, 0), fem.rest_positions()};
  auto glue = [&](int v, const Eigen::Vector3d& at) {
    bc.fixed[3 * v] = bc.fixed[3 * v + 1] = bc.fixed[3 * v + 2] = 1;
    bc.target_m.segment<3>(3 * v) = at;
  };
  int nearest = 0;
  for (int v = 0; v < n; ++v) {
    const Eigen::Vector3d p = fem.mesh().rest_m.col(v);
    if (n_support.dot(p) < n_support.dot(fem.mesh().rest_m.col(nearest))) nearest = v;
    if (n_support.dot(p) < offset + kTouch_m) glue(v, p);
  }
  glue(nearest, fem.mesh().rest_m.col(nearest));
  fem::FemSolveOptions opt;
  opt.load_steps = 1;
  opt.force_tolerance_n = 1e-7;
  opt.external_force_n.resize(3 * n);
  const Eigen::VectorXd mass = fem.lumped_masses_kg(s.density_kg_per_m3);
  for (int v = 0; v < n; ++v) opt.external_force_n.segment<3>(3 * v) = mass[v] * s.gravity_m_per_s2;
  opt.supports.push_back({n_support, offset});

  FemReference ref;
  ref.nodes = n;
  ref.tets = static_cast<int>(fem.mesh().tets.size());
  auto solve_sticking = [&](Eigen::VectorXd* x) {
    fem::FemSolveReport total;
    for (int round = 0; round < 20; ++round) {
      const fem::FemSolveReport r = fem.solve(bc, x, opt);
      total.newton_iterations += r.newton_iterations;
      total.residual_n = r.residual_n;
      total.converged = r.converged;
      int glued = 0;
      for (int v = 0; v < n; ++v) {
        const Eigen::Vector3d p = x->segment<3>(3 * v);
        const double depth = offset - n_support.dot(p);
        if (!bc.fixed[3 * v] && depth > 0.0) {
          glue(v, p + depth * n_support);  // on the plane, where it slid to
          ++glued;
        }
      }
      if (glued == 0) return total;
    }
    total.converged = false;  // still gluing after the last round: the patch did not settle
    return total;
  };
  auto record = [&](const Eigen::VectorXd& x, const fem::FemSolveReport& r) {
    Eigen::Matrix3Xd f(3, static_cast<Eigen::Index>(beads.size()));
    for (size_t i = 0; i < beads.size(); ++i)
      f.col(static_cast<Eigen::Index>(i)) = fem::embedded_position(fem.mesh(), x, beads[i]);
    ref.fiducials_m.push_back(f);
    ref.solves.push_back(r);
  };
  Eigen::VectorXd x = fem.rest_positions();
  opt.bodies = {probe_body(s, stage_pose(s, 0.0))};
  record(x, solve_sticking(&x));
  // each stage reached in moves of at most 1 mm (the penalty contact starts shallow each time)
  double depth = 0.0;
  for (double target : s.stage_depths_m) {
    fem::FemSolveReport r;
    const int moves = std::max(1, static_cast<int>(std::ceil(std::abs(target - depth) / 1e-3)));
    for (int m = 1; m <= moves; ++m) {
      opt.bodies = {probe_body(s, stage_pose(s, depth + (target - depth) * m / moves))};
      const fem::FemSolveReport step = solve_sticking(&x);
      r.newton_iterations += step.newton_iterations;
      r.residual_n = step.residual_n;
      r.converged = step.converged;
    }
    depth = target;
    record(x, r);
  }
  ref.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return ref;
}

void compare_fields(const Eigen::Matrix3Xd& model_m, const Eigen::Matrix3Xd& reference_m,
                    const Eigen::Matrix3Xd& model_rest_m, const Eigen::Matrix3Xd& reference_rest_m,
                    const Eigen::Matrix3Xd& unloaded_m, StageError* e) {
  const Eigen::Index n = reference_m.cols();
  if (n == 0 || model_m.cols() != n || model_rest_m.cols() != n || reference_rest_m.cols() != n ||
      unloaded_m.cols() != n)
    throw std::invalid_argument("calibration: the fields to compare have different fiducials");
  const Eigen::Matrix3Xd error = model_m - reference_m;
  e->mean_error_m = error.rowwise().mean();
  e->shape_error_m = (error.colwise() - e->mean_error_m).colwise().norm().mean();
  const Eigen::Matrix3Xd d_model = model_m - model_rest_m, d_ref = reference_m - reference_rest_m;
  const double ref_sq = d_ref.squaredNorm();
  e->response_ratio = ref_sq > 0.0 ? (d_model.array() * d_ref.array()).sum() / ref_sq : 0.0;
  e->reference_from_unloaded_m = (reference_m - unloaded_m).colwise().norm().mean();
  e->model_from_unloaded_m = (model_m - unloaded_m).colwise().norm().mean();
}

PbdRun run_pbd_protocol(const CalibrationSetup& s, const SoftTissueSpec& spec_in, const FemReference& ref) {
  if (ref.fiducials_m.size() != s.stage_depths_m.size() + 1)
    throw std::invalid_argument("calibration: the reference does not have one result per stage");
  SoftTissueSpec spec = spec_in;
  spec.settle_s = s.warmup_steps * s.step_s;  // the warm-up
  spec.params.gravity_m_per_s2 = s.gravity_m_per_s2;
  spec.params.support_mu_static = spec.params.support_mu_kinetic = kTissueFriction.max;  // sticking
  spec.params.probe_mu_static = spec.params.probe_mu_kinetic = 0.0;                      // frictionless
  TissueScene tissue(s.organ, spec, s.probe, s.step_s);

  PbdRun run;
  Eigen::Matrix3Xd unloaded(3, static_cast<Eigen::Index>(s.organ.fiducials_m.size()));
  for (Eigen::Index i = 0; i < unloaded.cols(); ++i) unloaded.col(i) = s.organ.fiducials_m[static_cast<size_t>(i)];
  run.fiducials_m.reserve(s.stage_depths_m.size() + 1);
  auto compare = [&](size_t stage, double depth) {
    const Eigen::Matrix3Xd& truth = ref.fiducials_m[stage];
    const Eigen::VectorXd err = (tissue.fiducials_m() - truth).colwise().norm();
    StageError e;
    e.depth_m = depth;
    e.mean_m = err.mean();
    e.std_m = std::sqrt((err.array() - e.mean_m).square().mean());
    e.max_m = err.maxCoeff();
    e.mean_displacement_m = (truth - ref.fiducials_m[0]).colwise().norm().mean();
    run.fiducials_m.push_back(tissue.fiducials_m());
    compare_fields(run.fiducials_m.back(), truth, run.fiducials_m.front(), ref.fiducials_m[0], unloaded, &e);
    run.stages.push_back(e);
  };
  compare(0, 0.0);
  double depth = 0.0;
  run.step_ms.reserve(s.stage_depths_m.size() * static_cast<size_t>(s.steps_per_stage));
  for (size_t k = 0; k < s.stage_depths_m.size(); ++k) {
    const double from = depth, to = s.stage_depths_m[k];
    for (int i = 1; i <= s.steps_per_stage; ++i) {
      const ProbePose pose = stage_pose(s, from + (to - from) * i / s.steps_per_stage);
      const auto a = Clock::now();
      tissue.step(&pose);
      run.step_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - a).count());
    }
    depth = to;
    compare(k + 1, depth);
  }
  double sum = 0.0;
  for (size_t k = 1; k < run.stages.size(); ++k) sum += run.stages[k].mean_m;
  run.mean_over_stages_m = run.stages.size() > 1 ? sum / static_cast<double>(run.stages.size() - 1) : 0.0;
  return run;
}

namespace {
constexpr const char* kReferenceMagic = "pcisim-fem-reference 2";

void put_numbers(std::ostream& out, const char* key, const std::vector<double>& values) {
  char v[32];
  out << key;
  for (double x : values) {
    std::snprintf(v, sizeof v, " %.17g", x);
    out << v;
  }
  out << "\n";
}

void put_points(std::ostream& out, const Eigen::Matrix3Xd& p) {
  for (Eigen::Index i = 0; i < p.cols(); ++i) put_numbers(out, "", {p(0, i), p(1, i), p(2, i)});
}

// what the probe, the support and the material are, as the numbers the text keeps
std::vector<double> probe_numbers(const CalibrationSetup& s) {
  const Eigen::Quaterniond q = s.probe.start_rotation.normalized();
  return {s.probe.face_width_m,
          s.probe.face_thickness_m,
          s.probe.height_m,
          s.probe.start_position_m.x(),
          s.probe.start_position_m.y(),
          s.probe.start_position_m.z(),
          q.w(),
          q.x(),
          q.y(),
          q.z()};
}
std::vector<double> support_numbers(const CalibrationSetup& s) {
  return {s.organ.support_normal.x(), s.organ.support_normal.y(), s.organ.support_normal.z(), s.organ.support_offset_m};
}
}  // namespace

std::string fem_reference_text(const CalibrationSetup& s, const FemReference& ref,
                               const std::string& mesh_description) {
  const auto n = static_cast<Eigen::Index>(s.organ.fiducials_m.size());
  if (ref.fiducials_m.size() != s.stage_depths_m.size() + 1 || ref.solves.size() != ref.fiducials_m.size())
    throw std::invalid_argument("fem reference: not one result per stage (and rest)");
  for (const Eigen::Matrix3Xd& f : ref.fiducials_m)
    if (f.cols() != n) throw std::invalid_argument("fem reference: a stage without one position per fiducial");
  if (mesh_description.find('\n') != std::string::npos)
    throw std::invalid_argument("fem reference: the mesh description must be one line");
  std::ostringstream out;
  out << kReferenceMagic << "\nmesh " << mesh_description << "\n";
  put_numbers(out, "material", {s.young_pa, s.poisson, s.density_kg_per_m3});
  put_numbers(out, "gravity", {s.gravity_m_per_s2.x(), s.gravity_m_per_s2.y(), s.gravity_m_per_s2.z()});
  put_numbers(out, "probe", probe_numbers(s));
  put_numbers(out, "support", support_numbers(s));
  out << "solve " << ref.nodes << " " << ref.tets << " " << ref.seconds << "\n";
  out << "stages " << s.stage_depths_m.size();
  put_numbers(out, "", s.stage_depths_m);
  out << "converged";
  for (const auto& r : ref.solves) out << " " << (r.converged ? 1 : 0);
  out << "\nfiducials " << n << "\nunloaded\n";
  Eigen::Matrix3Xd unloaded(3, n);
  for (Eigen::Index i = 0; i < n; ++i) unloaded.col(i) = s.organ.fiducials_m[static_cast<size_t>(i)];
  put_points(out, unloaded);
  for (size_t k = 0; k < ref.fiducials_m.size(); ++k) {
    out << "stage " << k << "\n";
    put_points(out, ref.fiducials_m[k]);
  }
  return out.str();
}

FemReference parse_fem_reference(const std::string& text, const CalibrationSetup& s, const std::string& source,
                                 std::string* mesh_description) {
  std::istringstream in(text);
  auto fail = [&](const std::string& what) { return std::runtime_error("fem reference " + source + ": " + what); };
  auto differs = [&](const std::string& what) {
    return std::invalid_argument("fem reference " + source + ": " + what + " is not the setup's");
  };
  std::string line, word;
  if (!std::getline(in, line) || line != kReferenceMagic)
    throw fail("not a pcisim FEM reference of this version (first line: " + line.substr(0, 40) + ")");
  if (!std::getline(in, line) || line.rfind("mesh ", 0) != 0) throw fail("no mesh line");
  if (mesh_description) *mesh_description = line.substr(5);
  auto numbers = [&](const char* key, size_t count) {
    std::vector<double> v(count);
    if (!(in >> word) || word != key) throw fail(std::string("expected '") + key + "'");
    for (double& x : v)
      if (!(in >> x) || !std::isfinite(x)) throw fail(std::string("bad '") + key + "' line");
    return v;
  };
  auto same = [](const std::vector<double>& a, const std::vector<double>& b) {
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i)
      if (std::abs(a[i] - b[i]) > 1e-12 * std::max(1.0, std::abs(b[i]))) return false;
    return true;
  };
  if (!same(numbers("material", 3), {s.young_pa, s.poisson, s.density_kg_per_m3}))
    throw differs("its material (E, nu, density)");
  if (!same(numbers("gravity", 3), {s.gravity_m_per_s2.x(), s.gravity_m_per_s2.y(), s.gravity_m_per_s2.z()}))
    throw differs("its gravity");
  if (!same(numbers("probe", 10), probe_numbers(s))) throw differs("its probe (size, start pose)");
  if (!same(numbers("support", 4), support_numbers(s))) throw differs("its support plane");
  FemReference ref;
  if (!(in >> word >> ref.nodes >> ref.tets >> ref.seconds) || word != "solve") throw fail("bad 'solve' line");
  size_t stages = 0;
  if (!(in >> word >> stages) || word != "stages" || stages > 1000) throw fail("bad 'stages' line");
  std::vector<double> depths(stages);
  for (double& d : depths)
    if (!(in >> d)) throw fail("bad stage depth");
  if (!same(depths, s.stage_depths_m)) throw differs("its stages (" + std::to_string(stages) + ")");
  if (!(in >> word) || word != "converged") throw fail("expected 'converged'");
  ref.solves.assign(stages + 1, fem::FemSolveReport{});
  for (auto& r : ref.solves) {
    int c = 0;
    if (!(in >> c) || (c != 0 && c != 1)) throw fail("bad 'converged' line");
    r.converged = c == 1;
  }
  Eigen::Index n = 0;
  if (!(in >> word >> n) || word != "fiducials" || n != static_cast<Eigen::Index>(s.organ.fiducials_m.size()))
    throw differs("its fiducial count");
  auto points = [&]() {
    Eigen::Matrix3Xd p(3, n);
    for (Eigen::Index i = 0; i < n; ++i)
      if (!(in >> p(0, i) >> p(1, i) >> p(2, i)) || !p.col(i).allFinite()) throw fail("bad fiducial position");
    return p;
  };
  if (!(in >> word) || word != "unloaded") throw fail("expected 'unloaded'");
  const Eigen::Matrix3Xd unloaded = points();
  for (Eigen::Index i = 0; i < n; ++i)
    if ((unloaded.col(i) - s.organ.fiducials_m[static_cast<size_t>(i)]).norm() > 1e-9)
      throw differs("fiducial " + std::to_string(i) + " (another organ or seed?)");
  for (size_t k = 0; k <= stages; ++k) {
    size_t number = 0;
    if (!(in >> word >> number) || word != "stage" || number != k)
      throw fail("expected 'stage " + std::to_string(k) + "'");
    ref.fiducials_m.push_back(points());
  }
  if (in >> word) throw fail("text after the last stage");
  return ref;
}

}  // namespace pcisim::physics::soft_tissue
