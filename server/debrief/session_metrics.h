#pragma once
// What a session's debrief reports (issue #35), taken from the simulation's own truth as it runs:
// the beam's time, pulses and dose, contrast, the C-arm's poses, the tip's path, time in a wrong
// branch and the wall's force on the tip. One object per session, kept across scene reloads
// (like SessionLimits); the server's threads record into it (the x-ray thread the beam, the LCM
// receive thread injections, the send thread each wire state it publishes), never the 1 kHz loop.
// Every record takes one short lock (with priority inheritance: the LCM send thread, which records
// the wire states, runs SCHED_FIFO) and allocates nothing (the timeline's storage is made up front;
// a session past it keeps its figures and counts the events it could not list).
// Definitions, formulas and sources: docs/debrief.md.
#include <array>
#include <cstdint>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "physics/world_snapshot.h"
#include "realtime/pi_mutex.h"
#include "server/debrief/debrief_params.h"
#include "xray/geometry/detector_geometry.h"

namespace pcisim::anatomy {
struct VesselTree;
}

namespace pcisim::server {

// where the beam's dose is reckoned: the interventional reference point (IRP), 15 cm from the
// isocentre toward the focal spot (IEC 60601-2-43), and the beam's area there
struct BeamGeometry {
  double source_to_irp_mm = 600.0;
  double field_area_at_irp_cm2 = 0.0;
};
// the IRP and the detector's whole field carried back to it (no collimation is simulated)
BeamGeometry beam_geometry(double source_to_axis_mm, double source_to_image_mm, double detector_width_mm,
                           double detector_height_mm);

enum class TimelineKind : uint8_t {
  kFluoroOn,
  kFluoroOff,
  kCineOn,
  kCineOff,
  kCArm,
  kContrast,
  kForceEvent,
  kReset,
  kProlapse,
  kBuckling
};
const char* timeline_kind_name(TimelineKind k);

struct TimelineEntry {
  double time_s = 0.0;  // since the session began
  TimelineKind kind = TimelineKind::kFluoroOn;
  // C-arm: primary, secondary deg; contrast: ml; force event: peak N, duration s; prolapse: the
  // largest fold, deg, duration s; buckling: the most feed the tip did not take up, mm, duration s
  double a = 0.0, b = 0.0;
};

// the tip over the session, for the debrief's pictures: thinned to every 2^k-th state once full
struct TrackPoint {
  double time_s = 0.0;  // session time
  float tip_mm[3] = {0, 0, 0};
  float tip_force_n = 0.0f;
  float heart_phase = 0.0f;  // [0, 1) of the cardiac cycle (0 without a beating heart)
  uint8_t off_route = 0;     // in a wrong branch (with a target)
  uint16_t pipeline = 0;     // which scene of the session (a reload starts another)
};

// the frame the debrief draws the tip's path on: the one that showed the most contrast-filled
// branches (the latest of those), 16-bit as rendered, with its projection
struct Angiogram {
  int width = 0, height = 0;
  std::vector<uint16_t> pixels;
  xray::DetectorGeometry geometry;
  double time_s = -1.0;      // session time; < 0: no frame showed contrast
  double heart_phase = 0.0;  // the heart's phase the frame shows (NaN: a still background)
  int contrast_branches = 0;
  uint16_t pipeline = 0;
};

struct CArmUse {
  double primary_deg = 0.0, secondary_deg = 0.0;
  double beam_s = 0.0;  // beam time at this pose
};

struct DebriefFigures {
  double procedure_time_s = 0.0;  // first scene running to the end (or the report)
  double fluoro_time_s = 0.0;     // beam time, fluoroscopy and cine together (the lab's "fluoro time")
  double cine_time_s = 0.0;       // of it, cine
  int64_t fluoro_pulses = 0, cine_frames = 0;
  int cine_runs = 0;
  int contrast_injections = 0;
  double contrast_ml = 0.0;
  double air_kerma_mgy = 0.0;  // at the IRP
  double dap_gycm2 = 0.0;      // dose-area product
  std::vector<CArmUse> carm_poses;
  double tip_path_mm = 0.0;             // the tip's 3-D path over the wire states
  double tip_path_projected_mm = 0.0;   // the same across the beam: on the plane normal to the C-arm's central ray
  double tip_path_in_vessels_mm = 0.0;  // in the vessels' rest frame: the heart's motion taken out
  bool has_target = false;              // a scene of the session named a target branch its tree has
  std::string target_branch;
  double wrong_branch_s = 0.0;     // the tip in a branch neither the target nor on the way to it
  double target_reached_s = -1.0;  // session time the tip first entered the target (-1: never)
  bool tip_forces_known = false;   // the wire computes the wall's force (the rod; not the chain-mail)
  double peak_tip_force_n = 0.0;
  double tip_force_above_threshold_s = 0.0;
  int force_events = 0;  // episodes above the risk force
  // the wire folded back: its last 5 mm turned more than kProlapseDeg from its direction 10-30 mm
  // behind the tip; the feed not reaching the tip: over the last second the hub fed at least
  // kBucklingFeedMm and the tip moved (through the vessels) less than a quarter of it
  int prolapse_events = 0, buckling_events = 0;
  int64_t wire_states = 0;
  int resets = 0;  // the wire started over (a reset or a new scene): its path is not joined across
  std::vector<TimelineEntry> timeline;
  int64_t timeline_dropped = 0;
  std::vector<TrackPoint> track;
  Angiogram angiogram;
  DebriefParams params;  // the last scene's
};

class SessionMetrics {
 public:
  static constexpr int kMaxTimeline = 8192;
  static constexpr int kMaxPoses = 64;
  static constexpr int kMaxTrack = 16384;
  static constexpr double kProlapseDeg = 150.0;
  static constexpr double kBucklingFeedMm = 3.0;
  SessionMetrics();

