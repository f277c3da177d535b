#pragma once
// The anatomies a dataset's samples run on, built once and shared by every job: the case (its
// CT, vessels and heart), the wall-contact field around its vessels and the X-ray background CT. Both are read-only
// once built. A job asking for one another job is building waits for it. The most recently used few are kept (a phantom
// case with its field is ~100 MB).
#include <Eigen/Core>
#include <future>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "anatomy/case/case.h"
#include "dataset/sample/sample_plan.h"
#include "physics/guidewire/lumen_query.h"

namespace pcisim::dataset {

struct BuiltAnatomy {
  std::string key;
  std::shared_ptr<const anatomy::Case> c;
  std::shared_ptr<const physics::LumenQuery> lumen;  // null without vessel_contact
  std::vector<Eigen::Vector3d> rest_points_m;        // the centerline at rest, tree order
  std::vector<std::string> branch_names;
  // the CT the fluoroscopy projects (the case's, or the thorax phantom around its vessels); each
  // job's renderer takes a copy: generating the phantom costs far more than copying it
  anatomy::Volume background;
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
