#pragma once
// Everything a sample draws, from (spec, sample index) alone: the same plan on any shard, any
// machine, any run. The scene comes out of the base scene with the drawn values set and parsed
// by the scene loader, so every range is the scene's own.
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "dataset/spec/dataset_spec.h"
#include "server/scene/scene.h"

namespace pcisim::dataset {

struct SamplePlan {
  int64_t index = 0;
  uint64_t seed = 0;         // the sample's seed (its detector noise), printed with failures
  server::Scene scene;       // the base scene with this sample's values
  nlohmann::json scene_doc;  // the same as JSON (written beside the sample: it reruns it)
  std::string anatomy;       // "phantom_seed N" or the case folder: what the sample runs on
  nlohmann::json drawn;      // every drawn value by its spec key, for the labels
  double warmup_s = 0;       // simulated before the first frame
  bool injection = false;    // one contrast injection, starting at injection_start_s (simulation time)
  double injection_start_s = 0;
  std::string script;          // the trainee script drawn (driver kind script): "builtin" or a path
  bool gpu_projector = false;  // the background is projected by CUDA
};

// the random stream of the sample's instrument driver (sample_rng.h)
inline constexpr uint64_t kDriverStream = 2;

// throws json::JsonError when the drawn scene is refused (a combination the extremes did not
// cover, say sad_mm above a drawn sid_mm): the sample is then recorded as failed
SamplePlan plan_sample(const DatasetSpec& spec, int64_t index);

// whether "auto" finds a GPU (this build has CUDA and a device answers); asked once
bool gpu_projector_available();

// the projector a sample renders with: the spec's "projector" over the scene's (`scene_kind`)
xray::ProjectorKind sample_projector(const DatasetSpec& spec, xray::ProjectorKind scene_kind);

// "" when `kind` can run on this machine, else why not (no CUDA in this build, no GPU answers, no
// GL context): a cheap probe, nothing rendered
std::string projector_problem(xray::ProjectorKind kind);

}  // namespace pcisim::dataset
