#pragma once
// What the session's debrief judges against (scene key "debrief"; docs/debrief.md defines each
// figure and where its thresholds come from; ranges in scene_loader.cc).
#include <string>

namespace pcisim::server {

struct DebriefParams {
  // the branch the scene sends the trainee to ("" none): the tip anywhere but in it or a branch on
  // the way to it (its parents up to the root) counts as time in a wrong branch
  std::string target_branch;
  // the wall's force on the tip's nodes worth a mark on the timeline, N: the time above it is reported
  double tip_force_threshold_n = 0.05;
  // a force at which a wire tip may enter the wall, N: each episode above it is a risk event.
  // 0.12 N is the tip load of a wire made to penetrate an occlusion's cap (12 gf: docs/debrief.md)
  double tip_force_risk_n = 0.12;
  // the x-ray tube's output and technique, for the air kerma at the interventional reference
  // point (IRP): K = Y (mA s) (1 m / d)^2 a pulse (docs/debrief.md). Assumed adult cardiac figures,
  // not a measured unit's
  double tube_output_ugy_per_mas_at_1m = 50.0;
  double fluoro_mas_per_pulse = 0.15;
  double cine_mas_per_frame = 1.5;
};

}  // namespace pcisim::server
