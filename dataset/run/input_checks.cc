#include "dataset/run/input_checks.h"

#include <fmt/format.h>

#include <exception>
#include <string>
#include <utility>
#include <vector>

#include "dataset/sample/instrument_driver.h"
#include "dataset/sample/sample_plan.h"
#include "json/json_reader.h"
#include "server/case_builder.h"
#include "server/scene/scene.h"

namespace pcisim::dataset {
namespace {

[[noreturn]] void refuse(const DatasetSpec& spec, const std::string& field, const std::string& what) {
  throw json::JsonError(fmt::format("{}: {}: {}", spec.source, field, what));
}

server::Scene scene_with(const DatasetSpec& spec,
                         const std::vector<std::pair<std::string, nlohmann::json>>& overrides) {
  return server::parse_scene(scene_document(spec, overrides).dump(), spec.scene_source);
}

void check_scripts(const DatasetSpec& spec) {
  if (spec.driver.kind != DriverSpec::Kind::kScript) return;
  for (size_t i = 0; i < spec.driver.scripts.size(); ++i) {
    const std::string field = fmt::format("driver.scripts[{}]", i);
    try {
      // the reader every sample uses: a regular file of at most a MiB, parsed whole
      InstrumentDriver driver(spec.driver, SampleRng::for_sample(spec.seed, 0, kDriverStream), spec.driver.scripts[i]);
    } catch (const std::exception& e) {
      refuse(spec, field, e.what());
    }
  }
}

// the projector of the base scene, and of every varied value at its extremes (a vary entry may
// pick the scene's projector), as the spec's "projector" resolves it
void check_projectors(const DatasetSpec& spec) {
  auto check = [&](const server::Scene& scene, const std::string& field) {
    const xray::ProjectorKind scene_kind = scene.xray->fluoro.projector.projector;
    const xray::ProjectorKind kind = sample_projector(spec, scene_kind);
    const std::string problem = projector_problem(kind);
    if (problem.empty()) return;
    if (spec.projector == "cuda" || (spec.projector == "auto" && kind != scene_kind))
      refuse(spec, "projector", fmt::format("\"{}\" cannot run here: {}", spec.projector, problem));
    refuse(spec, field,
           fmt::format("the scene's projector \"{}\" (effects.xray.projector, taken by the spec's projector \"{}\") "
                       "cannot run here: {}; set the spec's \"projector\" to \"cpu\"",
                       xray::projector_name(kind), spec.projector, problem));
  };
  check(scene_with(spec, {}), "scene");
  for (const auto& v : spec.vary) {
    // only a value at effects.xray.projector or an object above it can change the projector
    if (v.path != "effects" && v.path != "effects.xray" && v.path != "effects.xray.projector") continue;
    for (const auto& x : v.distribution.extremes())
      check(scene_with(spec, {{v.path, x}}), "vary." + v.path + " = " + json::short_dump(x));
  }
}

// each case read and checked against the scene, as a sample's build reads it
void check_cases(const DatasetSpec& spec) {
  auto check = [&](const std::string& dir, const std::string& field) {
    try {
      server::Scene scene = scene_with(spec, {{"anatomy", {{"case", dir}}}});
      (void)server::build_case(scene);
    } catch (const std::exception& e) {
      const std::string what = e.what();
      refuse(spec, field, what.find(dir) == std::string::npos ? fmt::format("{}: {}", dir, what) : what);
    }
  };
  for (size_t i = 0; i < spec.anatomy.cases.size(); ++i)
    check(spec.anatomy.cases[i], fmt::format("anatomy.cases[{}]", i));
  // no anatomy drawn: every sample runs on the scene's own, which may be a case folder
  if (spec.anatomy.cases.empty() && spec.anatomy.phantom_seeds.empty()) {
    const server::Scene scene = scene_with(spec, {});
    if (!scene.case_dir.empty()) check(scene.case_dir, "scene: anatomy.case");
  }
}

}  // namespace

void check_spec_inputs(const DatasetSpec& spec) {
  // cheapest first: the scripts, then the projector, then the cases (a CT may take seconds)
  check_scripts(spec);
  check_projectors(spec);
  check_cases(spec);
}

}  // namespace pcisim::dataset
