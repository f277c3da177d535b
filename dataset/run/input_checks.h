#pragma once
// What a dataset needs besides its spec's text, checked before the first sample (docs/dataset.md,
// "Checked up front"): every trainee script read and parsed, the projector each sample would
// take able to run here (a probe, nothing rendered), every case folder read and fitted to the
// scene. Without this a bad one is accepted and then fails every sample.
#include "dataset/spec/dataset_spec.h"

namespace pcisim::dataset {

// throws json::JsonError "<spec file>: <field>: <what is wrong>", the field as the spec names it
// (driver.scripts[1], projector, vary.effects.xray.projector = "gl", anatomy.cases[0], ...)
void check_spec_inputs(const DatasetSpec& spec);

}  // namespace pcisim::dataset
