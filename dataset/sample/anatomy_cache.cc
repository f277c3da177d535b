#include "dataset/sample/anatomy_cache.h"

#include <fmt/format.h>

#include "physics/guidewire/sdf_lumen.h"
#include "server/case_builder.h"
#include "xray/fluoro/case_background.h"

namespace pcisim::dataset {
namespace {

std::shared_ptr<const BuiltAnatomy> build(const SamplePlan& plan, const std::string& key) {
  auto a = std::make_shared<BuiltAnatomy>();
  a->key = key;
  a->c = server::build_case(plan.scene);
  const auto& w = plan.scene.world;
  if (w.vessel_contact && w.guidewire)
    a->lumen = std::make_shared<const physics::SdfLumen>(a->c->vessels, w.vessel_contact->sdf_spacing_m);
  a->background = xray::background_volume(*a->c, plan.scene.xray->fluoro);
  for (const auto& b : a->c->vessels.branches) {
    a->branch_names.push_back(b.name);
    for (const auto& p : b.points) a->rest_points_m.push_back(p.position_m);
  }
  return a;
}

}  // namespace

std::string AnatomyCache::key_of(const SamplePlan& plan) {
  const auto& f = plan.scene.xray->fluoro;
  const auto& w = plan.scene.world;
  const double sdf_m = w.vessel_contact && w.guidewire ? w.vessel_contact->sdf_spacing_m : 0.0;
  return fmt::format("{}|{}x{}x{}|{}|{}", plan.anatomy, f.volume_dims[0], f.volume_dims[1], f.volume_dims[2],
                     f.volume_spacing_mm, sdf_m);
}

std::shared_ptr<const BuiltAnatomy> AnatomyCache::get(const SamplePlan& plan) {
  const std::string key = key_of(plan);
  std::promise<std::shared_ptr<const BuiltAnatomy>> promise;
  std::shared_future<std::shared_ptr<const BuiltAnatomy>> built;
  bool builder = false;
  {
    std::lock_guard lock(mutex_);
    for (auto it = slots_.begin(); it != slots_.end(); ++it) {
      if (it->key != key) continue;
      slots_.splice(slots_.begin(), slots_, it);  // most recently used first
      built = it->built;
      break;
    }
    if (!built.valid()) {
      builder = true;
      built = promise.get_future().share();
      slots_.push_front({key, built});
      while (slots_.size() > capacity_) slots_.pop_back();
    }
  }
  if (builder) {
    // built outside the lock; a failure reaches every job waiting on it, and is forgotten so a
    // later sample tries again
    try {
      promise.set_value(build(plan, key));
    } catch (...) {
      promise.set_exception(std::current_exception());
      std::lock_guard lock(mutex_);
      slots_.remove_if([&](const Slot& s) { return s.key == key; });
    }
  }
  return built.get();
}

BeatCache::Kept BeatCache::get(const std::string& key, const std::function<Kept()>& make) {
  std::promise<Kept> promise;
  std::shared_future<Kept> making;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    Entry& e = kept_[key];
    if (Kept held = e.made.lock()) return held;
    if (e.making.valid()) {
      making = e.making;
    } else {
      e.making = promise.get_future().share();
    }
  }
  if (making.valid()) {
    // another job's: wait while it makes it; where its make failed, make one here
    try {
      return making.get();
    } catch (...) {
      return get(key, make);
    }
  }
  try {
    Kept beat = make();
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      Entry& e = kept_[key];
      e.made = beat;
      e.making = {};  // (the waiters keep their copies of the future)
    }
    promise.set_value(beat);
    return beat;
  } catch (...) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      kept_.erase(key);  // before the waiters wake: they make their own
    }
    promise.set_exception(std::current_exception());
    throw;
  }
}

}  // namespace pcisim::dataset
