#include "dataset/run/dataset_run.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>

#include "dataset/run/sample_writer.h"
#include "dataset/sample/sample_plan.h"

namespace pcisim::dataset {
namespace {

using Clock = std::chrono::steady_clock;

std::string duration_text(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  const auto t = static_cast<int64_t>(std::llround(s));
  if (t >= 3600) return fmt::format("{}h{:02d}m", t / 3600, (t % 3600) / 60);
  if (t >= 60) return fmt::format("{}m{:02d}s", t / 60, t % 60);
  return fmt::format("{}s", t);
}

}  // namespace

RunReport run_dataset(const DatasetSpec& spec, const RunOptions& o, std::ostream& progress) {
  RunReport r;
  DatasetFolder folder(o.out_dir, spec.text, o.shard);
  int64_t owned = 0;
  for (int64_t i = o.shard.index; i < spec.samples; i += o.shard.count) ++owned;
  r.resumed = static_cast<int64_t>(folder.done().size() + folder.failed().size());
  int64_t todo = owned - r.resumed;
  if (o.max_samples >= 0) todo = std::min(todo, o.max_samples);
  const std::string who = o.shard.count > 1 ? fmt::format("shard {}/{}: ", o.shard.index, o.shard.count) : "";
  if (r.resumed > 0)
    progress << fmt::format("pcisim-dataset: {}resuming: {} of {} samples already made or failed\n", who, r.resumed,
                            owned);

  SampleRunner runner(spec);
  const auto t_start = Clock::now();
  auto last_print = t_start - std::chrono::seconds(10);
  int64_t printed_at = -1;  // samples finished at the last line
  auto print = [&](bool force) {
    const auto now = Clock::now();
    if (printed_at == r.made + r.failed || (!force && now - last_print < std::chrono::seconds(1))) return;
    printed_at = r.made + r.failed;
    last_print = now;
    const double wall = std::chrono::duration<double>(now - t_start).count();
    const int64_t finished = r.made + r.failed;
    const double eta = finished > 0 ? wall / finished * static_cast<double>(todo - finished) : NAN;
    progress << fmt::format("pcisim-dataset: {}{}/{} samples ({} failed), {} frames, {:.1f} frames/s, ETA {}\n", who,
                            finished, todo, r.failed, r.frames, wall > 0 ? r.frames / wall : 0.0,
                            finished >= todo ? "done" : duration_text(eta));
    progress.flush();
  };

  for (int64_t i = o.shard.index; i < spec.samples && r.made + r.failed < todo; i += o.shard.count) {
    if (folder.done().contains(i) || folder.failed().contains(i)) continue;
    if (o.stop && o.stop->load()) {
      r.interrupted = true;
      break;
    }
    uint64_t seed = 0;
    try {
      const SamplePlan plan = plan_sample(spec, i);
      seed = plan.seed;
      SampleWriter writer(folder.begin_sample(i));
      const int64_t frames_before = runner.times().frames;
      const nlohmann::json sample = runner.run(plan, writer);
      writer.finish(sample);
      folder.commit_sample(i, {{"seed", plan.seed}, {"frames", spec.frames_per_sample}, {"anatomy", plan.anatomy}});
      r.frames += runner.times().frames - frames_before;
      ++r.made;
    } catch (const DiskFull& e) {
      folder.abandon_sample(i);
      r.disk_full = true;
      r.disk_full_what = e.what();
      break;
    } catch (const std::exception& e) {
      folder.abandon_sample(i);
      try {
        folder.record_failure(i, seed, e.what());
      } catch (const DiskFull& full) {
        r.disk_full = true;
        r.disk_full_what = full.what();
        break;
      }
      progress << fmt::format("pcisim-dataset: {}sample {} (seed {}) failed: {}\n", who, i, seed, e.what());
      ++r.failed;
    }
    print(false);
  }
  print(true);
  r.wall_s = std::chrono::duration<double>(Clock::now() - t_start).count();
  r.times = runner.times();
  r.remaining = owned - static_cast<int64_t>(folder.done().size() + folder.failed().size());
  return r;
}

}  // namespace pcisim::dataset
