#include "ultrasound/echo/acoustic_model.h"

#include <algorithm>
#include <cmath>
#include <iterator>

namespace pcisim::ultrasound {
namespace {

struct Knot {
  double hu, v;
};

template <size_t N>
double piecewise(const Knot (&k)[N], double hu) {
  if (hu <= k[0].hu) return k[0].v;
  for (size_t i = 1; i < N; ++i)
    if (hu <= k[i].hu) return k[i - 1].v + (k[i].v - k[i - 1].v) * (hu - k[i - 1].hu) / (k[i].hu - k[i - 1].hu);
  return k[N - 1].v;
}

constexpr Knot kSpeed[] = {{-1000, 343}, {-100, 1450}, {0, 1480}, {40, 1540}, {300, 1600}, {1000, 3500}};
constexpr Knot kScatter[] = {{-1000, 0.0}, {-100, 1.5}, {0, 0.05}, {30, 0.5}, {60, 0.8}, {150, 1.0}};
constexpr double kBackscatterScale = 1e-4;

uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

}  // namespace

double density_g_cm3(double hu) {
  return std::max(1.0 + hu / 1000.0, 0.0012);
}

double speed_of_sound_m_s(double hu) {
  return piecewise(kSpeed, hu);
}

double impedance_mrayl(double hu) {
  return density_g_cm3(hu) * speed_of_sound_m_s(hu) * 1e-3;
}

double reflection(double z1, double z2) {
  const double r = (z2 - z1) / (z2 + z1);
  return r * r;
}

double attenuation_factor(double hu) {
  if (hu <= 300.0) return 1.0;
  return 1.0 + (20.0 / 0.54 - 1.0) * (std::min(hu, 1000.0) - 300.0) / 700.0;
}

double attenuation_db(double alpha_db_cm_mhz, double hu, double frequency_mhz, double dx_cm) {
  return alpha_db_cm_mhz * attenuation_factor(hu) * frequency_mhz * dx_cm;
}

double backscatter(double hu) {
  return kBackscatterScale * piecewise(kScatter, hu);
}

double speckle(uint64_t seed, int64_t i, int64_t j, int64_t k) {
  const uint64_t h =
      splitmix64(splitmix64(splitmix64(splitmix64(seed) ^ static_cast<uint64_t>(i)) ^ static_cast<uint64_t>(j)) ^
                 static_cast<uint64_t>(k));
  const double u = (static_cast<double>(h >> 11) + 1.0) * 0x1.0p-53;  // (0, 1]
  return -std::log(u);
}

double brightness_db(double intensity, double gain_db, double tgc_db_per_cm, double depth_cm) {
  return 10.0 * std::log10(std::max(intensity, 1e-30)) + gain_db + tgc_db_per_cm * depth_cm;
}

uint8_t log_compress(double brightness_db, double dynamic_range_db) {
  const double g = 255.0 * (brightness_db + dynamic_range_db) / dynamic_range_db;
  return static_cast<uint8_t>(std::lround(std::clamp(g, 0.0, 255.0)));
}

}  // namespace pcisim::ultrasound
