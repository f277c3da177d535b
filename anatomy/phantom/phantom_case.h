#pragma once
// The built-in phantom as a case: the seeded coronary tree, its lofted lumen and, on request, the
// thorax CT around it. What `pcisim-server --write-case` writes.
#include <array>
#include <cstdint>

#include "anatomy/case/case.h"
#include "anatomy/vessel/lumen_mesh.h"

namespace pcisim::anatomy {

struct PhantomCaseSpec {
  uint32_t seed = 1;  // the coronary tree's seed
  bool with_ct = true;
  uint32_t ct_seed = 1;  // the thorax's seed
  std::array<int64_t, 3> ct_dims{256, 256, 128};
  double ct_spacing_mm = 1.4;
  bool ct_contrast = false;  // iodine in the coronary lumens (a CTA)
  LumenMeshSpec lumen;       // the loft of the lumen surface
};

// the lumen is rounded to float millimetres (what lumen.stl stores), so the case reads back
// exactly as built
Case make_phantom_case(const PhantomCaseSpec& spec);

// the landmarks the phantom names: its heart centre (the origin), each branch's ostium (first
// point) and end
std::vector<Landmark> phantom_landmarks(const VesselTree& tree);

}  // namespace pcisim::anatomy
