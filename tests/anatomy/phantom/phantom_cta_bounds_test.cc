// make_phantom_cta refuses, before allocating anything, a spec outside its bounds
// (phantom_cta.h): a CT the size of a building or of an atom once ran out of memory
// (std::bad_alloc after 35 s and 4.2 GB, or "cannot create std::vector larger than max_size()").
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "anatomy/phantom/phantom_cta.h"

namespace pcisim::anatomy {
namespace {

// the message make_phantom_cta refuses `s` with, "" when it does not throw std::invalid_argument
std::string refusal(const PhantomCtaSpec& s) {
  try {
    make_phantom_cta(s);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

PhantomCtaSpec tiny() {
  PhantomCtaSpec s;
  s.dims = {64, 64, 64};
  s.spacing_mm = {1, 1, 1};
  return s;
}

TEST(PhantomCtaBounds, TooManyVoxelsAreRefusedNamingTheDims) {
  PhantomCtaSpec s = tiny();
  s.dims = {2048, 2048, 2048};
  s.spacing_mm = {0.4, 0.4, 0.4};
  EXPECT_EQ(refusal(s), "PhantomCtaSpec.dims: expected at most 268435456 voxels, got 2048 x 2048 x 2048 = 8589934592");
  s.dims = {64, 5000, 64};
  EXPECT_EQ(refusal(s), "PhantomCtaSpec.dims: expected 1..4096 voxels along y, got 5000");
}

TEST(PhantomCtaBounds, AVoxelOutsideACtsIsRefused) {
  PhantomCtaSpec s = tiny();
  s.spacing_mm = {1e9, 1e9, 1e9};
  EXPECT_EQ(refusal(s), "PhantomCtaSpec.spacing_mm: expected 0.1 to 20 mm along x, got 1000000000");
  s.spacing_mm = {1, 1, 1e-9};
  EXPECT_EQ(refusal(s), "PhantomCtaSpec.spacing_mm: expected 0.1 to 20 mm along z, got 1e-09");
}

TEST(PhantomCtaBounds, AFieldOfViewOverAMetreIsRefused) {
  PhantomCtaSpec s = tiny();
  s.dims = {4000, 16, 16};
  s.spacing_mm = {0.5, 1, 1};
  EXPECT_EQ(refusal(s),
            "PhantomCtaSpec.dims x spacing_mm: expected a field of view of at most 1000 mm along x, got 4000 x 0.5 = "
            "2000 mm");
}

TEST(PhantomCtaBounds, ABlurOrThreadCountWithoutBoundIsRefused) {
  PhantomCtaSpec s = tiny();
  s.blur_sigma_mm = 1e6;  // a kernel of millions of taps per voxel
  EXPECT_EQ(refusal(s), "PhantomCtaSpec.blur_sigma_mm: expected 0 to 5 mm, got 1000000");
  s = tiny();
  s.threads = 1'000'000;
  EXPECT_EQ(refusal(s), "PhantomCtaSpec.threads: expected 0..256 (0: every core), got 1000000");
}

}  // namespace
}  // namespace pcisim::anatomy
