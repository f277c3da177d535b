#include "dataset/sample/instrument_driver.h"

#include <algorithm>
#include <numbers>
#include <stdexcept>

namespace pcisim::dataset {

InstrumentDriver::InstrumentDriver(const DriverSpec& spec, SampleRng rng, const std::string& script)
    : spec_(spec), rng_(rng) {
  if (spec.kind == DriverSpec::Kind::kScript) {
#if defined(PCISIM_DATASET_HAVE_SCRIPTS)
    script_ = std::make_unique<clients::TraineeScript>(
        script == "builtin" ? clients::TraineeScript::parse(clients::TraineeScript::builtin_text(), "builtin")
                            : clients::TraineeScript::load(script));
#else
    throw std::runtime_error("driver.kind \"script\": this build has no trainee script reader (built without LCM)");
#endif
  }
}

physics::InstrumentInput InstrumentDriver::at(double t_s) {
  physics::InstrumentInput in;
#if defined(PCISIM_DATASET_HAVE_SCRIPTS)
  if (script_) {
    const clients::InstrumentReading r = script_->sample(t_s);
    in.insertion_m = 1e-3 * r.insertion_mm;
    in.rotation_rad = r.rotation_rad;
    in.insertion_rate_m_per_s = 1e-3 * r.insertion_rate_mm_s;
    in.rotation_rate_rad_per_s = r.rotation_rate_rad_s;
    return in;
  }
#endif
  // integrate the held rates up to t_s, drawing new ones at each hold boundary; the insertion
  // stays within [0, max] (the rate reads 0 while pinned there)
  while (last_t_s_ < t_s) {
    if (hold_start_s_ < 0 || last_t_s_ >= hold_start_s_ + spec_.hold_s) {
      hold_start_s_ = hold_start_s_ < 0 ? 0 : hold_start_s_ + spec_.hold_s;
      insert_rate_mm_s_ = spec_.insert_rate_mm_s.draw_number(rng_);
      rotate_rate_deg_s_ = spec_.rotate_rate_deg_s.draw_number(rng_);
    }
    const double until = std::min(t_s, hold_start_s_ + spec_.hold_s);
    const double dt = until - last_t_s_;
    insertion_mm_ = std::clamp(insertion_mm_ + insert_rate_mm_s_ * dt, 0.0, spec_.max_insertion_mm);
    rotation_deg_ += rotate_rate_deg_s_ * dt;
    last_t_s_ = until;
  }
  const bool pinned = (insertion_mm_ <= 0 && insert_rate_mm_s_ < 0) ||
                      (insertion_mm_ >= spec_.max_insertion_mm && insert_rate_mm_s_ > 0);
  in.insertion_m = 1e-3 * insertion_mm_;
  in.rotation_rad = rotation_deg_ * std::numbers::pi / 180;
  in.insertion_rate_m_per_s = pinned ? 0.0 : 1e-3 * insert_rate_mm_s_;
  in.rotation_rate_rad_per_s = rotate_rate_deg_s_ * std::numbers::pi / 180;
  return in;
}

}  // namespace pcisim::dataset
