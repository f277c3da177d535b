#include "physics/world.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

#include "physics/blood/blood_chain_mail.h"
#include "physics/guidewire/catheter_path.h"
#include "physics/guidewire/chain_mail_wire.h"
#include "physics/guidewire/coulomb_friction.h"
#include "physics/guidewire/input_guard.h"
#include "physics/guidewire/link_spec.h"
#include "physics/guidewire/rod_wire.h"
#include "physics/guidewire/sdf_lumen.h"
#include "physics/guidewire/wall_contact.h"
#include "physics/guidewire/wire_feedback.h"
#include "physics/heart/beating_heart.h"
#include "physics/heart/heart_fit.h"
#include "anatomy/heart/heart_mesh.h"
#include "physics/motion/vessel_skin.h"
#include "physics/param_checks.h"
#include "physics/pbd/pbd_cuda_solver.h"
#include "physics/soft_tissue/tissue_scene.h"
#include "anatomy/phantom/coronary_phantom.h"
#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::physics {
namespace {

// the heart's particles (template frame) placed in the case's frame by its pose; `out` keeps its
// size, so a step allocates nothing
void place_heart(const anatomy::HeartPose& pose, const Eigen::Matrix3Xd& template_m, Eigen::Matrix3Xd* out) {
  out->noalias() = (pose.scale * pose.rotation) * template_m;
  out->colwise() += pose.translation_m;
}

using Clock = std::chrono::steady_clock;

void validate(const WorldSpec& s) {
  require(in(s.step_s, 1e-5, 1.0), "step_s: expected [1e-5, 1] s");
  require(!s.vessel_contact || s.guidewire, "vessel_contact: needs guidewire");
  require(!s.friction || s.vessel_contact, "friction: needs vessel_contact");
  require(!s.blood_flow || s.guidewire, "blood_flow: needs guidewire");
  require(!s.vessel_motion || s.heart_beat, "vessel_motion: needs heart_beat");
  if (s.guidewire) validate(*s.guidewire);
  if (const auto& c = s.vessel_contact) {
    // finer than 0.05 mm the field of the whole tree outgrows memory (0.1 mm: ~140 MB)
    require(kContactSdfSpacingM.contains(c->sdf_spacing_m),
            "vessel_contact.sdf_spacing_m: expected " + kContactSdfSpacingM.describe());
    require(kContactWallMarginM.contains(c->wall_margin_m),
            "vessel_contact.wall_margin_m: expected " + kContactWallMarginM.describe());
    require(kContactWallStiffnessNPerM.contains(c->wall_stiffness_n_per_m),
            "vessel_contact.wall_stiffness_n_per_m: expected " + kContactWallStiffnessNPerM.describe());
  }
  if (const auto& f = s.friction) {
    require(kFrictionCoefficient.contains(f->body_static),
            "friction.body_static: expected " + kFrictionCoefficient.describe());
    require(in(f->body_kinetic, 0.0, f->body_static), "friction.body_kinetic: expected [0, body_static]");
    require(kFrictionCoefficient.contains(f->tip_static),
            "friction.tip_static: expected " + kFrictionCoefficient.describe());
    require(in(f->tip_kinetic, 0.0, f->tip_static), "friction.tip_kinetic: expected [0, tip_static]");
  }
  if (s.blood_flow) validate(*s.blood_flow);
  if (const auto& h = s.heart_beat) {
    std::string why;
    require(h->solver != pbd::SolverKind::kJacobiCuda || pbd::pbd_cuda_available(&why),
            "heart_beat.solver: jacobi_cuda needs a CUDA build and a GPU (" + why + ")");
  }
  if (s.vessel_motion) validate(*s.vessel_motion);
  require(!s.probe_contact || s.soft_tissue, "probe_contact: needs soft_tissue");
  // the organ scene's anatomy is an organ on a support, not a coronary tree in a heart
  require(!s.soft_tissue || (!s.guidewire && !s.heart_beat),
          "soft_tissue: goes with probe_contact and ultrasound only (not guidewire or heart_beat)");
  if (s.soft_tissue) soft_tissue::validate(*s.soft_tissue);
  if (s.soft_tissue && s.soft_tissue->params.solver == pbd::SolverKind::kJacobiCuda) {
    std::string why;
    require(pbd::pbd_cuda_available(&why), "soft_tissue.device: cuda needs a CUDA build and a GPU (" + why + ")");
  }
  if (s.probe_contact) soft_tissue::validate(*s.probe_contact);
}

}  // namespace

