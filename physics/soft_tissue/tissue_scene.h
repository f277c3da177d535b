#pragma once
// The soft-tissue scene's physics (issue #16): the case's organ built into its particle model,
// stepped on its support with the probe the user moves, and what the step hands on: the skinned
// tet mesh and fiducials (for ultrasound and calibration) and the probe's force as a local force
// model for the 1 kHz haptic loop. Built once (allocates, settles); step() allocates nothing.
#include <Eigen/Core>
#include <optional>

#include "anatomy/organ/organ.h"
#include "physics/local_force_model.h"
#include "physics/soft_tissue/soft_tissue_spec.h"
#include "physics/soft_tissue/tissue_body.h"
#include "physics/soft_tissue/tissue_model.h"

namespace pcisim::physics::soft_tissue {

// the transducer of `p` as a convex body: the face at probe z = 0 (normal +z), the block behind it
ConvexProbe transducer(const ProbeContactParams& p, const ProbePose& pose);

// the haptic model along the probe's beam axis: x = beam . face centre (m, deeper is larger),
// f0 = the tissue's push back along -beam (>= 0), K the secant of force over depth between the
// last two steps (clamped to [0, k_max]; kept while the depth barely changes), B the scene's
class ProbeForceModel {
 public:
  explicit ProbeForceModel(const ProbeContactParams& p) : params_(p) {}
  LocalForceModel update(const Eigen::Vector3d& position_m, const Eigen::Vector3d& beam, const Eigen::Vector3d& force_n,
                         double time_s, double step_s);

 private:
  ProbeContactParams params_;
  bool has_previous_ = false;
  double previous_depth_m_ = 0.0, previous_force_n_ = 0.0, stiffness_n_per_m_ = 0.0;
};

class TissueScene {
 public:
  // throws std::invalid_argument naming the field (validate, build_tissue_model's radius check)
  TissueScene(const anatomy::Organ& organ, const SoftTissueSpec& spec, const std::optional<ProbeContactParams>& probe,
              double step_s);

  // the probe's pose for this step (ignored when not finite: the last stays), then one step
  void step(const ProbePose* probe_pose);

  const TissueModel& model() const { return model_; }
  const TissueBody& body() const { return body_; }
  TissueBody& body() { return body_; }  // its particles may be edited between steps (tests, tools)
  bool has_probe() const { return probe_.has_value(); }
  const ProbePose& probe_pose() const { return pose_; }
  const Eigen::Matrix3Xd& tet_vertices_m() const { return tet_now_m_; }  // skinned, after the last step
  const Eigen::Matrix3Xd& fiducials_m() const { return fiducials_now_m_; }
  Eigen::Vector3d probe_force_n() const;  // zero without probe_contact
  const LocalForceModel& force_model() const { return force_model_; }
  double time_s() const { return time_s_; }

 private:
  void skin();

  std::optional<ProbeContactParams> probe_;
  double step_s_;
  TissueModel model_;
  TissueBody body_;
  ClusterFrames frames_;
  Eigen::Matrix3Xd tet_now_m_, fiducials_now_m_;
  ProbePose pose_;
  std::optional<ProbeForceModel> feedback_;
  LocalForceModel force_model_;
  double time_s_ = 0.0;
};

}  // namespace pcisim::physics::soft_tissue
