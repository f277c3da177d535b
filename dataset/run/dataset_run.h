#pragma once
// Makes a dataset, or one shard of it: every sample this shard owns that is neither made nor
// recorded as failed, in order, with a progress line (samples, frames/s, ETA) at most once a
// second. A failing sample is recorded (seed, error) and the run goes on; a full disk, a folder
// that cannot be written or no memory stops the run (the sample in progress removed) and says so; SIGINT/SIGTERM finish
// the current sample and stop. Any of these resumes with the same command. With jobs > 1 samples are made in parallel
// and listed in the order they finish (the merge sorts them).
#include <atomic>
#include <cstdint>
#include <ostream>
#include <string>

#include "dataset/run/dataset_folder.h"
#include "dataset/sample/sample_runner.h"
#include "dataset/spec/dataset_spec.h"

namespace pcisim::dataset {

struct RunOptions {
  std::string out_dir;
  Shard shard;
  int64_t max_samples = -1;  // stop after making this many (-1: all the shard owns)
  // samples made at once, each by its own runner on its own thread (the same bytes whatever the
  // count: a sample depends on its plan alone); the anatomies are shared, the renderers not
  int jobs = 1;
  const std::atomic<bool>* stop = nullptr;  // set (by a signal handler) to stop after the sample in progress
};

struct RunReport {
  int64_t made = 0, failed = 0, resumed = 0;  // this run; resumed: found done or failed before
  int64_t frames = 0;
  double wall_s = 0;
  StageTimes times;
  bool disk_full = false, interrupted = false;
  std::string disk_full_what;
  std::string stop_error;  // why the run stopped early (the folder cannot be written, no memory), "" when it did not
  int64_t remaining = 0;   // samples of this shard not made or failed yet
};

RunReport run_dataset(const DatasetSpec& spec, const RunOptions& options, std::ostream& progress);

}  // namespace pcisim::dataset