struct World::Impl {
  WorldSpec spec;
  anatomy::VesselTree tree;
  std::shared_ptr<const LumenQuery> lumen;
  std::optional<ChainMailWire> wire;
  std::optional<RodWire> rod;
  std::optional<WallContact> contact;
  std::optional<CoulombFriction> friction;
  std::optional<BloodChainMail> blood;
  std::optional<BeatingHeart> heart;
  anatomy::HeartMesh heart_mesh;  // the one the heart was built on (vessel_motion): sample_beat_cycle's copy
  HeartFitReport heart_fit;
  std::optional<VesselSkin> skin;
  std::optional<soft_tissue::TissueScene> tissue;
  anatomy::HeartPose heart_pose;     // template frame -> the case's
  Eigen::Matrix3Xd heart_in_case_m;  // the heart's particles in the case's frame (skin input)
  InputGuard guard;
  InstrumentInput used;
  std::vector<EffectCost> costs;
  int cost_wire = -1, cost_blood = -1, cost_contact = -1, cost_friction = -1, cost_heart = -1, cost_motion = -1,
      cost_tissue = -1;
  LocalForceModel model;
  double time_s = 0.0;
  int64_t step = 0;
  int tip_branch = -1;
  // guidewire.beat_coupling kContact: the rod lives in the world, the skin's last update is how
  // its lumen moves
  bool rod_in_world = false;
  struct SkinMotion final : LumenMotion {
    const VesselSkin* skin = nullptr;
    Eigen::Vector3d displacement_m(const Eigen::Vector3d& rest_p_m, double a) const override {
      return skin->displacement_m(rest_p_m, a);
    }
    bool carries(const Eigen::Vector3d& rest_p_m) const override { return skin->carries(rest_p_m); }
  } skin_motion;

  // the rod's nodes between the world and the rest frame (blood drift is described at rest)
  void rod_to_rest(double sign) {
    const auto x = rod->mutable_nodes_m();
    const auto off = rod->wall_offset_m();
    for (size_t i = 0; i < x.size(); ++i) x[i] -= sign * off[i];
  }

  static double ms(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
  }
};

World::World(const WorldSpec& spec) : World(spec, nullptr) {}

World::World(const WorldSpec& spec, std::shared_ptr<const LumenQuery> contact_geometry)
    : World(spec, anatomy::make_coronary_phantom(anatomy::CoronaryPhantomSpec{spec.anatomy.seed}),
            std::move(contact_geometry)) {}

