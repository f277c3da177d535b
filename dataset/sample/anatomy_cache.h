#pragma once
// The anatomies a dataset's samples run on, built once and shared by every job: the case (its
// CT, vessels and heart), the wall-contact field around its vessels and the X-ray background CT. Both are read-only
// once built. A job asking for one another job is building waits for it. The most recently used few are kept (a phantom
// case with its field is ~100 MB).
#include <Eigen/Core>
#include <functional>
#include <future>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "anatomy/case/case.h"
#include "dataset/sample/sample_plan.h"
#include "physics/guidewire/lumen_query.h"
#include "xray/fluoro/beating_background.h"

namespace pcisim::dataset {

// One anatomy's beating background as its jobs share it, by the beat's key (the heart's and the
// warp's settings: sample_runner.cc): the heart's cycle sampled and every bin's change of the CT.
// The first job to ask makes them, the others wait and share them (with 16 jobs each made its
// own on most samples: a third of a GPU host's labelled-frame time, issue #36). A beat is kept
// only while a job holds it (its renderer's current beat: SampleRunner), so a spec that draws the
// heart rate from a range, every sample its own key, keeps no more than one beat a job. A make
// that throws is forgotten, and the jobs that waited for it make their own (each fails or not
// by itself, as without the cache). The key alone says two beats are the same: the changes are
// checked only for their box (BeatingBackground).
struct SharedBeat {
  xray::BeatSamples samples;
  std::shared_ptr<const xray::BeatChanges> changes;  // null: too large to keep (each job writes its own)
};
class BeatCache {
 public:
  using Kept = std::shared_ptr<const SharedBeat>;
  // the beat a job holds for `key`, or `make`'s (run here: once per key while jobs hold it)
  Kept get(const std::string& key, const std::function<Kept()>& make);

 private:
  struct Entry {
    std::shared_future<Kept> making;  // valid while the first asker makes it
    std::weak_ptr<const SharedBeat> made;
  };
  std::mutex mutex_;
  std::map<std::string, Entry> kept_;
};

struct BuiltAnatomy {
  std::string key;
  std::shared_ptr<const anatomy::Case> c;
  std::shared_ptr<const physics::LumenQuery> lumen;  // null without vessel_contact
  std::vector<Eigen::Vector3d> rest_points_m;        // the centerline at rest, tree order
  std::vector<std::string> branch_names;
  // the CT the fluoroscopy projects (the case's, or the thorax phantom around its vessels); each
  // job's renderer takes a copy: generating the phantom costs far more than copying it
  anatomy::Volume background;
  mutable BeatCache beats;  // its beating backgrounds, shared by the jobs
};

class AnatomyCache {
 public:
  explicit AnatomyCache(size_t capacity) : capacity_(capacity) {}
  // the plan's anatomy (built now, or by another job, or kept); throws what building threw
  std::shared_ptr<const BuiltAnatomy> get(const SamplePlan& plan);

  // the key of a plan's anatomy: the case or phantom, the CT's resolution (a phantom's CT is
  // generated at the scene's X-ray volume settings) and the contact field's spacing
  static std::string key_of(const SamplePlan& plan);

 private:
  struct Slot {
    std::string key;
    std::shared_future<std::shared_ptr<const BuiltAnatomy>> built;
  };
  size_t capacity_;
  std::mutex mutex_;
  std::list<Slot> slots_;  // most recently used first
};

}  // namespace pcisim::dataset
