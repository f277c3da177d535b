#include "dataset/spec/dataset_spec.h"

#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "json/json_reader.h"
#include "json/regular_file.h"
#include "server/scene/scene.h"

namespace pcisim::dataset {
namespace {

namespace fs = std::filesystem;

std::string read_text(const std::string& path, const std::string& what, std::uintmax_t max_bytes) {
  try {
    return json::read_regular_file(path, "the " + what, static_cast<int64_t>(max_bytes));
  } catch (const json::FileError& e) {
    throw json::JsonError(e.what());
  }
}

std::string resolve(const std::string& base_dir, const std::string& p) {
  const fs::path path(p);
  return path.is_absolute() || base_dir.empty() ? path.lexically_normal().string()
                                                : (fs::path(base_dir) / path).lexically_normal().string();
}

Distribution distribution(json::JsonReader& r, const std::string& key, const Distribution& fallback, bool numeric,
                          double min, double max) {
  const nlohmann::json* v = r.value(key);
  if (!v) return fallback;
  Distribution d = Distribution::parse(*v, r.path_of(key));
  if (numeric) {
    for (const auto& x : d.extremes()) {
      if (!x.is_number() || x.get<double>() < min || x.get<double>() > max)
        r.fail(key, fmt::format("expected numbers in [{}, {}], got {}", min, max, json::short_dump(x)));
    }
  }
  return d;
}

DriverSpec read_driver(json::JsonReader r) {
  DriverSpec d;
  const std::string kind = r.text("kind", "random_walk", {"random_walk", "script"});
  d.kind = kind == "script" ? DriverSpec::Kind::kScript : DriverSpec::Kind::kRandomWalk;
  if (d.kind == DriverSpec::Kind::kScript) {
    const auto& scripts = r.list("scripts");
    if (scripts.empty()) r.fail("scripts", "expected a list of trainee script files (or \"builtin\")");
    for (const auto& s : scripts) {
      if (!s.is_string() || s.get<std::string>().empty())
        r.fail("scripts", fmt::format("expected file paths or \"builtin\", got {}", json::short_dump(s)));
      d.scripts.push_back(s.get<std::string>());
    }
  } else {
    d.hold_s = r.number("hold_s", d.hold_s, 0.02, 60);
    d.insert_rate_mm_s = distribution(r, "insert_rate_mm_s", d.insert_rate_mm_s, true, -50, 50);
    d.rotate_rate_deg_s = distribution(r, "rotate_rate_deg_s", d.rotate_rate_deg_s, true, -720, 720);
    d.max_insertion_mm = r.number("max_insertion_mm", d.max_insertion_mm, 1, 2000);
  }
  r.finish();
  return d;
}

}  // namespace

nlohmann::json scene_document(const DatasetSpec& spec,
                              const std::vector<std::pair<std::string, nlohmann::json>>& overrides) {
  nlohmann::json doc = json::parse_json_checked(spec.scene_text, spec.scene_source);
  for (const auto& [path, value] : overrides) {
    // walk the dotted path, making objects where they are missing
    nlohmann::json* at = &doc;
    size_t from = 0;
    while (true) {
      const size_t dot = path.find('.', from);
      const std::string key = path.substr(from, dot == std::string::npos ? std::string::npos : dot - from);
      if (!at->is_object())
        throw json::JsonError(fmt::format("{}: the scene has a value that is not an object before \"{}\"", path, key));
      at = &(*at)[key];
      if (dot == std::string::npos) break;
      from = dot + 1;
    }
    *at = value;
  }
  return doc;
}

DatasetSpec parse_dataset_spec(const std::string& text, const std::string& source, const std::string& base_dir) {
  DatasetSpec s;
  s.source = source;
  s.text = text;
  try {
    const nlohmann::json doc = json::parse_json_checked(text, source);
    json::JsonReader r(doc, "");
    s.name = r.text("name", s.name);
    if (s.name.empty() || s.name.find_first_of("/\\\n") != std::string::npos)
      r.fail("name", "expected a short name without slashes");
    s.samples = r.integer("samples", 0, 1, 10'000'000);
    if (!r.has("samples")) r.fail("samples", "expected how many samples to make, 1 to 10000000");
    s.frames_per_sample = r.integer("frames_per_sample", s.frames_per_sample, 1, 10'000);
    s.seed = static_cast<uint64_t>(r.integer("seed", 1, 0, 2'000'000'000));
    const std::string scene = r.text("scene", "built-in");
    if (scene == "built-in") {
      s.scene_source = "built-in";
      s.scene_text = server::default_scene_text();
    } else {
      s.scene_source = resolve(base_dir, scene);
      try {
        s.scene_text = read_text(s.scene_source, "scene file", server::kMaxSceneFileBytes);
      } catch (const json::JsonError& e) {
        r.fail("scene", e.what());
      }
    }
    s.projector = r.text("projector", s.projector, {"auto", "scene", "cpu", "exact", "cuda"});
    s.warmup_s = distribution(r, "warmup_s", s.warmup_s, true, 0, 600);

    json::JsonReader anatomy = r.child("anatomy");
    if (const nlohmann::json* seeds = anatomy.value("phantom_seeds")) {
      const Distribution d = Distribution::parse(*seeds, anatomy.path_of("phantom_seeds"));
      if (d.kind() != Distribution::Kind::kIntegers && d.kind() != Distribution::Kind::kChoice)
        anatomy.fail("phantom_seeds", "expected {\"integers\": [a, b]} or {\"choice\": [seeds]}");
      std::vector<nlohmann::json> all;
      if (d.kind() == Distribution::Kind::kChoice) {
        all = d.extremes();
      } else {
        const auto ends = d.extremes();
        const int64_t a = ends[0].get<int64_t>(), b = ends[1].get<int64_t>();
        if (b - a >= 100'000) anatomy.fail("phantom_seeds", "expected at most 100000 seeds");
        for (int64_t k = a; k <= b; ++k) all.push_back(k);
      }
      for (const auto& v : all) {
        if (!v.is_number_integer() || v.get<int64_t>() < 0 || v.get<int64_t>() > (1 << 30))
          anatomy.fail("phantom_seeds", fmt::format("expected seeds in [0, {}], got {}", 1 << 30, json::short_dump(v)));
        s.anatomy.phantom_seeds.push_back(static_cast<uint32_t>(v.get<int64_t>()));
      }
    }
    for (const auto& c : anatomy.list("cases")) {
      if (!c.is_string()) anatomy.fail("cases", fmt::format("expected case folder paths, got {}", json::short_dump(c)));
      const std::string dir = resolve(base_dir, c.get<std::string>());
      std::error_code ec;
      if (!fs::is_regular_file(fs::path(dir) / "case.json", ec))
        anatomy.fail("cases", fmt::format("{}: not a case folder (no case.json)", dir));
      s.anatomy.cases.push_back(dir);
    }
    anatomy.finish();

    s.driver = read_driver(r.child("driver"));
    for (auto& script : s.driver.scripts)
      if (script != "builtin") script = resolve(base_dir, script);

    json::JsonReader contrast = r.child("contrast");
    s.contrast.probability = contrast.number("probability", s.contrast.probability, 0, 1);
    s.contrast.start_s = distribution(contrast, "start_s", s.contrast.start_s, true, -60, 600);
    contrast.finish();

    json::JsonReader labels = r.child("labels");
    s.labels.mask_min_line_integral =
        labels.number("mask_min_line_integral", s.labels.mask_min_line_integral, 1e-4, 10);
    s.labels.wire_keypoints = labels.integer("wire_keypoints", s.labels.wire_keypoints, 2, 256);
    s.labels.wire_keypoint_span_mm = labels.number("wire_keypoint_span_mm", s.labels.wire_keypoint_span_mm, 1, 2000);
    labels.finish();

    if (const nlohmann::json* vary = r.value("vary")) {
      if (!vary->is_object()) r.fail("vary", "expected an object: scene JSON path -> value or distribution");
      for (const auto& [path, value] : vary->items()) {
        const std::string where = "vary." + path;
        if (path.empty() || path.front() == '.' || path.back() == '.' || path.find("..") != std::string::npos)
          throw json::JsonError(fmt::format("{}: expected a scene JSON path such as effects.xray.primary_deg", where));
        if (path == "anatomy" || path.starts_with("anatomy."))
          throw json::JsonError(fmt::format("{}: the anatomy is drawn by the spec's \"anatomy\" key", where));
        s.vary.push_back({path, Distribution::parse(value, where)});
      }
      size_t tried = 0;
      for (const auto& v : s.vary) tried += v.distribution.extremes().size();
      if (tried > kMaxVariedValuesTried)
        r.fail("vary", fmt::format("expected at most {} values to try against the scene (each choice's values, each "
                                   "range's two ends), got {}",
                                   kMaxVariedValuesTried, tried));
    }
    r.finish();
  } catch (const json::JsonError& e) {
    const std::string what = e.what();
    throw json::JsonError(what.starts_with(source) ? what : fmt::format("{}: {}", source, what));
  }

  // the base scene, then each varied value at its extremes: what the scene would refuse is named now
  auto check = [&](const std::vector<std::pair<std::string, nlohmann::json>>& overrides, const std::string& where) {
    try {
      const server::Scene scene = server::parse_scene(scene_document(s, overrides).dump(), s.scene_source);
      if (!scene.xray)
        throw json::JsonError(fmt::format("{}: effects: a dataset needs effect \"xray\"", s.scene_source));
    } catch (const json::JsonError& e) {
      throw json::JsonError(fmt::format("{}: {}: {}", source, where, e.what()));
    }
  };
  check({}, "scene");
  for (const auto& v : s.vary)
    for (const auto& x : v.distribution.extremes())
      check({{v.path, x}}, "vary." + v.path + " = " + json::short_dump(x));
  return s;
}

DatasetSpec load_dataset_spec(const std::string& path) {
  const std::string text = read_text(path, "dataset spec", 1 << 20);
  return parse_dataset_spec(text, path, fs::path(path).parent_path().string());
}

}  // namespace pcisim::dataset
