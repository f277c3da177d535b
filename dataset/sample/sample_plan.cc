#include "dataset/sample/sample_plan.h"

#include <fmt/format.h>

#include "json/json_reader.h"
#include "xray/projectors/cuda_projector.h"
#ifdef PCISIM_HAVE_OSMESA
#include "xray/projectors/gl/gl_projector.h"
#endif

namespace pcisim::dataset {

// the sample's independent random streams (sample_rng.h)
enum Stream : uint64_t { kParams = 0, kSeed = 1 };  // kDriverStream = 2: sample_plan.h

bool gpu_projector_available() {
  static const bool available = [] {
#if defined(PCISIM_HAVE_CUDA)
    return xray::CudaTrilinearProjector::available();
#else
    return false;
#endif
  }();
  return available;
}

xray::ProjectorKind sample_projector(const DatasetSpec& spec, xray::ProjectorKind scene_kind) {
  if (spec.projector == "cpu") return xray::ProjectorKind::kCpuTrilinear;
  if (spec.projector == "exact") return xray::ProjectorKind::kExact;
  if (spec.projector == "cuda") return xray::ProjectorKind::kCudaTrilinear;
  if (spec.projector == "auto" && gpu_projector_available()) return xray::ProjectorKind::kCudaTrilinear;
  return scene_kind;
}

std::string projector_problem(xray::ProjectorKind kind) {
  std::string why;
  switch (kind) {
    case xray::ProjectorKind::kExact:
    case xray::ProjectorKind::kCpuTrilinear:
      return "";
    case xray::ProjectorKind::kCudaTrilinear:
#if defined(PCISIM_HAVE_CUDA)
      if (xray::CudaTrilinearProjector::available(&why)) return "";
      return "no GPU: " + why;
#else
      return "this build has no CUDA";
#endif
    case xray::ProjectorKind::kGl:
#if defined(PCISIM_HAVE_OSMESA)
      if (xray::gl_projector_available(&why)) return "";
      return "no GL context can be made (" + why + ")";
#else
      return "this build has no OSMesa";
#endif
  }
  return "an unknown projector";
}

SamplePlan plan_sample(const DatasetSpec& spec, int64_t index) {
  SamplePlan p;
  p.index = index;
  p.seed = SampleRng::for_sample(spec.seed, static_cast<uint64_t>(index), kSeed).next() >> 33;
  SampleRng rng = SampleRng::for_sample(spec.seed, static_cast<uint64_t>(index), kParams);
  std::vector<std::pair<std::string, nlohmann::json>> overrides;

  // anatomy: one of the phantom seeds or case folders, each equally likely
  const size_t choices = spec.anatomy.phantom_seeds.size() + spec.anatomy.cases.size();
  if (choices > 0) {
    const auto k = static_cast<size_t>(rng.integer(0, static_cast<int64_t>(choices) - 1));
    if (k < spec.anatomy.phantom_seeds.size()) {
      const uint32_t seed = spec.anatomy.phantom_seeds[k];
      overrides.push_back({"anatomy", {{"phantom_seed", seed}}});
      p.drawn["anatomy"] = {{"phantom_seed", seed}};
    } else {
      const std::string& dir = spec.anatomy.cases[k - spec.anatomy.phantom_seeds.size()];
      overrides.push_back({"anatomy", {{"case", dir}}});
      p.drawn["anatomy"] = {{"case", dir}};
    }
  }
  // the scene's values, in the spec's order
  for (const auto& v : spec.vary) {
    nlohmann::json x = v.distribution.draw(rng);
    p.drawn["vary"][v.path] = x;
    overrides.push_back({v.path, std::move(x)});
  }
  p.warmup_s = spec.warmup_s.draw_number(rng);
  p.drawn["warmup_s"] = p.warmup_s;
  p.injection = rng.uniform01() < spec.contrast.probability;
  const double start_after_first_frame_s = spec.contrast.start_s.draw_number(rng);
  p.injection_start_s = p.warmup_s + start_after_first_frame_s;
  if (p.injection) p.drawn["contrast_start_s"] = start_after_first_frame_s;
  if (spec.driver.kind == DriverSpec::Kind::kScript) {
    p.script =
        spec.driver.scripts[static_cast<size_t>(rng.integer(0, static_cast<int64_t>(spec.driver.scripts.size()) - 1))];
    p.drawn["script"] = p.script;
  }

  p.scene_doc = scene_document(spec, overrides);
  p.scene = server::parse_scene(p.scene_doc.dump(), spec.scene_source);
  if (!p.scene.xray) throw json::JsonError("the scene has no effect \"xray\"");
  p.anatomy = p.scene.case_dir.empty() ? fmt::format("phantom_seed {}", p.scene.world.anatomy.seed) : p.scene.case_dir;

  // the projector: the spec's choice over the scene's
  auto& kind = p.scene.xray->fluoro.projector.projector;
  kind = sample_projector(spec, kind);
  p.gpu_projector = kind == xray::ProjectorKind::kCudaTrilinear;
  return p;
}

}  // namespace pcisim::dataset
