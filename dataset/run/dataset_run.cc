#include "dataset/run/dataset_run.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <new>
#include <cmath>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "dataset/run/sample_writer.h"
#include "dataset/sample/sample_plan.h"

namespace pcisim::dataset {
namespace {

using Clock = std::chrono::steady_clock;

// anatomies kept besides one per job (sample_runner.cc keeps as many renderers per job)
constexpr size_t kCachedAnatomies = 3;

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
  // this run's list: the shard's samples not made or failed yet, at most max_samples of them
  std::vector<int64_t> todo;
  int64_t owned = 0;
  for (int64_t i = o.shard.index; i < spec.samples; i += o.shard.count) {
    ++owned;
    if (!folder.done().contains(i) && !folder.failed().contains(i)) todo.push_back(i);
  }
  r.resumed = owned - static_cast<int64_t>(todo.size());
  if (o.max_samples >= 0 && static_cast<int64_t>(todo.size()) > o.max_samples)
    todo.resize(static_cast<size_t>(o.max_samples));
  const auto total = static_cast<int64_t>(todo.size());
  const std::string who = o.shard.count > 1 ? fmt::format("shard {}/{}: ", o.shard.index, o.shard.count) : "";
  if (r.resumed > 0)
    progress << fmt::format("pcisim-dataset: {}resuming: {} of {} samples already made or failed\n", who, r.resumed,
                            owned);

  std::mutex mutex;  // guards the folder's lists, the report and the progress stream
  std::atomic<size_t> next{0};
  std::atomic<bool> halt{false};
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
    const double eta = finished > 0 ? wall / finished * static_cast<double>(total - finished) : NAN;
    progress << fmt::format("pcisim-dataset: {}{}/{} samples ({} failed), {} frames, {:.1f} frames/s, ETA {}\n", who,
                            finished, total, r.failed, r.frames, wall > 0 ? r.frames / wall : 0.0,
                            finished >= total ? "done" : duration_text(eta));
    progress.flush();
  };

  // the run stops for what is not a sample's fault: a full disk, a folder it cannot write, no memory
  std::exception_ptr unexpected;
  auto stop_locked = [&](const std::exception& e) {
    if (r.stop_error.empty()) {
      r.disk_full = dynamic_cast<const DiskFull*>(&e) != nullptr;
      r.stop_error = dynamic_cast<const std::bad_alloc*>(&e) ? std::string("out of memory") : std::string(e.what());
      if (r.disk_full) r.disk_full_what = r.stop_error;
    }
    halt.store(true);
  };
  auto stop = [&](int64_t i, const std::exception& e, std::nullptr_t) {
    std::lock_guard lock(mutex);
    folder.abandon_sample(i);
    stop_locked(e);
  };

  // each worker takes the next sample of the list until it is empty or the run must stop
  auto work = [&](SampleRunner& runner) {
    while (true) {
      if (halt.load() || (o.stop && o.stop->load())) return;
      const size_t k = next.fetch_add(1);
      if (k >= todo.size()) return;
      const int64_t i = todo[k];
      uint64_t seed = 0;
      try {
        const SamplePlan plan = plan_sample(spec, i);
        seed = plan.seed;
        std::string dir;
        {
          std::lock_guard lock(mutex);
          dir = folder.begin_sample(i);
        }
        SampleWriter writer(dir);
        const nlohmann::json sample = runner.run(plan, writer);
        writer.finish(sample);
        std::lock_guard lock(mutex);
        folder.commit_sample(i, {{"seed", plan.seed}, {"frames", spec.frames_per_sample}, {"anatomy", plan.anatomy}});
        r.frames += spec.frames_per_sample;
        ++r.made;
        print(false);
      } catch (const WriteError& e) {
        // the folder cannot be written: not this sample's fault, the run stops
        stop(i, e, nullptr);
        return;
      } catch (const std::bad_alloc& e) {
        stop(i, e, nullptr);
        return;
      } catch (const std::exception& e) {
        // the sample itself failed (a scene its draws break, a solver's refusal): recorded, go on
        std::lock_guard lock(mutex);
        folder.abandon_sample(i);
        try {
          folder.record_failure(i, seed, e.what());
        } catch (const std::exception& write) {
          stop_locked(write);
          return;
        }
        progress << fmt::format("pcisim-dataset: {}sample {} (seed {}) failed: {}\n", who, i, seed, e.what());
        ++r.failed;
        print(false);
      } catch (...) {
        std::lock_guard lock(mutex);
        folder.abandon_sample(i);
        if (!unexpected) unexpected = std::current_exception();
        halt.store(true);
        return;
      }
    }
  };
  const int jobs = std::max(1, std::min<int>(o.jobs, static_cast<int>(std::max<int64_t>(1, total))));
  auto anatomies = std::make_shared<AnatomyCache>(kCachedAnatomies + static_cast<size_t>(jobs));
  std::vector<std::unique_ptr<SampleRunner>> runners;
  for (int j = 0; j < jobs; ++j) runners.push_back(std::make_unique<SampleRunner>(spec, anatomies));
  std::vector<std::thread> threads;
  for (int j = 1; j < jobs; ++j) threads.emplace_back(work, std::ref(*runners[j]));
  work(*runners[0]);
  for (auto& t : threads) t.join();
  if (unexpected) std::rethrow_exception(unexpected);
  r.interrupted = r.stop_error.empty() && o.stop && o.stop->load() && next.load() < todo.size();

  print(true);
  r.wall_s = std::chrono::duration<double>(Clock::now() - t_start).count();
  for (const auto& runner : runners) r.times += runner->times();
  r.remaining = owned - static_cast<int64_t>(folder.done().size() + folder.failed().size());
  return r;
}

}  // namespace pcisim::dataset
