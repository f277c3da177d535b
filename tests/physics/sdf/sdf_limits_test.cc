// The field's build is bounded before it allocates: a grid of too many points, or walls whose band
// would store too many, is refused by make_build_plan (the cheap, serial part), not after gigabytes.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "physics/sdf/sdf_build_plan.h"

namespace pcisim::physics::sdf {
namespace {

// a closed cube of side a_m at the origin, faces wound outward (12 large triangles)
anatomy::TriangleMesh cube(double a_m) {
  anatomy::TriangleMesh m;
  for (int k = 0; k < 8; ++k) m.vertices_m.emplace_back(a_m * (k & 1), a_m * ((k >> 1) & 1), a_m * ((k >> 2) & 1));
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

std::string refusal(const anatomy::TriangleMesh& mesh, double spacing_m, double band_m) {
  try {
    make_build_plan(mesh, spacing_m, 0.0, band_m);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

// a 0.6 m lumen at 1 mm with a 100 mm band: 216 M grid points (within kMaxGridPoints) but
// ~152 M in band bricks (the grid without its inner 0.4 m cube; nothing is stored outside the
// grid), a 1.8 GB build; refused while its bricks are listed, in milliseconds
TEST(SdfLimits, AWallBandOfTooManyPointsIsRefusedBeforeThePool) {
  const std::string why = refusal(cube(0.6), 1e-3, 0.1);
  EXPECT_NE(why.find("the walls' band needs more than " + std::to_string(kMaxBandPoints) + " grid points"),
            std::string::npos)
      << why;
  // the same walls with the default band (4 cells) fit
  EXPECT_EQ(refusal(cube(0.6), 1e-3, 0.0), "");
}

TEST(SdfLimits, AGridOfTooManyPointsIsRefused) {
  const std::string why = refusal(cube(2.0), 1e-3, 0.0);  // 8 G points
  EXPECT_NE(why.find("grid too large for spacing 0.001"), std::string::npos) << why;
}

}  // namespace
}  // namespace pcisim::physics::sdf
