#pragma once
// What a dataset is made of (docs/dataset.md has every key): a base scene, the distributions each
// sample draws from (anatomy, any scene value by its JSON path, the instrument driver, the
// contrast injection, the warm-up) and how many samples of how many frames. Checked like a scene:
// an unknown key or a bad value is refused with its JSON path.
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "dataset/spec/distribution.h"

namespace pcisim::dataset {

// how the wire is moved during a sample
struct DriverSpec {
  enum class Kind { kRandomWalk, kScript };
  Kind kind = Kind::kRandomWalk;
  // kScript: trainee scripts (docs/trainee-script.md), one drawn per sample; "builtin" is the
  // built-in trainee. Paths resolved against the spec's folder
  std::vector<std::string> scripts;
  // kRandomWalk: every hold_s the insertion and rotation rates are drawn afresh; the insertion
  // stays in [0, max_insertion_mm]
  double hold_s = 0.4;
  Distribution insert_rate_mm_s = Distribution::parse({{"uniform", {-2.0, 8.0}}}, "");
  Distribution rotate_rate_deg_s = Distribution::parse({{"uniform", {-90.0, 90.0}}}, "");
  double max_insertion_mm = 70;
};

// one injection per sample, with this probability, starting start_s after the first frame (may
// be negative: the bolus already under way); its volume and length are the scene's
// effects.contrast values (vary them like any other)
struct ContrastDrawSpec {
  double probability = 0.7;
  Distribution start_s = Distribution::parse({{"uniform", {-1.0, 1.0}}}, "");
};

struct LabelSpec {
  // a pixel is in the vessel mask when the iodine's line integral through it, sum of
  // mu_iodine x opacity x chord, is at least this (0.05: the contrast takes >= 4.9 % of the beam)
  double mask_min_line_integral = 0.05;
  int wire_keypoints = 16;             // COCO keypoints along the wire's distal span, tip last
  double wire_keypoint_span_mm = 120;  // that span, measured back from the tip along the wire
};

struct AnatomyDraw {
  // one drawn per sample, each entry equally likely; both empty: the scene's own anatomy
  std::vector<uint32_t> phantom_seeds;
  std::vector<std::string> cases;  // case folders, absolute after parsing
};

// a scene value that varies: its JSON path in the scene ("effects.xray.primary_deg") and how
struct VaryEntry {
  std::string path;
  Distribution distribution;
};

struct DatasetSpec {
  std::string name = "dataset";
  std::string source;  // the spec file, or "(text)"
  std::string text;    // the spec as given (copied into the output folder; a resume must match it)
  int64_t samples = 1;
  int frames_per_sample = 10;
  uint64_t seed = 1;
  std::string scene_source = "built-in";  // "built-in" or the scene file's path
  std::string scene_text;                 // the base scene's text
  // "auto": the CUDA projector when this build has it and a GPU answers, else the scene's;
  // "scene": the scene's; "cpu", "exact", "cuda": that projector
  std::string projector = "auto";
  Distribution warmup_s = Distribution::parse({{"uniform", {1.0, 3.0}}}, "");  // simulated before frame 0
  AnatomyDraw anatomy;
  DriverSpec driver;
  ContrastDrawSpec contrast;
  LabelSpec labels;
  std::vector<VaryEntry> vary;
};

// the values tried against the base scene before any sample (every choice value, both ends of
// every range, over all vary entries): each is a scene parse (~0.1 ms), so a spec is checked in
// well under a second, however long its lists
inline constexpr size_t kMaxVariedValuesTried = 4096;

// throws json::JsonError "<source>: <json path>: <what was expected>". Every vary entry is tried
// at its extremes (both ends of a range, every choice) against the base scene, so a value the
// scene would refuse is named here, before any sample runs. `base_dir` resolves relative paths
DatasetSpec parse_dataset_spec(const std::string& text, const std::string& source, const std::string& base_dir);
DatasetSpec load_dataset_spec(const std::string& path);

// the base scene as JSON with `overrides` (JSON path -> value) set, ready for server::parse_scene;
// throws json::JsonError when a path runs through a value that is not an object
nlohmann::json scene_document(const DatasetSpec& spec,
                              const std::vector<std::pair<std::string, nlohmann::json>>& overrides);

}  // namespace pcisim::dataset
