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

constexpr size_t kScatterers = 4096;  // a power of two

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
  return piecewise(kAttenuation, hu);
}

double attenuation_db(double alpha_db_cm_mhz, double factor, double frequency_mhz, double dx_cm) {
  return alpha_db_cm_mhz * factor * frequency_mhz * dx_cm;
}

double backscatter(double hu) {
  return kBackscatterScale * piecewise(kScatter, hu);
}

namespace {

// the scatterers' table: Box-Muller on a fixed sequence, then its mean taken out and its mean
// power made 1
const std::array<std::complex<float>, kScatterers>& scatterer_table() {
  static const std::array<std::complex<float>, kScatterers> table = [] {
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
    std::array<std::complex<float>, kScatterers> out{};
    for (size_t n = 0; n < a.size(); ++n) out[n] = std::complex<float>(a[n] * scale);
    return out;
  }();
  return table;
}

// a cell's coordinates, each times an odd constant, mixed once (splitmix64's finaliser
// avalanches every input bit) with the seed's own mix
constexpr uint64_t kCellI = 0x9e3779b97f4a7c15ull, kCellJ = 0xc2b2ae3d27d4eb4full, kCellK = 0x165667b19e3779f9ull;

}  // namespace

std::complex<float> scatterer(uint64_t seed, int64_t i, int64_t j, int64_t k) {
  const uint64_t h = splitmix64(splitmix64(seed) ^ (static_cast<uint64_t>(i) * kCellI) ^
                                (static_cast<uint64_t>(j) * kCellJ) ^ (static_cast<uint64_t>(k) * kCellK));
  return scatterer_table()[h & (kScatterers - 1)];
}

std::complex<float> scatterer_field(uint64_t seed, const double (&u)[3]) {
  ScattererCell cell;
  return scatterer_field(seed, u, &cell);
}

std::complex<float> scatterer_field(uint64_t seed, const double (&u)[3], ScattererCell* cell) {
  // per axis: the cell's lower lattice line and the two lines' weights
  int64_t i0[3];
  float w[3][2];
  for (int a = 0; a < 3; ++a) {
    const double fl = std::floor(u[a]);
    i0[a] = static_cast<int64_t>(fl);
    w[a][1] = static_cast<float>(u[a] - fl);
    w[a][0] = 1.0f - w[a][1];
  }
  if (i0[0] != cell->index[0] || i0[1] != cell->index[1] || i0[2] != cell->index[2]) {
    const auto& table = scatterer_table();
    const uint64_t mixed = splitmix64(seed);
    constexpr uint64_t kAxis[3] = {kCellI, kCellJ, kCellK};
    uint64_t key[3][2];
    // a step to a face neighbour (one axis, by one) keeps the 4 corners of the shared face
    // (differences taken unsigned: the empty cache's INT64_MIN must not overflow)
    int moved = -1, steps = 0;
    bool up = false;
    for (int a = 0; a < 3; ++a) {
      const uint64_t d = static_cast<uint64_t>(i0[a]) - static_cast<uint64_t>(cell->index[a]);
      if (d != 0) moved = (d == 1 || d == ~uint64_t{0}) ? a : 3, up = d == 1, ++steps;
      key[a][0] = static_cast<uint64_t>(i0[a]) * kAxis[a];
      key[a][1] = (static_cast<uint64_t>(i0[a]) + 1) * kAxis[a];
    }
    // moved up along the axis: the new lower face is the old upper one; down: the reverse
    const int bit = steps == 1 && moved < 3 ? 1 << moved : 0;
    const int kept = up ? 0 : bit;
    if (bit)
      for (int corner = 0; corner < 8; ++corner)
        if ((corner & bit) == kept) cell->corner[corner] = cell->corner[corner ^ bit];
    for (int corner = 0; corner < 8; ++corner) {
      if (bit && (corner & bit) == kept) continue;
      const int x = corner & 1, y = corner >> 1 & 1, z = corner >> 2 & 1;
      cell->corner[corner] = table[splitmix64(mixed ^ key[0][x] ^ key[1][y] ^ key[2][z]) & (kScatterers - 1)];
    }
    for (int a = 0; a < 3; ++a) cell->index[a] = i0[a];
  }
  // (real and imaginary parts summed as floats: a complex product is not needed for a real weight)
  float re = 0.0f, im = 0.0f, weight2 = 0.0f;
  for (int corner = 0; corner < 8; ++corner) {
    const int x = corner & 1, y = corner >> 1 & 1, z = corner >> 2 & 1;
    const float wc = w[0][x] * w[1][y] * w[2][z];
    re += wc * cell->corner[corner].real();
    im += wc * cell->corner[corner].imag();
    weight2 += wc * wc;
  }
  const float norm = 1.0f / std::sqrt(weight2);
  return {re * norm, im * norm};
}

double brightness_db(double intensity, double gain_db, double tgc_db_per_cm, double depth_cm) {
  return 10.0 * std::log10(std::max(intensity, 1e-30)) + gain_db + tgc_db_per_cm * depth_cm;
}

uint8_t log_compress(double brightness_db, double dynamic_range_db) {
  const double g = 255.0 * (brightness_db + dynamic_range_db) / dynamic_range_db;
  return static_cast<uint8_t>(std::lround(std::clamp(g, 0.0, 255.0)));
}

}  // namespace pcisim::ultrasound
