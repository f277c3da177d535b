#pragma once
// Plain 3-vectors and 3x3 matrices that compile for both the host and a CUDA device: the
// CUDA Jacobi solver's arithmetic (device_constraints.h, device_rotation.h) is written once on
// these, so its CPU twin can be tested here without a GPU. Eigen stays on the host side.
#include <cmath>

#ifdef __CUDACC__
#define PCISIM_HD __host__ __device__
#else
#define PCISIM_HD
#endif

namespace pcisim::physics::pbd::device {

struct Vec3 {
  double x = 0.0, y = 0.0, z = 0.0;
};

PCISIM_HD inline Vec3 operator+(Vec3 a, Vec3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
PCISIM_HD inline Vec3 operator-(Vec3 a, Vec3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
PCISIM_HD inline Vec3 operator*(double s, Vec3 a) {
  return {s * a.x, s * a.y, s * a.z};
}
PCISIM_HD inline Vec3 operator/(Vec3 a, double s) {
  return {a.x / s, a.y / s, a.z / s};
}
PCISIM_HD inline Vec3& operator+=(Vec3& a, Vec3 b) {
  return a = a + b;
}
PCISIM_HD inline double dot(Vec3 a, Vec3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
PCISIM_HD inline double squared_norm(Vec3 a) {
  return dot(a, a);
}
PCISIM_HD inline double norm(Vec3 a) {
  return std::sqrt(squared_norm(a));
}
PCISIM_HD inline Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
PCISIM_HD inline bool finite(Vec3 a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}

// column-major like Eigen: m[3 * col + row]
struct Mat3 {
  double m[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  PCISIM_HD double& operator()(int row, int col) { return m[3 * col + row]; }
  PCISIM_HD double operator()(int row, int col) const { return m[3 * col + row]; }
  PCISIM_HD Vec3 col(int c) const { return {m[3 * c], m[3 * c + 1], m[3 * c + 2]}; }
  PCISIM_HD void set_col(int c, Vec3 v) { m[3 * c] = v.x, m[3 * c + 1] = v.y, m[3 * c + 2] = v.z; }
};

PCISIM_HD inline Vec3 operator*(const Mat3& a, Vec3 v) {
  return v.x * a.col(0) + v.y * a.col(1) + v.z * a.col(2);
}
PCISIM_HD inline bool finite(const Mat3& a) {
  for (double v : a.m)
    if (!std::isfinite(v)) return false;
  return true;
}

// 3n doubles laid out x0 y0 z0 x1 ... (Eigen's Matrix3Xd)
PCISIM_HD inline Vec3 load(const double* p, long i) {
  return {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
}
PCISIM_HD inline void store(double* p, long i, Vec3 v) {
  p[3 * i] = v.x, p[3 * i + 1] = v.y, p[3 * i + 2] = v.z;
}

}  // namespace pcisim::physics::pbd::device
