// The test suite's shared contact field (tests/common/shared_lumen.h) is the field a World builds
// itself: the same distances and normals everywhere, built once per process.
#include "tests/common/shared_lumen.h"

#include <gtest/gtest.h>

#include <random>
#include <utility>

#include "anatomy/phantom/coronary_phantom.h"
#include "physics/guidewire/sdf_lumen.h"

namespace pcisim::physics {
namespace {

TEST(SharedLumen, IsTheFieldTheWorldBuildsAndIsBuiltOnce) {
  // 0.6 mm: the same code as the scenes' 0.2 mm at a ninth of the cost
  const auto tree = anatomy::make_coronary_phantom(anatomy::CoronaryPhantomSpec{3});
  const double spacing_m = 0.6e-3;
  const SdfLumen own(tree, spacing_m);
  const auto before = test::shared_lumen_counts();
  const auto shared = test::shared_lumen(tree, spacing_m);
  const auto after = test::shared_lumen_counts();
  EXPECT_EQ((after.built + after.read) - (before.built + before.read), 1) << "built here or read from disk";
  EXPECT_EQ(test::shared_lumen(tree, spacing_m), shared) << "the second call is the same field";
  EXPECT_EQ(test::shared_lumen_counts().reused, after.reused + 1);
  EXPECT_NE(test::shared_lumen(tree, 0.7e-3), shared) << "another spacing is another field";

  // and the field as the other test processes read it: from the file, not from this process
  SignedDistanceField stored;
  ASSERT_TRUE(test::read_stored_field(tree, spacing_m, &stored)) << "the shared field was stored";
  const SdfLumen from_disk(tree, std::move(stored));

  // samples near the wall (inside the band) and far from it, around every branch
  std::mt19937 rng(7);
  std::normal_distribution<double> jitter(0.0, 1.5e-3);
  int compared = 0;
  for (const auto& b : tree.branches) {
    for (const auto& p : b.points) {
      const Eigen::Vector3d q = p.position_m + Eigen::Vector3d(jitter(rng), jitter(rng), jitter(rng));
      const WallSample a = own.sample(q), c = shared->sample(q), d = from_disk.sample(q);
      ASSERT_EQ(a.distance_m, c.distance_m) << "branch " << b.name;
      ASSERT_EQ(a.normal, c.normal) << "branch " << b.name;
      ASSERT_EQ(a.distance_m, d.distance_m) << "branch " << b.name << ", read from the file";
      ASSERT_EQ(a.normal, d.normal) << "branch " << b.name << ", read from the file";
      ++compared;
    }
  }
  EXPECT_GT(compared, 500);
}

}  // namespace
}  // namespace pcisim::physics
