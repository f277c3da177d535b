#include "anatomy/phantom/phantom_case.h"

#include <fmt/format.h>

#include "anatomy/mesh/mesh_io.h"
#include "anatomy/phantom/coronary_phantom.h"
#include "anatomy/phantom/thorax_phantom.h"

namespace pcisim::anatomy {

std::vector<Landmark> phantom_landmarks(const VesselTree& tree) {
  // the phantom's heart is centred on the origin by construction (coronary_phantom.h)
  std::vector<Landmark> out{{"heart centre", Eigen::Vector3d::Zero()}};
  for (const auto& b : tree.branches) {
    if (b.points.empty()) continue;
    out.push_back({b.name + " ostium", b.points.front().position_m});
    out.push_back({b.name + " end", b.points.back().position_m});
  }
  return out;
}

Case make_phantom_case(const PhantomCaseSpec& spec) {
  Case c;
  c.name = fmt::format("phantom seed {}", spec.seed);
  c.vessels = make_coronary_phantom({.seed = spec.seed});
  c.lumen = loft_lumen(c.vessels, spec.lumen);
  round_to_float_mm(c.lumen);
  c.landmarks = phantom_landmarks(c.vessels);
  if (spec.with_ct) {
    ThoraxPhantomSpec t;
    t.seed = spec.ct_seed;
    t.dims = spec.ct_dims;
    t.spacing_mm = spec.ct_spacing_mm;
    t.contrast = spec.ct_contrast;
    c.ct = make_thorax_phantom(t, c.vessels);
    c.ct_lumen_enhanced = spec.ct_contrast;
  }
  return c;
}

}  // namespace pcisim::anatomy
