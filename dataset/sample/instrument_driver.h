#pragma once
// The hand on the wire during a sample, not paced to any clock: a seeded random walk of
// insertion and twist rates, or a trainee script (clients/bridge/trainee_script.h) read at the
// step's time. Asked at increasing times only.
#include <memory>

#if defined(PCISIM_DATASET_HAVE_SCRIPTS)
#include "clients/bridge/trainee_script.h"
#endif
#include "dataset/spec/dataset_spec.h"
#include "dataset/spec/sample_rng.h"
#include "physics/instrument_input.h"

namespace pcisim::dataset {

class InstrumentDriver {
 public:
  // a random walk from `rng` (the sample's driver stream), or the script at `script` ("builtin"
  // or a path; throws std::runtime_error naming a bad script, or when this build has no script
  // reader: built without the clients, as on the GPU machine)
  InstrumentDriver(const DriverSpec& spec, SampleRng rng, const std::string& script);
  // the instrument at t_s (>= the last call's)
  physics::InstrumentInput at(double t_s);

 private:
  DriverSpec spec_;
  SampleRng rng_;
#if defined(PCISIM_DATASET_HAVE_SCRIPTS)
  std::unique_ptr<clients::TraineeScript> script_;
#endif
  // the walk: rates held over [hold_start_s, hold_start_s + hold_s), state at last_t_s
  double hold_start_s_ = -1, last_t_s_ = 0;
  double insert_rate_mm_s_ = 0, rotate_rate_deg_s_ = 0;
  double insertion_mm_ = 0, rotation_deg_ = 0;
};

}  // namespace pcisim::dataset
