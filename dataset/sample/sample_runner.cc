#include "dataset/sample/sample_runner.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>

#include "anatomy/case/heart_center.h"
#include "dataset/sample/coco.h"
#include "dataset/sample/frame_labels.h"
#include "dataset/sample/instrument_driver.h"
#include "physics/world.h"
#include "server/beat_samples.h"

namespace pcisim::dataset {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// renderers kept per job, one per recent anatomy (each holds its CT's projector)
constexpr size_t kCachedRenderers = 3;

// the branch holding the tip, in the tree where `points_m` (tree order; empty: at rest) put it.
// `scratch` is a copy of `rest` (made once per anatomy: only its positions change per frame)
int tip_branch(const anatomy::VesselTree& rest, const std::vector<Eigen::Vector3d>& points_m,
               const Eigen::Vector3d& tip_m, anatomy::VesselTree* scratch) {
  if (points_m.empty()) return anatomy::innermost_branch(rest, tip_m);
  size_t k = 0;
  for (auto& b : scratch->branches)
    for (auto& p : b.points)
      if (k < points_m.size()) p.position_m = points_m[k++];
  return anatomy::innermost_branch(*scratch, tip_m);
}

}  // namespace

SampleRunner::SampleRunner(const DatasetSpec& spec, std::shared_ptr<AnatomyCache> anatomies)
    : spec_(spec), anatomies_(std::move(anatomies)), labeler_(spec.labels.mask_min_line_integral) {}
SampleRunner::~SampleRunner() = default;

SampleRunner::Renderer& SampleRunner::renderer_for(std::shared_ptr<const BuiltAnatomy> anatomy) {
  for (size_t i = 0; i < renderers_.size(); ++i) {
    if (renderers_[i]->anatomy->key != anatomy->key) continue;
    std::rotate(renderers_.begin() + static_cast<std::ptrdiff_t>(i),
                renderers_.begin() + static_cast<std::ptrdiff_t>(i) + 1, renderers_.end());
    return *renderers_.back();
  }
  if (renderers_.size() >= kCachedRenderers) renderers_.erase(renderers_.begin());
  renderers_.push_back(std::make_unique<Renderer>());
  renderers_.back()->anatomy = std::move(anatomy);
  return *renderers_.back();
}

