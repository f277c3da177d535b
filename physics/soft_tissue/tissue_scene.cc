#include "physics/soft_tissue/tissue_scene.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace pcisim::physics::soft_tissue {
namespace {

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

// the scene's spec checked before anything is built; the model's own checks name the radius
const SoftTissueSpec& validated(const SoftTissueSpec& s) {
  validate(s);
  return s;
}

TissueModel build_model(const anatomy::Organ& organ, const SoftTissueSpec& spec) {
  require(!organ.surface.triangles.empty(),
          "soft_tissue: the case has no organ surface (the soft-tissue scene needs an organ: anatomy.organ)");
  return build_tissue_model(organ.surface, organ.fiducials_m, spec.model);
}

ContactPlane support_of(const anatomy::Organ& organ) {
  return {organ.support_normal, organ.support_offset_m};
}

}  // namespace

void validate(const SoftTissueSpec& s) {
  auto check = [](double v, const ParamRange& range, const std::string& field) {
    require(range.contains(v), "soft_tissue." + field + ": expected " + range.describe());
  };
  const TissueModelSpec& m = s.model;
  check(m.particle_radius_m, kTissueParticleRadiusM, "particle_radius_m");
  check(m.voxel_m, kTissueVoxelM, "voxel_m");
  require(m.voxel_m <= m.particle_radius_m, "soft_tissue.voxel_m: expected at most the particle radius");
  check(m.cluster_spacing_factor, kTissueClusterSpacingFactor, "cluster_spacing_factor");
  check(m.cluster_overlap, kTissueClusterOverlap, "cluster_overlap");
  require(m.cluster_min_members >= 1 && m.cluster_min_members <= 1000,
          "soft_tissue.cluster_min_members: expected [1, 1000]");
  check(m.tet_spacing_factor, kTissueTetSpacingFactor, "tet_spacing_factor");
  check(s.settle_s, kTissueSettleS, "settle_s");
  validate(s.params);  // "soft_tissue: <field> must be in ..."
}

void validate(const ProbeContactParams& p) {
  auto check = [](double v, const ParamRange& range, const std::string& field) {
    require(range.contains(v), "probe_contact." + field + ": expected " + range.describe());
  };
  check(p.face_width_m, kProbeFaceWidthM, "face_width_m");
  check(p.face_thickness_m, kProbeFaceThicknessM, "face_thickness_m");
  check(p.height_m, kProbeHeightM, "height_m");
  require(p.start_position_m.allFinite() && p.start_position_m.norm() <= 10.0,
          "probe_contact.start_position_m: expected finite, within 10 m");
  const double q = p.start_rotation.norm();
  require(std::isfinite(q) && std::abs(q - 1.0) <= 0.01, "probe_contact.start_rotation: expected a unit quaternion");
  check(p.max_stiffness_n_per_m, kProbeMaxStiffnessNPerM, "max_stiffness_n_per_m");
  check(p.damping_n_s_per_m, kProbeDampingNSPerM, "damping_n_s_per_m");
}

ConvexProbe transducer(const ProbeContactParams& p, const ProbePose& pose) {
  const double hx = 0.5 * p.face_width_m, hy = 0.5 * p.face_thickness_m;
  ConvexProbe probe;
  probe.faces = {{Eigen::Vector3d::UnitX(), hx},  {-Eigen::Vector3d::UnitX(), hx},
                 {Eigen::Vector3d::UnitY(), hy},  {-Eigen::Vector3d::UnitY(), hy},
                 {Eigen::Vector3d::UnitZ(), 0.0}, {-Eigen::Vector3d::UnitZ(), p.height_m}};
  probe.pose = pose;
  return probe;
}

LocalForceModel ProbeForceModel::update(const Eigen::Vector3d& position_m, const Eigen::Vector3d& beam,
                                        const Eigen::Vector3d& force_n, double time_s, double step_s) {
  const double depth_m = beam.dot(position_m);
  const double f_n = std::max(-force_n.dot(beam), 0.0);  // the tissue pushes the probe back out
  // the secant over the last step, where the depth moved enough to measure it (0.1 mm); a probe
  // out of contact feels no spring
  if (f_n == 0.0) {
    stiffness_n_per_m_ = 0.0;
  } else if (has_previous_ && std::abs(depth_m - previous_depth_m_) > 1e-4) {
    const double k = (f_n - previous_force_n_) / (depth_m - previous_depth_m_);
    stiffness_n_per_m_ = std::isfinite(k) ? std::clamp(k, 0.0, params_.max_stiffness_n_per_m) : 0.0;
  }
  has_previous_ = true;
  previous_depth_m_ = depth_m;
  previous_force_n_ = f_n;

  LocalForceModel m;
  m.made_utime = static_cast<int64_t>(std::llround(time_s * 1e6));
  m.valid_for_us = static_cast<int64_t>(std::llround(2.0 * step_s * 1e6));  // two physics periods
  m.x0_m = depth_m;
  m.f0_n = f_n;
  m.k_n_per_m = stiffness_n_per_m_;
  m.b_n_s_per_m = params_.damping_n_s_per_m;
  if (!std::isfinite(m.x0_m) || !std::isfinite(m.f0_n)) m = LocalForceModel{};  // the haptic loop fades to zero
  return m;
}

TissueScene::TissueScene(const anatomy::Organ& organ, const SoftTissueSpec& spec,
                         const std::optional<ProbeContactParams>& probe, double step_s)
    : probe_(probe),
      step_s_(step_s),
      model_(build_model(organ, validated(spec))),
      body_(model_, spec.params, support_of(organ),
            probe ? transducer(*probe, {probe->start_position_m, probe->start_rotation.normalized()}) : ConvexProbe{}),
      frames_(model_),
      tet_now_m_(3, model_.tet_vertices_m.cols()),
      fiducials_now_m_(3, static_cast<Eigen::Index>(model_.fiducial_skin.size())) {
  require(std::isfinite(step_s) && step_s > 0.0, "soft_tissue: the physics step must be positive");
  if (probe_) {
    validate(*probe_);
    pose_ = {probe_->start_position_m, probe_->start_rotation.normalized()};
    feedback_.emplace(*probe_);
  }
  // settle on the support before the first frame (the probe waits at its start pose)
  const int settle_steps = static_cast<int>(std::ceil(spec.settle_s / step_s_));
  for (int i = 0; i < settle_steps; ++i) body_.step(step_s_);
  skin();
}

void TissueScene::step(const ProbePose* probe_pose) {
  if (probe_ && probe_pose && body_.set_probe_pose(*probe_pose))
    pose_ = {probe_pose->position_m, probe_pose->rotation.normalized()};
  body_.step(step_s_);
  time_s_ += step_s_;
  skin();
  if (feedback_) {
    const Eigen::Vector3d beam = pose_.rotation * Eigen::Vector3d::UnitZ();
    force_model_ = feedback_->update(pose_.position_m, beam, body_.probe_force_n(), time_s_, step_s_);
  }
}

Eigen::Vector3d TissueScene::probe_force_n() const {
  return probe_ ? body_.probe_force_n() : Eigen::Vector3d::Zero();
}

// the tet mesh and the fiducials follow the clusters [soft-tissue, "Weighted matrix blending"]
void TissueScene::skin() {
  cluster_frames(model_, body_.positions_m(), &frames_);
  skin_points(frames_, model_.tet_skin, &tet_now_m_);
  if (!model_.fiducial_skin.empty()) skin_points(frames_, model_.fiducial_skin, &fiducials_now_m_);
}

}  // namespace pcisim::physics::soft_tissue