World::World(const WorldSpec& spec, const anatomy::VesselTree& tree, std::shared_ptr<const LumenQuery> contact_geometry,
             const anatomy::HeartPose& heart_pose, const Eigen::Matrix3Xd& heart_rest_m, const anatomy::Organ* organ)
    : impl_(std::make_unique<Impl>()) {
  validate(spec);
  Impl& w = *impl_;
  w.spec = spec;
  w.heart_pose = heart_pose;
  // effects in step order; only the listed ones exist (and get a cost slot, -1 otherwise)
  auto cost_slot = [&w](bool listed, const char* name) {
    if (!listed) return -1;
    w.costs.push_back({name, 0.0});
    return static_cast<int>(w.costs.size()) - 1;
  };
  w.cost_heart = cost_slot(spec.heart_beat.has_value(), "heart_beat");
  w.cost_motion = cost_slot(spec.vessel_motion.has_value(), "vessel_motion");
  w.cost_wire = cost_slot(spec.guidewire.has_value(), "guidewire");
  w.cost_blood = cost_slot(spec.blood_flow.has_value(), "blood_flow");
  w.cost_contact = cost_slot(spec.vessel_contact.has_value(), "vessel_contact");
  w.cost_friction = cost_slot(spec.friction.has_value(), "friction");
  // the probe's contacts run inside the tissue's substeps: their time is soft_tissue's
  w.cost_tissue = cost_slot(spec.soft_tissue.has_value(), "soft_tissue");
  if (spec.soft_tissue) {
    require(organ != nullptr, "soft_tissue: the scene's anatomy has no organ (anatomy.organ: \"kidney\")");
    w.tissue.emplace(*organ, *spec.soft_tissue, spec.probe_contact, spec.step_s);
    w.model = w.tissue->force_model();
    return;
  }
  if (spec.heart_beat && !spec.vessel_motion) w.heart.emplace(*spec.heart_beat);
  if (!spec.guidewire && !spec.vessel_motion) return;  // nothing else needs the anatomy

  w.tree = tree;
  if (spec.vessel_motion) {
    // a heart the tree rides must not swallow it: the template is fitted under this tree
    // (the heart is simulated in the template's frame: the case's heart pose places it under the
    // tree, so the fit sees the tree in the template's frame and the skin the heart in the case's)
    anatomy::HeartMesh mesh = anatomy::template_heart_mesh();
    if (heart_rest_m.cols() > 0) {
      // the case's heart, fitted to the patient's CT (modeling/heart/heart_elastic_fit.h): its
      // epicardium is where the CT shows it, under the vessels the same CT shows, so it is not
      // dented (the dent measures against the designed template)
      require(heart_rest_m.cols() == mesh.vertices_m.cols() && heart_rest_m.allFinite(),
              "anatomy: the case's fitted heart has " + std::to_string(heart_rest_m.cols()) +
                  " vertices, the template heart " + std::to_string(mesh.vertices_m.cols()));
      mesh.vertices_m = heart_rest_m;
    } else {
      anatomy::VesselTree tree_in_template = w.tree;
      for (auto& b : tree_in_template.branches) {
        for (auto& p : b.points) {
          p.position_m = heart_pose.to_template(p.position_m);
          p.radius_m /= heart_pose.scale;
        }
      }
      w.heart_fit = fit_heart_under_tree(tree_in_template, HeartFitParams{}, &mesh);
    }
    w.heart.emplace(*spec.heart_beat, mesh);
    w.heart_mesh = std::move(mesh);
    // the tree rides the epicardium; the wire, its contact and the blood are simulated in the
    // vessels' rest frame and carried into the world by the same skin (docs/heart.md)
    w.heart_in_case_m.resize(3, w.heart->rest_positions_m().cols());
    place_heart(heart_pose, w.heart->rest_positions_m(), &w.heart_in_case_m);
    w.skin.emplace(w.tree, w.heart_in_case_m, w.heart->epicardium(), *spec.vessel_motion);
  }
  if (!spec.guidewire) return;
  auto path = anatomy::guide_catheter_path(w.tree);
  require(path.size() >= 2, "anatomy: the vessel tree has no guide catheter path (branches named aorta and LM needed)");
  const bool rod = spec.guidewire->model == GuidewireModel::kRod;
  if (!rod) w.wire.emplace(*spec.guidewire, CatheterPath(path));
  if (spec.vessel_contact) {
    // eq 15 against the SDF of the lofted lumen at the scene's spacing
    if (contact_geometry) {
      w.lumen = std::move(contact_geometry);
    } else {
      try {
        w.lumen = std::make_shared<SdfLumen>(w.tree, spec.vessel_contact->sdf_spacing_m);
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(std::string("vessel_contact.sdf_spacing_m: the lumen's field cannot be built (") +
                                    e.what() + ")");
      }
    }
    if (!rod) w.contact.emplace(*spec.vessel_contact, *w.lumen, w.wire->node_count());
  }
  if (rod) {
    // the rod touches the wall and feels friction inside its own substeps
    w.rod.emplace(*spec.guidewire, CatheterPath(std::move(path)), w.lumen.get(), spec.vessel_contact, spec.friction);
    // the wall is what carries a rod living in the world: without vessel_contact it rides the
    // vessels kinematically whatever beat_coupling says (docs/guidewire.md)
    w.rod_in_world = w.skin && spec.vessel_contact && spec.guidewire->beat_coupling == BeatCoupling::kContact;
    if (w.rod_in_world) {
      w.skin_motion.skin = &*w.skin;
      w.rod->set_lumen_motion(&w.skin_motion);
    }
  } else if (spec.friction) {
    w.friction.emplace(*spec.friction, w.wire->node_count());
  }
  if (spec.blood_flow) {
    BloodFlowParams blood = *spec.blood_flow;
    if (!spec.heart_beat) blood.pulsatility = 0.0;  // no cycle to follow: steady flow
    w.blood.emplace(blood, w.tree);
  }
}

