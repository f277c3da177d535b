#pragma once
// Iodine in the coronary tree over time, a simple documented model (docs/xray.md):
// each injection pushes contrast into one ostium (left main or RCA); the bolus front advances
// down every branch below it at a flow velocity, so a point s mm downstream of the ostium sees
// the ostium's concentration delayed by s / v. At the ostium the concentration rises while the
// injection lasts (time constant rise_s) to a peak set by injection rate over coronary flow,
// then washes out exponentially (washout_s); mixing with unopacified side flow tapers it
// downstream (exp(-s / taper_mm)). Opacity 1 = a lumen full of undiluted contrast.
// The tree is cut into lumen segments (truncated cones ~segment_mm long) once; per frame only
// each segment's opacity is computed (nothing allocated).
#include <Eigen/Core>
#include <span>
#include <string>
#include <vector>

#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::xray {

enum class CoronaryOstium { kLeft, kRight };

// lumen segments below this opacity are not drawn (fluoroscopy.cc) nor labelled (the dataset's
// vessel mask): their iodine is under a thousandth of a full lumen's
inline constexpr double kMinDrawnOpacity = 1e-3;

// contrast in the tree: the bolus enters at the ostium and travels downstream, then washes out
struct ContrastInjection {
  double start_s = 0;       // when the injection began (simulation time)
  double duration_s = 2.0;  // how long it is pushed
  double volume_ml = 8.0;
  CoronaryOstium ostium = CoronaryOstium::kLeft;  // the left main (LAD, LCx, D, OM) by default
};

struct ContrastBolusSpec {
  // mean coronary flow velocity: 10-30 cm/s at rest by Doppler wire, more in hyperaemia
  // (Doucette et al., Circulation 1992); the bolus front moves with it
  double velocity_mm_per_s = 150;
  double rise_s = 0.15;    // how fast the ostium fills once the injection starts
  double washout_s = 1.5;  // exponential clearance after it stops (1-2 s in angiograms)
  double taper_mm = 300;   // dilution length downstream
  // resting coronary blood flow ~225 ml/min, ~2/3 of it in the left tree (Guyton & Hall,
  // Textbook of Medical Physiology, ch. 21): an injection faster than this fills the lumen fully
  double left_flow_ml_per_s = 2.5;
  double right_flow_ml_per_s = 1.25;
  double segment_mm = 2.0;        // lumen segment length for the overlay
  double visible_opacity = 0.05;  // a branch counts as holding contrast above this
};

struct LumenSegment {
  Eigen::Vector3d a_mm, b_mm;  // axis ends, phantom frame (the tree's x 1000)
  double ra_mm = 0, rb_mm = 0;
  double s_mm = 0;                 // mid-point distance downstream of the ostium
  int branch = -1;                 // index into the tree's branches
  int point_a = -1, point_b = -1;  // the centerline points the ends sit on, tree order (flattened)
  CoronaryOstium ostium = CoronaryOstium::kLeft;
};

class ContrastBolus {
 public:
  // segments every branch except the aorta; the stretch of a branch inside its parent's lumen
  // (the LM and RCA inside the aortic root, a side branch's first points) is left out, and the
  // ostium (s = 0) is where the LM or RCA leaves the aorta
  ContrastBolus(const anatomy::VesselTree& tree, const ContrastBolusSpec& spec);

  // concentration (0..1) at s mm below `ostium` at time t_s, summed over the injections
  double opacity(double s_mm, CoronaryOstium ostium, double t_s, std::span<const ContrastInjection> injections) const;
  // the tree has moved (the beating heart): every centerline point's position now, in tree
  // order (branch 0's points, then branch 1's, ...); a span of any other length is ignored.
  // Allocates nothing.
  void move(std::span<const Eigen::Vector3d> points_m);
  int tree_point_count() const { return tree_point_count_; }

  // every segment's and branch's (max over its segments) opacity at t_s; allocates nothing
  void update(double t_s, std::span<const ContrastInjection> injections);

  const std::vector<LumenSegment>& segments() const { return segments_; }
  const std::vector<double>& segment_opacity() const { return segment_opacity_; }
  const std::vector<double>& branch_opacity() const { return branch_opacity_; }  // by tree branch index
  const std::vector<std::string>& branch_names() const { return branch_names_; }
  const ContrastBolusSpec& spec() const { return spec_; }

 private:
  ContrastBolusSpec spec_;
  std::vector<LumenSegment> segments_;
  std::vector<double> segment_opacity_, branch_opacity_;
  std::vector<std::string> branch_names_;
  int tree_point_count_ = 0;
};

}  // namespace pcisim::xray