nlohmann::json SampleRunner::run(const SamplePlan& plan, FrameSink& sink) {
  auto t0 = Clock::now();
  const server::Scene& scene = plan.scene;
  const server::XraySpec& xs = *scene.xray;
  const std::shared_ptr<const BuiltAnatomy> built = anatomies_->get(plan);
  Renderer& a = renderer_for(built);
  const anatomy::Case& c = *built->c;
  const std::shared_ptr<const physics::LumenQuery>& lumen = built->lumen;
  times_.anatomy_s += seconds_since(t0);
  t0 = Clock::now();
  physics::World world(scene.world, c.vessels, lumen, c.heart, c.heart_vertices_m, c.organ ? &*c.organ : nullptr);
  times_.world_s += seconds_since(t0);
  t0 = Clock::now();

  // the renderer over the case's CT, restarted for this sample (or built when none fits)
  xray::CArmPose pose = xs.initial_pose;
  pose.isocenter_mm = anatomy::heart_center_mm(c);
  const auto& f = xs.fluoro;
  const std::string renderer_key = fmt::format("{}|{}|{}", static_cast<int>(f.projector.projector),
                                               f.projector.trilinear.step_voxels, f.projector.trilinear.slices);
  if (!a.renderer || a.renderer_key != renderer_key) {
    // built with the scene's seed (the thorax phantom's), restarted at once with the sample's
    // noise seed, as every later sample on this anatomy is
    a.renderer.reset();
    a.renderer = std::make_unique<xray::FluoroscopyRenderer>(c.vessels, anatomy::Volume(built->background), f);
    a.renderer_key = renderer_key;
  }
  // the beating background depends on the heart alone: kept (with its bins projected so far)
  // while the next sample's heart is the same
  const bool beating = scene.world.vessel_motion && xs.heart_phase_bins > 0;
  const auto& effects = plan.scene_doc.at("effects");
  const std::string beat_key = beating
                                   ? fmt::format("{}|{}|{}|{}|{}", effects.value("heart_beat", nlohmann::json()).dump(),
                                                 effects.value("vessel_motion", nlohmann::json()).dump(),
                                                 scene.physics_rate_hz, xs.heart_phase_bins, xs.heart_phase_blend)
                                   : "";
  const bool keep_beat = beating && a.renderer->beat() && a.beat_key == beat_key;
  xray::FluoroSpec noise_spec = f;
  noise_spec.seed = static_cast<uint32_t>(plan.seed);
  a.renderer->restart(noise_spec, keep_beat);
  xray::FluoroscopyRenderer& renderer = *a.renderer;
  times_.anatomy_s += seconds_since(t0);
  t0 = Clock::now();
  if (beating && !keep_beat) {
    // this heart's cycle and the bins' changes of this CT: made by the first job to need them,
    // shared by the others (each background still builds its warp's fields from the samples)
    const xray::BeatingBackgroundOptions options = server::beat_options(xs);
    bool made = false;
    const BeatCache::Kept beat = built->beats.get(beat_key, [&] {
      auto b = std::make_shared<SharedBeat>();
      b->samples = server::beat_samples_mm(world.sample_beat_cycle(xs.heart_phase_bins));
      renderer.set_beat(b->samples, options);
      b->changes = renderer.beat()->changes();
      made = true;
      return b;
    });
    if (!made) renderer.set_beat(beat->samples, options, beat->changes);
    a.beat = beat;
  }
  if (!beating) a.beat = nullptr;
  a.beat_key = beat_key;
  times_.beat_s += seconds_since(t0);
  t0 = Clock::now();

  InstrumentDriver driver(
      spec_.driver, SampleRng::for_sample(spec_.seed, static_cast<uint64_t>(plan.index), kDriverStream), plan.script);
  std::vector<xray::ContrastInjection> injections;
  if (plan.injection && xs.contrast) {
    xray::ContrastInjection inj;
    inj.start_s = plan.injection_start_s;
    inj.duration_s = xs.injection_duration_s;
    inj.volume_ml = xs.injection_volume_ml;
    injections.push_back(inj);
  }
  times_.world_s += seconds_since(t0);

  physics::WorldSnapshot snap;
  std::vector<Eigen::Vector3d> wire_mm, vessel_mm;
  const double step_s = scene.world.step_s;
  for (int k = 0; k < spec_.frames_per_sample; ++k) {
    // physics up to the frame's pulse
    t0 = Clock::now();
    const double t_frame = plan.warmup_s + k / xs.pulse_rate_fps;
    while (world.time_s() + 0.5 * step_s < t_frame) world.step(driver.at(world.time_s() + step_s));
    world.write_snapshot(snap);
    times_.physics_s += seconds_since(t0);

    xray::FluoroInput in;
    in.time_s = snap.time_s;
    in.pose = pose;
    in.wire_m = snap.wire_nodes_m;
    in.injections = injections;
    // an empty list would leave the bolus where an earlier sample's heart carried it
    in.vessel_points_m = snap.vessel_points_m.empty() ? std::span<const Eigen::Vector3d>(built->rest_points_m)
                                                      : std::span<const Eigen::Vector3d>(snap.vessel_points_m);
    if (beating) in.heart_phase = snap.heart_phase;
    renderer.render(in, frame_);
    const xray::FluoroFrameCost& cost = renderer.last_frame_cost();
    times_.projection_s += 1e-3 * (cost.background_ms + cost.beat_ms);
    times_.overlay_s += 1e-3 * cost.overlay_ms;
    times_.noise_s += 1e-3 * cost.detector_ms;

    // labels: the vessel images, then the geometry of everything the frame shows
    t0 = Clock::now();
    labeler_.label(frame_.geometry, renderer.contrast(), f.iodine_mu_per_mm);
    wire_mm.resize(snap.wire_nodes_m.size());
    for (size_t i = 0; i < wire_mm.size(); ++i) wire_mm[i] = 1e3 * snap.wire_nodes_m[i];
    vessel_mm.resize(snap.vessel_points_m.size());
    for (size_t i = 0; i < vessel_mm.size(); ++i) vessel_mm[i] = 1e3 * snap.vessel_points_m[i];
    const std::vector<Eigen::Vector3d> keys =
        wire_keypoints(frame_.geometry, wire_mm, spec_.labels.wire_keypoints, spec_.labels.wire_keypoint_span_mm);
    FrameTruth truth;
    truth.frame = k;
    truth.time_s = snap.time_s;
    truth.heart_phase = snap.heart_phase;
    truth.geometry = frame_.geometry;
    truth.pose = frame_.pose;
    truth.sid_mm = f.c_arm.source_to_image_mm;
    truth.sad_mm = f.c_arm.source_to_axis_mm;
    truth.wire_mm = wire_mm;
    truth.wire_px = frame_.wire_px;
    truth.keypoints = keys;
    // the tip's branch: the lumen holding it most deeply, in the tree as the heart has moved it
    if (!snap.wire_nodes_m.empty()) {
      if (moved_tree_of_ != built->key) {
        moved_tree_ = c.vessels;
        moved_tree_of_ = built->key;
      }
      const int b = tip_branch(c.vessels, snap.vessel_points_m, snap.wire_nodes_m.back(), &moved_tree_);
      if (b >= 0) truth.tip_branch = built->branch_names[static_cast<size_t>(b)];
    }
    truth.tree = &c.vessels;
    truth.vessel_points_mm = vessel_mm;
    truth.branch_opacity = renderer.contrast().branch_opacity();
    // each centerline point's contrast: the largest of the lumen segments ending on it
    point_opacity_.assign(built->rest_points_m.size(), 0.0);
    const auto& segs = renderer.contrast().segments();
    const auto& seg_op = renderer.contrast().segment_opacity();
    for (size_t i = 0; i < segs.size(); ++i) {
      for (int p : {segs[i].point_a, segs[i].point_b})
        if (p >= 0 && static_cast<size_t>(p) < point_opacity_.size())
          point_opacity_[static_cast<size_t>(p)] = std::max(point_opacity_[static_cast<size_t>(p)], seg_op[i]);
    }
    truth.point_opacity = point_opacity_;
    truth.visible_opacity = f.contrast.visible_opacity;
    truth.mask_pixels = labeler_.mask_pixels();
    const nlohmann::json labels = frame_labels(truth);
    const nlohmann::json coco =
        coco_frame_annotations(keys, labeler_.branch_ids(), frame_.width, frame_.height, built->branch_names);
    times_.labels_s += seconds_since(t0);

    t0 = Clock::now();
    sink.frame({.frame = k, .image = &frame_, .vessels = &labeler_, .labels = &labels, .coco = &coco});
    times_.write_s += seconds_since(t0);
    ++times_.frames;
  }
  ++times_.samples;

  nlohmann::json injection = nullptr;
  if (!injections.empty())
    injection = {{"start_s", injections[0].start_s},
                 {"duration_s", injections[0].duration_s},
                 {"volume_ml", injections[0].volume_ml},
                 {"ostium", "left"}};
  return {
      {"sample", plan.index},
      {"seed", plan.seed},
      {"anatomy", plan.anatomy},
      {"drawn", plan.drawn.is_null() ? nlohmann::json::object() : plan.drawn},
      {"frames", spec_.frames_per_sample},
      {"first_frame_s", plan.warmup_s},
      {"pulse_rate_fps", xs.pulse_rate_fps},
      {"physics_rate_hz", scene.physics_rate_hz},
      {"projector", xray::projector_name(f.projector.projector)},
      {"beating_background", beating ? xs.heart_phase_bins : 0},
      {"photons_per_pixel", f.photons_per_pixel},
      {"blur_sigma_px", f.blur_sigma_px},
      {"injection", injection},
      {"driver", spec_.driver.kind == DriverSpec::Kind::kScript ? "script" : "random_walk"},
      {"effects", scene.effects},
      {"scene", plan.scene_doc},
  };
}

}  // namespace pcisim::dataset