World::~World() = default;

BeatCycle World::sample_beat_cycle(int bins) const {
  if (bins < 2) throw std::invalid_argument("sample_beat_cycle: bins must be at least 2, got " + std::to_string(bins));
  const Impl& w = *impl_;
  BeatCycle out;
  if (!w.spec.heart_beat || !w.spec.vessel_motion || !w.skin) return out;
  // a private copy: the live heart and skin keep their state
  BeatingHeart heart(*w.spec.heart_beat, w.heart_mesh);
  Eigen::Matrix3Xd heart_in_case(3, heart.rest_positions_m().cols());
  place_heart(w.heart_pose, heart.rest_positions_m(), &heart_in_case);
  VesselSkin skin(w.tree, heart_in_case, heart.epicardium(), *w.spec.vessel_motion);
  const Eigen::Index nh = heart_in_case.cols();
  const Eigen::Index nv = skin.point_count();
  auto gather = [&](const Eigen::Matrix3Xd& heart_m, std::span<const Eigen::Vector3d> vessels_m) {
    Eigen::Matrix3Xd all(3, nh + nv);
    all.leftCols(nh) = heart_m;
    for (Eigen::Index i = 0; i < nv; ++i) all.col(nh + i) = vessels_m[i];
    return all;
  };
  out.heart_points = static_cast<int>(nh);
  out.rest_m = gather(heart_in_case, skin.rest_points_m());

  const double dt = w.spec.step_s;
  auto advance = [&] {
    const double before = heart.phase();
    heart.step(dt);
    place_heart(w.heart_pose, heart.positions_m(), &heart_in_case);
    skin.update(heart_in_case);
    double d = heart.phase() - before;
    if (d <= 0.0) d += 1.0;  // wrapped
    return d;
  };
  // settling: the first cycle from rest, up to the first step after the wrap
  while (true) {
    const double before = heart.phase();
    advance();
    if (heart.phase() <= before) break;
  }
  // sampled: unwrapped phases from that step until a whole cycle past it is covered
  std::vector<double> u{heart.phase()};
  std::vector<Eigen::Matrix3Xd> x{gather(heart_in_case, skin.points_m())};
  while (u.back() < u.front() + 1.0) {
    u.push_back(u.back() + advance());
    x.push_back(gather(heart_in_case, skin.points_m()));
  }
  out.at_bin_m.reserve(bins);
  for (int b = 0; b < bins; ++b) {
    const double phase = static_cast<double>(b) / bins;
    // phases before the first sampled step are reached at the end of the cycle (across the wrap)
    const double t = phase >= u.front() ? phase : phase + 1.0;
    const auto hi = std::clamp<size_t>(std::upper_bound(u.begin(), u.end(), t) - u.begin(), 1, u.size() - 1);
    const size_t lo = hi - 1;
    const double a = std::clamp((t - u[lo]) / (u[hi] - u[lo]), 0.0, 1.0);
    out.at_bin_m.push_back((1.0 - a) * x[lo] + a * x[hi]);
  }
  return out;
}

