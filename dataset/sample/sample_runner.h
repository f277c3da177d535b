#pragma once
// Runs one sample headless and as fast as the machine goes: the drawn scene's physics stepped
// from t = 0 under the instrument driver, then frames_per_sample fluoroscopy frames at the
// scene's pulse rate, each handed with its labels to a sink. The same plan gives the same bytes:
// everything is seeded by the sample, and what is cached between samples (the case, its contact
// field, the renderer over its CT) is rebuilt or restarted so no sample sees another's state.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "anatomy/case/case.h"
#include "dataset/sample/anatomy_cache.h"
#include "dataset/sample/sample_plan.h"
#include "dataset/sample/vessel_labeler.h"
#include "physics/guidewire/lumen_query.h"
#include "xray/fluoro/fluoroscopy.h"

namespace pcisim::dataset {

struct FrameOutput {
  int frame = 0;
  const xray::FluoroFrame* image = nullptr;  // 16-bit display frame, dark = radiopaque
  const VesselLabeler* vessels = nullptr;    // the mask and the branch label image
  const nlohmann::json* labels = nullptr;    // frame_labels()
  const nlohmann::json* coco = nullptr;      // coco_frame_annotations()
};

class FrameSink {
 public:
  virtual ~FrameSink() = default;
  virtual void frame(const FrameOutput& out) = 0;
};

// wall time by stage, summed over every sample this runner ran
struct StageTimes {
  double anatomy_s = 0;     // case, contact field and renderer built (once per anatomy kept), restarted
  double world_s = 0;       // the scene's physics built
  double beat_s = 0;        // one heart cycle sampled and the CT's warp built (beating background)
  double physics_s = 0;     // world steps
  double projection_s = 0;  // the background (static and beating) projected
  double overlay_s = 0;     // iodine and wire
  double noise_s = 0;       // the detector chain: quanta, noise, blur, log, window
  double labels_s = 0;      // masks, centerlines, keypoints, JSON
  double write_s = 0;       // the sink (PNG and JSON files)
  int64_t frames = 0, samples = 0;

  StageTimes& operator+=(const StageTimes& o) {
    anatomy_s += o.anatomy_s, world_s += o.world_s, beat_s += o.beat_s, physics_s += o.physics_s;
    projection_s += o.projection_s, overlay_s += o.overlay_s, noise_s += o.noise_s, labels_s += o.labels_s;
    write_s += o.write_s, frames += o.frames, samples += o.samples;
    return *this;
  }
};

class SampleRunner {
 public:
  // `anatomies` may be shared by several runners (one per job)
  SampleRunner(const DatasetSpec& spec, std::shared_ptr<AnatomyCache> anatomies);
  ~SampleRunner();

  // the sample's frames to `sink`; returns what the sample was (sample.json): its seed, anatomy,
  // drawn values and the scene's effective settings. Throws on any failure (the caller records it)
  nlohmann::json run(const SamplePlan& plan, FrameSink& sink);
  const StageTimes& times() const { return times_; }

 private:
  // this runner's renderer over one anatomy's CT, and the beating background it holds
  struct Renderer {
    std::shared_ptr<const BuiltAnatomy> anatomy;
    std::unique_ptr<xray::FluoroscopyRenderer> renderer;
    std::string renderer_key, beat_key;      // what the renderer and its beating background were built for
    std::shared_ptr<const SharedBeat> beat;  // held while the background is this beat (BeatCache)
  };
  Renderer& renderer_for(std::shared_ptr<const BuiltAnatomy> anatomy);

  const DatasetSpec& spec_;
  std::shared_ptr<AnatomyCache> anatomies_;
  std::vector<std::unique_ptr<Renderer>> renderers_;  // the most recently used last
  VesselLabeler labeler_;
  anatomy::VesselTree moved_tree_;  // the tree where the heart has carried it (the tip's branch)
  std::string moved_tree_of_;       // the anatomy moved_tree_ was copied from
  std::vector<double> point_opacity_;
  xray::FluoroFrame frame_;
  StageTimes times_;
};

}  // namespace pcisim::dataset
