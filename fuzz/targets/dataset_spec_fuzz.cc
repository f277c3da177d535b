// libFuzzer: a dataset spec's text through its parser (dataset/spec: every key, every varied value
// tried against the base scene at its extremes). Only the parse: no sample runs, and the up-front
// checks of what the spec names (dataset/run/input_checks.h) are not made. Paths resolve against a
// folder that does not exist. A refusal is a json::JsonError naming the key; anything else (another
// exception, a crash, a hang, UB, a leak) is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "dataset/spec/dataset_spec.h"
#include "json/json_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    (void)pcisim::dataset::parse_dataset_spec(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json",
                                              "/nonexistent-pcisim-fuzz");
  } catch (const pcisim::json::JsonError&) {}
  return 0;
}