void World::step(const InstrumentInput& input) {
  Impl& w = *impl_;
  w.used = w.guard.accept(input);
  if (w.tissue) {
    const auto a = Clock::now();
    const auto& q = w.used.probe_orientation_wxyz;
    const soft_tissue::ProbePose pose{
        Eigen::Vector3d(w.used.probe_position_m[0], w.used.probe_position_m[1], w.used.probe_position_m[2]),
        Eigen::Quaterniond(q[0], q[1], q[2], q[3])};
    w.tissue->step(w.used.probe_present ? &pose : nullptr);
    w.model = w.tissue->force_model();
    w.costs[w.cost_tissue].last_step_ms = Impl::ms(a, Clock::now());
  }
  if (w.heart) {
    const auto a = Clock::now();
    w.heart->step(w.spec.step_s);
    const auto b = Clock::now();
    w.costs[w.cost_heart].last_step_ms = Impl::ms(a, b);
    if (w.skin) {
      place_heart(w.heart_pose, w.heart->positions_m(), &w.heart_in_case_m);
      w.skin->update(w.heart_in_case_m);
      w.costs[w.cost_motion].last_step_ms = Impl::ms(b, Clock::now());
    }
  }
  if (w.rod) {
    const auto t0 = Clock::now();
    double c_blood = 0.0;
    if (w.blood) {
      w.blood->step(w.spec.step_s, w.heart ? w.heart->phase() : 0.0);
      if (w.rod_in_world) w.rod_to_rest(1.0);
      w.blood->apply(w.rod->mutable_nodes_m(), w.rod->first_free_node(), w.spec.step_s);
      if (w.rod_in_world) w.rod_to_rest(-1.0);
      c_blood = Impl::ms(t0, Clock::now());
    }
    const auto t1 = Clock::now();
    w.rod->step(w.used.insertion_m, w.used.rotation_rad, w.spec.step_s);
    w.tip_branch = anatomy::nearest_branch(w.tree, w.rod->nodes_m().back() - w.rod->wall_offset_m().back());
    w.model =
        to_local_force_model(w.rod->feedback(), w.used, *w.spec.guidewire, w.time_s + w.spec.step_s, w.spec.step_s);
    // contact and friction run inside the rod's substeps: their time is the guidewire's
    w.costs[w.cost_wire].last_step_ms = Impl::ms(t1, Clock::now());
    if (w.cost_blood >= 0) w.costs[w.cost_blood].last_step_ms = c_blood;
  }
  if (w.wire) {
    ChainMailWire& wire = *w.wire;
    auto t0 = Clock::now();
    wire.begin_step(w.used.insertion_m, w.used.rotation_rad);
    if (w.contact) w.contact->begin_step();
    if (w.friction) w.friction->begin_step(wire);
    auto t1 = Clock::now();
    double c_wire = Impl::ms(t0, t1), c_blood = 0.0, c_contact = 0.0, c_friction = 0.0;
    if (w.blood) {
      w.blood->step(w.spec.step_s, w.heart ? w.heart->phase() : 0.0);
      w.blood->apply(wire, w.spec.step_s);
      const auto t2 = Clock::now();
      c_blood = Impl::ms(t1, t2);
      t1 = t2;
    }
    // each pass: optimisation, contact, friction; then the chain-mail limits hold again
    const int passes = w.spec.guidewire->optimisation_passes;
    for (int k = 0; k < passes; ++k) {
      auto a = Clock::now();
      wire.optimise_pass(k);
      auto b = Clock::now();
      c_wire += Impl::ms(a, b);
      if (w.contact) {
        w.contact->project(wire);
        a = b;
        b = Clock::now();
        c_contact += Impl::ms(a, b);
      }
      if (w.friction) {
        w.friction->apply(wire, *w.contact);
        a = b;
        b = Clock::now();
        c_friction += Impl::ms(a, b);
      }
    }
    {
      // the last sweep keeps nodes inside the wall margin where the limits allow (eq 15)
      const auto a = Clock::now();
      if (w.contact) {
        wire.restore_limits(w.lumen.get(), w.spec.vessel_contact->wall_margin_m);
      } else {
        wire.restore_limits();
      }
      c_wire += Impl::ms(a, Clock::now());
    }
    const auto t3 = Clock::now();
    wire.end_step();
    const auto nodes = wire.nodes_m();
    w.tip_branch = anatomy::nearest_branch(w.tree, nodes.back());
    const WireFeedback f = compute_feedback(wire, *w.spec.guidewire, w.contact ? &*w.contact : nullptr,
                                            w.friction ? &*w.friction : nullptr);
    w.model = to_local_force_model(f, w.used, *w.spec.guidewire, w.time_s + w.spec.step_s, w.spec.step_s);
    c_wire += Impl::ms(t3, Clock::now());
    w.costs[w.cost_wire].last_step_ms = c_wire;
    if (w.cost_blood >= 0) w.costs[w.cost_blood].last_step_ms = c_blood;
    if (w.cost_contact >= 0) w.costs[w.cost_contact].last_step_ms = c_contact;
    if (w.cost_friction >= 0) w.costs[w.cost_friction].last_step_ms = c_friction;
  }
  w.time_s += w.spec.step_s;
  ++w.step;
}

