#pragma once
// The rigs of `pcisim-bench wire-force` (issue #33): the rod wire with its wall inside the solve
// (RodContactScheme::kSolve) in a set-up whose answer is a textbook result the bench computes
// without the rod. One function per rig, each returning what it measured and its reference:
//   tip_on_wall  a clamped wire whose tip a rigid finger pushes aside: the elastica's tip load
//   capstan      a wire of negligible bending stiffness drawn round a bent tube and held at its
//                far end: pull = hold e^(mu theta) (theta: the angle the wire wraps)
//   end_on       a straight wire pushed into the closed end of a straight tube: it first buckles
//                at the clamped-pinned Euler load; afterwards the tube holds it
//   dead_end     the default wire fed into the closed end of a bent tube: the hub's force against
//                the feed (a curve for the report's plot), what crumples, what is left in the wall
//   torque_lag   the hub turned a whole turn at a constant rate: the tip's rotation against time in
//                a tortuous tube with friction, beside a straight frictionless tube (the tip follows)
//   default_scene  no textbook: the default beating scene with the rod, what its steps cost there
#include <string>
#include <vector>

#include "physics/guidewire/guidewire_params.h"

namespace pcisim::bench::wire_force {

// every rig steps the wire at the scenes' 30 Hz
inline constexpr double kStepS = 1.0 / 30.0;

// the wall scheme every rig's wire runs (--contact solve|implicit; the bench sets it once)
physics::RodContactScheme contact_scheme();
void set_contact_scheme(physics::RodContactScheme scheme);

// one 30 Hz step of the wire: its median and 99th percentile over a run, and the substeps a
// step took (more than the 8 set where the contact halved them)
struct StepCost {
  double ms_p50 = 0, ms_p99 = 0;
  int substeps_p50 = 0, substeps_max = 0;
};

// a step's cost from the per-step figures (wire_force_rigs.cc)
StepCost step_cost(std::vector<double> step_ms, std::vector<int> substeps);
// its JSON fields, as every rig's line ends: "step_ms_p50": ..., "substeps_max": ...
std::string cost_json(const StepCost& c);

// --- tip_on_wall ---
// the wire's free length is whole segments (the hub is a node): 48 mm is whole at 0.5-4 mm
struct TipOnWall {
  double length_mm = 48, deflection_mm = 4.8;
  int segments = 300, substeps = 8;
};
struct TipOnWallResult {
  double free_length_mm = 0;  // what the wire has free: whole segments, the requested L rounded up
  double contact_force_n = 0, ei_nm2 = 0, beam_n = 0, elastica_n = 0, tip_x_mm = 0, residual_mm = 0;
  int contacts = 0;
  StepCost cost;
};
TipOnWallResult run_tip_on_wall(const TipOnWall& c);
std::string json_line(const TipOnWall& c, const TipOnWallResult& r);

// --- capstan ---
// the tube: 30 mm straight from the catheter's exit, then a bend of angle_deg at 15 mm radius
// (beyond 180 degrees a helix rising 5 mm a turn, so the tube clears itself), then 40 mm straight;
// 1.5 mm lumen radius. The wire (EI and GJ 1e-9, the range's floor; no soft tip) is drawn through
// by a 0.01 N leader force on its tip, then its tip is held by hold_n along the last straight
// while the hub pulls it back at 10 mm/s; mu is both friction coefficients
struct Capstan {
  double mu = 0.2, angle_deg = 90, hold_n = 0.05;
};
struct CapstanResult {
  double pull_n = 0;           // the hub's pull averaged over every substep of the last 0.75 s of the 1.5 s pull
  double pull_spread_n = 0;    // the largest departure of one step's average from it
  double pull_step_end_n = 0;  // the pull at the steps' ends (their last substeps), mean over those steps
  double wrap_rad = 0;         // the angle the wire wraps: the bend, less the helix's rise
  double capstan_n = 0;        // hold e^(mu wrap)
  double residual_mm = 0;      // the deepest a node was left in the wall while pulled
  bool drawn_through = false;
  StepCost cost;
};
CapstanResult run_capstan(const Capstan& c);
std::string json_line(const Capstan& c, const CapstanResult& r);

// --- end_on ---
// a straight tube closed at the far end, the catheter's exit on its axis, its lumen radius the
// clearance plus the wall margin (the wire's centerline may move clearance_mm off the axis). The
// wire (default section, no soft tip, no friction) is fed until its tip meets the end at free
// length length_mm, loaded (the hub's force raised step by step, the feed following) until it
// buckles, then pushed 20 mm more at 5 mm/s; a lateral gravity of 0.05 m/s^2 is the imperfection
// that picks the buckling direction
struct EndOn {
  double length_mm = 50, clearance_mm = 0.5;
};
struct EndOnResult {
  double buckling_n = 0;  // the hub's force when the wire's largest lateral deflection first reaches half the clearance
  double column_mm = 0;   // the buckling column: from the hub node (the clamp) to the end's stop
  double euler_n = 0;     // clamped-pinned over that column: 4.4934^2 EI / L^2 (= pi^2 EI / (0.699 L)^2)
  double max_hub_n = 0;   // the largest hub force over the 20 mm
  double max_crumpled_mm = 0;  // the most the free wire was shorter than its length
  double blew_up_at_mm = -1;   // the feed past the end at which it blew up (the run stops), -1: never
  double worst_mm = 0;         // the furthest a node went past the wall margin (<= 0: never)
  bool buckled = false;
  StepCost cost;
};
EndOnResult run_end_on(const EndOn& c);
std::string json_line(const EndOn& c, const EndOnResult& r);

// --- dead_end ---
// the default wire (its soft tip straight), friction 0.3 / 0.2, in the tube of the rod tests
// (40 mm straight, 90 degrees at 15 mm radius, then straight to its closed end 124 mm along its
// centerline; 1.5 mm lumen radius): fed 110 mm, then on towards 200 mm over 3 s and held 1 s
struct DeadEndSample {
  double commanded_mm = 0, fed_mm = 0, hub_n = 0, tip_n = 0, crumpled_mm = 0, worst_mm = 0, step_ms = 0;
  int substeps = 0;
};
struct DeadEndResult {
  std::vector<DeadEndSample> samples;  // one per step from the 110 mm on
  double max_hub_n = 0, max_tip_n = 0, max_crumpled_mm = 0, worst_mm = 0;
  double largest_hub_jump_n = 0;  // the largest change of the hub's force between two steps
  double refused_mm = 0;          // at the end
  StepCost cost;
};
DeadEndResult run_dead_end();
std::string json_line(const DeadEndResult& r);

// --- torque_lag ---
// the default wire (its soft tip straight; friction 0.1 / 0.07 body, 0.2 / 0.15 tip, or none) fed
// fed_mm at 30 mm/s into a tube of 1.5 mm lumen radius: tortuous (32 mm straight, then bends of
// 90, 90 and 120 degrees at 10-12 mm radius in three planes with 15 mm between them, the last
// ending 115.5 mm from the exit, then 30 mm straight) or straight (140 mm); then the hub turned
// 360 degrees at 180 deg/s and held 2 s. Fed less than 116 mm the tip stops short of the last bend
struct TorqueLag {
  bool tortuous = true, friction = true;
  double fed_mm = 130;
};
struct TorqueLagSample {
  double t_s = 0, hub_deg = 0, tip_deg = 0;  // from the turn's start; the tip's spin about its axis
};
struct TorqueLagResult {
  std::vector<TorqueLagSample> samples;  // one per step of the turn and the hold
  double lag_at_turn_end_deg = 0;        // hub - tip when the hub stops
  double final_lag_deg = 0;              // after the hold
  double max_lag_deg = 0;                // the most the tip fell behind the hub
  double max_lead_deg = 0;               // the most it ran ahead (after a slip)
  double max_tip_rate_ratio = 0;         // the tip's fastest turn over one step / the hub's rate (> 1: whip)
  bool completed = false;                // false: the run went non-finite
  StepCost cost;
};
TorqueLagResult run_torque_lag(const TorqueLag& c);
std::string json_line(const TorqueLag& c, const TorqueLagResult& r);

// --- default_scene ---
// the default beating scene driven by the built-in trainee's session (19.5 s down the LAD), its
// wire the rod (200 segments, the moving wall pushing it) with the given wall scheme; the cost is
// the world's guidewire effect (the rod's step with its contact and friction), per 30 Hz step
struct DefaultSceneResult {
  physics::RodContactScheme scheme = physics::RodContactScheme::kProjection;
  double max_ms = 0;           // the slowest step
  double max_residual_mm = 0;  // the deepest a node was left in the wall before it was moved out
  double max_hub_n = 0;
  int recoveries = 0;    // times the rod went non-finite and was laid out afresh
  int steps = 0;         // 30 Hz steps of the session
  int retried = 0;       // substeps taken back and tried at half the length, over the session
  int steps_halved = 0;  // steps with a substep taken back
  int deep_steps = 0;    // steps that left a node deeper than 0.3 mm in the wall before it was moved out
  StepCost cost;
};
DefaultSceneResult run_default_scene(physics::RodContactScheme scheme);
std::string json_line(const DefaultSceneResult& r);

}  // namespace pcisim::bench::wire_force