  // a scene's pipeline starts: its thresholds, its tree (the route to the target), whether its
  // wire computes the wall's force, and the beam's geometry. Not while a thread records
  void begin_pipeline(const DebriefParams& params, const anatomy::VesselTree& tree, bool tip_forces_known,
                      const BeamGeometry& beam, int64_t now_ns, int detector_width = 0, int detector_height = 0);

  // the x-ray thread: beam time added (seconds, the mode), a pulse or cine frame, the pedals
  void record_beam_time(double seconds, bool cine, double primary_deg, double secondary_deg);
  void record_pulse(bool cine);
  void record_pedals(bool fluoro, bool cine, int64_t now_ns);
  void record_carm(double primary_deg, double secondary_deg, int64_t now_ns);
  // a frame shown (its contrast-filled branches counted): kept when it shows more than the last kept
  void record_frame(const uint16_t* pixels, int width, int height, const xray::DetectorGeometry& geometry,
                    double heart_phase, int contrast_branches, int64_t now_ns);
  // the receive thread: an accepted injection
  void record_injection(double volume_ml, int64_t now_ns);
  // the send thread: each wire state as published; primary and secondary the C-arm's pose
  void record_wire(const physics::WorldSnapshot& s, double primary_deg, double secondary_deg, int64_t now_ns);

  // the figures so far (procedure time up to now_ns), with their lists (poses, timeline, track, frame)
  DebriefFigures figures(int64_t now_ns) const;
  // the same without the lists, into `out` in place (its strings keep their storage: the
  // once-a-second message allocates nothing once warm); out's lists are left as they are
  void figures_without_lists(int64_t now_ns, DebriefFigures* out) const;

 private:
  void add_event(TimelineKind kind, double a, double b, int64_t now_ns);
  // an episode of a condition over successive wire states (the tip's force above the risk force,
  // the wire folded back, the feed not reaching the tip): from the first state that meets it to the
  // first that does not; listed on the timeline at its start with its peak and duration when it ends
  struct Episode {
    TimelineKind kind;
    bool on = false;
    double start_s = 0.0, sim_start_s = 0.0, peak = 0.0;
    int count = 0;
  };
  void update_episode(Episode& e, bool on, double value, double sim_time_s, int64_t now_ns);
  void end_episode(Episode& e, double sim_end_s);
  void end_episodes();
  double session_s(int64_t now_ns) const;

  mutable realtime::PiMutex mutex_;
  DebriefParams params_;
  BeamGeometry beam_;
  bool forces_known_ = false;
  int64_t start_ns_ = 0;
  // per pipeline: which branches are the route (the target and its parents), the target's index
  std::vector<uint8_t> on_route_;
  int target_ = -1;
  // the wire's last state (continuity)
  bool have_last_ = false;
  int64_t last_step_ = 0;
  double last_time_s_ = 0.0;
  double last_tip_[3] = {0, 0, 0};
  double last_tip_rest_[3] = {0, 0, 0};
  int last_branch_ = -1;
  double last_tip_force_n_ = 0.0;
  // the beam
  bool fluoro_on_ = false, cine_on_ = false;
  Episode force_{TimelineKind::kForceEvent}, fold_{TimelineKind::kProlapse}, feed_{TimelineKind::kBuckling};
  // the last second or two of the hub's feed and the tip's place in the vessels (a ring)
  struct FeedSample {
    double time_s = 0.0, insertion_m = 0.0;
    Eigen::Vector3d tip_rest_m = Eigen::Vector3d::Zero();
  };
  std::array<FeedSample, 64> feed_samples_{};
  int feed_head_ = 0, feed_count_ = 0;
  DebriefFigures f_;
  std::vector<TimelineEntry> timeline_;  // kMaxTimeline, made up front
  int timeline_count_ = 0;
  std::vector<TrackPoint> track_;  // kMaxTrack, made up front
  int track_count_ = 0, track_stride_ = 1, track_skip_ = 0;
  uint16_t pipeline_ = 0;
  Angiogram angiogram_;  // its pixels sized by begin_pipeline
  // the x-ray thread's copy of a frame to keep, made outside the lock and swapped in (same capacity)
  std::vector<uint16_t> incoming_;
  std::array<CArmUse, kMaxPoses> poses_{};
  int pose_count_ = 0;
};

// debrief.json (docs/debrief.md lists its keys)
nlohmann::json to_json(const DebriefFigures& f);
// a few lines for the server's exit summary
std::string human_debrief(const DebriefFigures& f);

}  // namespace pcisim::server