void World::write_snapshot(WorldSnapshot& out) const {
  const Impl& w = *impl_;
  out.time_s = w.time_s;
  out.step = w.step;
  out.insertion_m = w.used.insertion_m;
  out.rotation_rad = w.used.rotation_rad;
  out.heart_phase = w.heart ? w.heart->phase() : 0.0;
  out.tip_branch = w.tip_branch;
  write_tissue(out);
  if (w.skin) {
    const auto pts = w.skin->points_m();
    out.vessel_points_m.assign(pts.begin(), pts.end());
  } else {
    out.vessel_points_m.clear();
  }
  if (w.rod) {
    const auto nodes = w.rod->nodes_m();
    out.wire_nodes_m.assign(nodes.begin(), nodes.end());
    // in the world already when the wall moves it; else carried there from the rest frame
    if (w.skin && !w.rod_in_world)
      for (auto& p : out.wire_nodes_m) p = w.skin->to_world(p);
    const auto t = w.rod->touched();
    out.wire_contact.assign(t.begin(), t.end());
    const auto f = w.rod->wall_force_vector_n();
    out.wire_contact_force_n.assign(f.begin(), f.end());
    // carried from the rest frame too, each force turned with the skin at its node
    if (w.skin && !w.rod_in_world)
      for (size_t i = 0; i < out.wire_contact_force_n.size(); ++i)
        out.wire_contact_force_n[i] = w.skin->turn_to_world(nodes[i], out.wire_contact_force_n[i]);
    out.tip_force_n = w.rod->tip_contact_force_n();
    out.hub_force_n = w.rod->hub_axial_force_n();
    out.hub_torque_nm = w.rod->hub_torque_nm();
    out.tip_m = out.wire_nodes_m.back();
    out.tip_rest_m = w.rod_in_world ? Eigen::Vector3d(nodes.back() - w.rod->wall_offset_m().back()) : nodes.back();
    return;
  }
  out.tip_force_n = 0.0;
  if (!w.wire) {
    out.wire_nodes_m.clear();
    out.wire_contact.clear();
    out.wire_contact_force_n.clear();
    out.hub_force_n = out.hub_torque_nm = 0.0;
    out.tip_m.setZero();
    out.tip_rest_m.setZero();
    return;
  }
  const auto nodes = w.wire->nodes_m();
  out.wire_nodes_m.assign(nodes.begin(), nodes.end());
  // the wire rides its vessels: rest frame to world
  if (w.skin)
    for (auto& p : out.wire_nodes_m) p = w.skin->to_world(p);
  out.wire_contact.resize(nodes.size());
  if (w.contact) {
    const auto t = w.contact->touched();
    std::copy(t.begin(), t.end(), out.wire_contact.begin());
  } else {
    std::fill(out.wire_contact.begin(), out.wire_contact.end(), 0);
  }
  out.wire_contact_force_n.assign(nodes.size(), Eigen::Vector3d::Zero());
  out.hub_force_n = w.model.f0_n;
  out.hub_torque_nm = w.model.t0_nm;
  out.tip_m = out.wire_nodes_m.back();
  out.tip_rest_m = nodes.back();  // (the chain-mail lives in the rest frame)
}

