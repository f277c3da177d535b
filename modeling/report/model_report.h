#pragma once
// model-report.json: what pcisim-model did, for people and for the benchmark. Format
// "pcisim-model-report" version 1: the input (file, size, spacing, direction), the seeds, each
// stage's seconds, figures and notes, the branches (name, parent, length, mean and least radius),
// the total time and the peak memory of the process.
#include <string>
#include <vector>
#include "anatomy/volume/volume.h"
#include "modeling/cta/cta_pipeline.h"

namespace pcisim::modeling {

// the process's peak resident memory so far (VmHWM), MiB; 0 where /proc does not tell
double peak_memory_mib();

void write_model_report(const std::string& path, const std::string& ct_source, const anatomy::Volume& ct,
                        const std::vector<Eigen::Vector3d>& seeds_mm, const CtaModel& model, double total_s);

}  // namespace pcisim::modeling
