#pragma once
// Per-link chain-mail limits: the spatially varying wire (stiff body, soft pre-bent tip).
#include <vector>

#include "physics/guidewire/guidewire_params.h"

namespace pcisim::physics {

struct LinkSpec {
  double rest_m = 0.0;                                    // rest length
  double length_min_m = 0.0, length_max_m = 0.0;          // alpha_min, alpha_max times rest (eqs 2-4)
  double beta_rad = 0.0, cos_beta = 1.0;                  // largest bend away from the rest direction
  double bend_rad = 0.0, cos_bend = 1.0, sin_bend = 0.0;  // rest angle to the previous link
  bool tip = false;                                       // in the soft shaped tip
};

// throws std::invalid_argument naming the field ("guidewire.segment_count: ...") when a
// parameter is out of its range
void validate(const GuidewireParams& p);

// links from proximal (index 0) to distal; the tip's pre-bend is spread over its links
std::vector<LinkSpec> make_link_specs(const GuidewireParams& p);

}  // namespace pcisim::physics
