#include "physics/pbd/rotation_extraction.h"

#include <algorithm>

#include "physics/pbd/device_rotation.h"

namespace pcisim::physics::pbd {

// the CPU runs the CUDA twin's kernel (device_rotation.h: one-sided Jacobi on the 3 x 3, the
// same regulariser and reflection fix): one source for both paths. It replaced Eigen's
// JacobiSVD, which agreed to 3.7e-15 per entry and was most of a soft-tissue step's time
Eigen::Matrix3d extract_rotation(const Eigen::Matrix3d& a, const Eigen::Matrix3d& previous, double rest_moment_kg_m2) {
  device::Mat3 da, dp;
  std::copy(a.data(), a.data() + 9, da.m);  // both column-major
  std::copy(previous.data(), previous.data() + 9, dp.m);
  const device::Mat3 r = device::extract_rotation(da, dp, rest_moment_kg_m2);
  Eigen::Matrix3d out;
  std::copy(r.m, r.m + 9, out.data());
  return out;
}

Eigen::Matrix3d extract_rotation(const Eigen::Matrix3d& a, const Eigen::Matrix3d& previous, double rest_moment_kg_m2,
                                 Eigen::Matrix3d* right_vectors) {
  device::Mat3 da, dp, dv;
  std::copy(a.data(), a.data() + 9, da.m);
  std::copy(previous.data(), previous.data() + 9, dp.m);
  std::copy(right_vectors->data(), right_vectors->data() + 9, dv.m);
  const device::Mat3 r = device::extract_rotation_from(da, dp, rest_moment_kg_m2, &dv);
  std::copy(dv.m, dv.m + 9, right_vectors->data());
  Eigen::Matrix3d out;
  std::copy(r.m, r.m + 9, out.data());
  return out;
}

}  // namespace pcisim::physics::pbd
