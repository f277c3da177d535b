#pragma once
// The echo model's rules that run per sample, written once for the CPU renderer and its CUDA twin
// (render/bmode_kernels.h, render/cuda_bmode.cu): plain numbers and pointers, no Eigen, no
// std::complex. acoustic_model.h gives the same rules to host code; its header names the sources.
#include <algorithm>
#include <cmath>
#include <cstdint>

#ifdef __CUDACC__
#define PCISIM_HD __host__ __device__
#else
#define PCISIM_HD
#endif

namespace pcisim::ultrasound {

// a complex amplitude as two floats (laid out as std::complex<float>)
struct Cf {
  float re = 0.0f, im = 0.0f;
};

// intensity reflection coefficient at normal incidence: R = ((Z2 - Z1) / (Z2 + Z1))^2
PCISIM_HD inline double reflection(double z1, double z2) {
  const double r = (z2 - z1) / (z2 + z1);
  return r * r;
}

// one-way intensity loss (dB) over a path: L = alpha k f dx_cm (alpha the soft tissue's
// coefficient in dB/cm/MHz, k the tissue's factor over it: attenuation_factor(HU), or a tissue
// map's, tissue_acoustics.h)
PCISIM_HD inline double attenuation_db(double alpha_db_cm_mhz, double factor, double frequency_mhz, double dx_cm) {
  return alpha_db_cm_mhz * factor * frequency_mhz * dx_cm;
}

// time-gain compensated, log-compressed brightness (dB): B = 10 log10(I) + gain + tgc d_cm
PCISIM_HD inline double brightness_db(double intensity, double gain_db, double tgc_db_per_cm, double depth_cm) {
  return 10.0 * std::log10(std::max(intensity, 1e-30)) + gain_db + tgc_db_per_cm * depth_cm;
}

// 8-bit grey: g = round(255 (B + DR) / DR), clamped to [0, 255] (0 dB, a perfect reflector at the
// face, is white; -DR is black)
PCISIM_HD inline uint8_t log_compress(double brightness_db, double dynamic_range_db) {
  const double g = 255.0 * (brightness_db + dynamic_range_db) / dynamic_range_db;
  return static_cast<uint8_t>(std::floor(std::clamp(g, 0.0, 255.0) + 0.5));
}

// the scatterers' table size (a power of two) and the hash that picks an entry
constexpr uint64_t kScatterers = 4096;

PCISIM_HD inline uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// a cell's coordinates, each times an odd constant, mixed once (splitmix64's finaliser
// avalanches every input bit) with the seed's own mix, splitmix64(seed)
constexpr uint64_t kCellI = 0x9e3779b97f4a7c15ull, kCellJ = 0xc2b2ae3d27d4eb4full, kCellK = 0x165667b19e3779f9ull;

// the 8 corners' amplitudes of the scatterer lattice cell last looked up, kept between calls: a
// scanline's samples step a fraction of a cell, and most fall in the cell of the one before
struct ScattererCell {
  int64_t index[3] = {INT64_MIN, INT64_MIN, INT64_MIN};
  Cf corner[8];
};

// the tissue's scatterer field at u (a point of the undeformed CT in lattice cells):
//   v(u) = sum_c w_c a_c / sqrt(sum_c w_c^2)
// a_c the table's entry hashed from (seed, the corner's lattice indices), w_c its trilinear weight
// (acoustic_model.h says why). `mixed_seed` is splitmix64(seed); the corners are hashed only when
// u leaves the cached cell, and a step to a face neighbour keeps the 4 shared ones (the result is
// the same bit for bit)
PCISIM_HD inline Cf scatterer_field(const Cf* table, uint64_t mixed_seed, const double (&u)[3], ScattererCell* cell) {
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
    const uint64_t axis[3] = {kCellI, kCellJ, kCellK};
    uint64_t key[3][2];
    // (differences taken unsigned: the empty cache's INT64_MIN must not overflow)
    int moved = -1, steps = 0;
    bool up = false;
    for (int a = 0; a < 3; ++a) {
      const uint64_t d = static_cast<uint64_t>(i0[a]) - static_cast<uint64_t>(cell->index[a]);
      if (d != 0) moved = (d == 1 || d == ~uint64_t{0}) ? a : 3, up = d == 1, ++steps;
      key[a][0] = static_cast<uint64_t>(i0[a]) * axis[a];
      key[a][1] = (static_cast<uint64_t>(i0[a]) + 1) * axis[a];
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
      cell->corner[corner] = table[splitmix64(mixed_seed ^ key[0][x] ^ key[1][y] ^ key[2][z]) & (kScatterers - 1)];
    }
    for (int a = 0; a < 3; ++a) cell->index[a] = i0[a];
  }
  float re = 0.0f, im = 0.0f, weight2 = 0.0f;
  for (int corner = 0; corner < 8; ++corner) {
    const int x = corner & 1, y = corner >> 1 & 1, z = corner >> 2 & 1;
    const float wc = w[0][x] * w[1][y] * w[2][z];
    re += wc * cell->corner[corner].re;
    im += wc * cell->corner[corner].im;
    weight2 += wc * wc;
  }
  const float norm = 1.0f / std::sqrt(weight2);
  return {re * norm, im * norm};
}

}  // namespace pcisim::ultrasound