void World::write_tissue(WorldSnapshot& out) const {
  const Impl& w = *impl_;
  out.probe_present = w.tissue && w.tissue->has_probe();
  if (!w.tissue) {
    out.tissue_tet_vertices_m.clear();
    out.fiducials_m.clear();
    return;
  }
  const Eigen::Matrix3Xd& tets = w.tissue->tet_vertices_m();
  out.tissue_tet_vertices_m.resize(tets.cols());
  for (Eigen::Index i = 0; i < tets.cols(); ++i) out.tissue_tet_vertices_m[i] = tets.col(i);
  const Eigen::Matrix3Xd& fid = w.tissue->fiducials_m();
  out.fiducials_m.resize(fid.cols());
  for (Eigen::Index i = 0; i < fid.cols(); ++i) out.fiducials_m[i] = fid.col(i);
  out.probe_position_m = w.tissue->probe_pose().position_m;
  out.probe_rotation = w.tissue->probe_pose().rotation.toRotationMatrix();
  out.probe_force_n = w.tissue->probe_force_n();
  out.probe_depth_mm = w.used.probe_depth_mm;
  out.probe_gain_db = w.used.probe_gain_db;
}

LocalForceModel World::force_model() const {
  return impl_->model;
}
std::span<const EffectCost> World::effect_costs() const {
  return impl_->costs;
}
double World::time_s() const {
  return impl_->time_s;
}
int64_t World::rejected_inputs() const {
  return impl_->guard.rejected();
}
double World::refused_feed_m() const {
  if (impl_->rod) return impl_->rod->refused_feed_m();
  return impl_->wire ? impl_->wire->commanded_feed_m() - impl_->wire->fed_length_m() : 0.0;
}

const ChainMailWire* World::guidewire_state() const {
  return impl_->wire ? &*impl_->wire : nullptr;
}
const RodWire* World::rod_state() const {
  return impl_->rod ? &*impl_->rod : nullptr;
}
const WallContact* World::contact_state() const {
  return impl_->contact ? &*impl_->contact : nullptr;
}
const CoulombFriction* World::friction_state() const {
  return impl_->friction ? &*impl_->friction : nullptr;
}
const LumenQuery* World::lumen() const {
  return impl_->lumen.get();
}
std::shared_ptr<const LumenQuery> World::shared_lumen() const {
  return impl_->lumen;
}
const anatomy::VesselTree& World::vessel_tree() const {
  return impl_->tree;
}
const HeartFitReport& World::heart_fit() const {
  return impl_->heart_fit;
}

const BeatingHeart* World::heart_state() const {
  return impl_->heart ? &*impl_->heart : nullptr;
}
const VesselSkin* World::vessel_skin() const {
  return impl_->skin ? &*impl_->skin : nullptr;
}
const soft_tissue::TissueScene* World::tissue_state() const {
  return impl_->tissue ? &*impl_->tissue : nullptr;
}

const BloodChainMail* World::blood_state() const {
  return impl_->blood ? &*impl_->blood : nullptr;
}

}  // namespace pcisim::physics
