#pragma once
// The guidewire as a generalized 3D chain-mail (paper section III): nodes joined by links with
// compress/stretch/shear limits, moved by geometric propagation from a sponsoring node
// (eqs 1-4) and relaxed by physical-optimisation passes (eqs 5-10).
//
// Node 0 is proximal, node N the tip. The proximal part lives in the guide catheter: a node is
// kinematic (placed on the catheter path) while its arc length from the tip exceeds the fed
// length, and free once it has left the catheter exit. The wire is torsionally stiff: the
// material frame is the frame parallel-transported down the wire from the catheter exit, turned
// by the proximal rotation, so turning the instrument turns the tip's bend plane.
#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "physics/guidewire/catheter_path.h"
#include "physics/guidewire/guidewire_params.h"
#include "physics/guidewire/link_spec.h"
#include "physics/guidewire/lumen_query.h"

namespace pcisim::physics {

class ChainMailWire {
 public:
  // allocates everything the wire will ever need; throws std::invalid_argument on bad params
  ChainMailWire(const GuidewireParams& params, CatheterPath path);

  // feed and twist from the instrument, then geometric propagation from the exit (eqs 1-4).
  // insertion is clamped to [0, length]; inputs must be finite (see InputGuard). A wire that
  // refused feed earlier takes back at most one link length more than the new push per step.
  void begin_step(double insertion_m, double rotation_rad);
  // one physical-optimisation pass (eqs 5-10) followed by rest-length restoration
  void optimise_pass(int pass_index);
  // compression that contact left is pushed back to the exit, where the catheter refuses that
  // much feed; then the limits are swept forward from the exit again (eqs 1-4). With a lumen,
  // each node the sweep places is also pushed back inside the wall margin (eq 15) without
  // leaving its valid region. Afterwards every free link is within its limits.
  void restore_limits(const LumenQuery* lumen = nullptr, double wall_margin_m = 0.0);
  // replaces a non-finite state by a straight wire out of the catheter (counted)
  void end_step();

  int segment_count() const { return n_; }
  int node_count() const { return n_ + 1; }
  int first_free_node() const { return first_free_; }  // == node_count() when none is out
  double rest_length_m() const { return rest_m_; }
  std::span<const Eigen::Vector3d> nodes_m() const { return nodes_; }
  std::span<Eigen::Vector3d> mutable_nodes_m() { return nodes_; }
  std::span<const Eigen::Vector3d> step_start_nodes_m() const { return start_; }
  std::span<const LinkSpec> links() const { return links_; }
  bool node_in_tip(int i) const { return i > 0 && links_[i - 1].tip; }
  double commanded_feed_m() const { return commanded_feed_; }
  double fed_length_m() const { return fed_; }  // what the wire accepted
  double rotation_rad() const { return rotation_; }
  // unit direction the tip bends towards (material director of the link before the tip's bend)
  Eigen::Vector3d tip_bend_direction() const;
  // rest direction of link j seen from link j-1's current frame: the axis of link j's valid
  // region (eqs 2-4). For the first free link the previous frame is the catheter exit's.
  Eigen::Vector3d rest_axis(int j) const;
  const CatheterPath& path() const { return path_; }
  int64_t recoveries() const { return recoveries_; }

 private:
  struct Frame {
    Eigen::Vector3d t, b, m;  // tangent, transported reference, material bend direction
  };
  Frame exit_frame() const;
  void advance(Frame& f, const Eigen::Vector3d& t_new) const;
  int first_free_for(double fed_m) const;
  void place_kinematic();
  void advance_along_track(double delta_m);
  void compute_frames();
  // returns the largest wall distance left at a swept node (-1 without a lumen)
  double forward_sweep(const LumenQuery* lumen, double wall_margin_m, bool may_swing);
  void backward_contact_sweep(const LumenQuery& lumen, double wall_margin_m);
  void bend_pass(bool forward);
  void length_pass();
  void backward_sweep_compression();

  GuidewireParams params_;
  CatheterPath path_;
  int n_ = 0;
  double rest_m_ = 0.0;
  Eigen::Vector3d ref_b_;  // reference director at the exit, fixed in the world
  std::vector<LinkSpec> links_;
  std::vector<Eigen::Vector3d> nodes_, start_;
  std::vector<Eigen::Vector3d> track_;              // scratch: the exit then the free nodes of the step start
  std::vector<double> cum_;                         // scratch: arc length along track_
  std::vector<Eigen::Vector3d> frame_t_, frame_m_;  // per link, refreshed by compute_frames()
  int first_free_ = 0;
  int tip_links_ = 0;
  bool tip_touching_ = false;  // a tip node lay at the wall after the last contact-aware sweep
  double commanded_feed_ = 0.0, fed_ = 0.0, rotation_ = 0.0;
  int64_t recoveries_ = 0;
};

}  // namespace pcisim::physics
