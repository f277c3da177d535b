#pragma once
// A picture of a case for people: two views side by side, front (AP: patient left on the image's
// right, head up) and side (patient's posterior on the right, head up): the CT as a mean-density
// projection in grey and every vessel branch drawn over it in white at its radius; an organ as its
// outline and its beads as small discs, in white. Written as
// overview.png beside every case folder pcisim writes.
#include <string>

#include "anatomy/case/case.h"

namespace pcisim::anatomy {

// throws std::runtime_error when the file cannot be written
void write_case_overview(const Case& c, const std::string& png_path);

}  // namespace pcisim::anatomy
