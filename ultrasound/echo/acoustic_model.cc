#include "ultrasound/echo/acoustic_model.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <numbers>

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
constexpr Knot kScatter[] = {{-1000, 0.0}, {-100, 1.5}, {0, 0.05}, {30, 0.15}, {60, 0.8}, {150, 1.0}};
constexpr Knot kAttenuation[] = {{-100, 1.1}, {-30, 1.1}, {0, 0.02},          {15, 0.02},
                                 {30, 1.0},   {300, 1.0}, {1000, 20.0 / 0.54}};
constexpr double kBackscatterScale = 1e-4;

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

double attenuation_factor(double hu) {
  return piecewise(kAttenuation, hu);
}

double backscatter(double hu) {
  return kBackscatterScale * piecewise(kScatter, hu);
}

namespace {

// the scatterers' table: Box-Muller on a fixed sequence, then its mean taken out and its mean
// power made 1
const std::array<Cf, kScatterers>& table_of_scatterers() {
  static const std::array<Cf, kScatterers> table = [] {
    std::array<std::complex<double>, kScatterers> a{};
    std::complex<double> mean = 0.0;
    for (size_t n = 0; n < a.size(); ++n) {
      const uint64_t h = splitmix64(0x5ca77e25ull + 2 * n), g = splitmix64(0x5ca77e25ull + 2 * n + 1);
      const double u = (static_cast<double>(h >> 11) + 1.0) * 0x1.0p-53;       // (0, 1]
      const double v = static_cast<double>(g >> 11) * 0x1.0p-53;               // [0, 1)
      a[n] = std::polar(std::sqrt(-std::log(u)), 2.0 * std::numbers::pi * v);  // E|a|^2 = 1
      mean += a[n];
    }
    mean /= static_cast<double>(a.size());
    double power = 0.0;
    for (auto& x : a) {
      x -= mean;
      power += std::norm(x);
    }
    const double scale = 1.0 / std::sqrt(power / static_cast<double>(a.size()));
    std::array<Cf, kScatterers> out{};
    for (size_t n = 0; n < a.size(); ++n) {
      const auto x = std::complex<float>(a[n] * scale);
      out[n] = {x.real(), x.imag()};
    }
    return out;
  }();
  return table;
}

}  // namespace

const Cf* scatterer_table() {
  return table_of_scatterers().data();
}

std::complex<float> scatterer(uint64_t seed, int64_t i, int64_t j, int64_t k) {
  const uint64_t h = splitmix64(splitmix64(seed) ^ (static_cast<uint64_t>(i) * kCellI) ^
                                (static_cast<uint64_t>(j) * kCellJ) ^ (static_cast<uint64_t>(k) * kCellK));
  const Cf a = scatterer_table()[h & (kScatterers - 1)];
  return {a.re, a.im};
}

std::complex<float> scatterer_field(uint64_t seed, const double (&u)[3]) {
  ScattererCell cell;
  return scatterer_field(seed, u, &cell);
}

std::complex<float> scatterer_field(uint64_t seed, const double (&u)[3], ScattererCell* cell) {
  const Cf v = scatterer_field(scatterer_table(), splitmix64(seed), u, cell);
  return {v.re, v.im};
}

}  // namespace pcisim::ultrasound
