#pragma once
// The echo model from CT numbers, one rule per function with its equation (docs/ultrasound.md).
// Sources (facts only): Schneider, Bortfeld, Schlegel 2000, Phys Med Biol 45:459 (density vs HU
// close to rho = 1 + HU/1000 g/cm^3 for soft tissue); Duck 1990 "Physical Properties of Tissue"
// and Szabo 2004 "Diagnostic Ultrasound Imaging", tables 4.1/4.2 (speed of sound: air 343, fat
// ~1450, water 1480, soft tissue ~1540, bone ~3500 m/s; attenuation: soft tissue 0.5-0.7,
// bone ~20 dB/cm/MHz); Wagner et al. 1983, IEEE Trans Sonics Ultrason 30:156 (fully developed
// speckle: Rayleigh amplitude, exponential intensity); Goksel & Salcudean 2009, IEEE TMI 28:1657
// (echo = reflection at impedance changes + scattering, attenuated with depth).
#include <complex>
#include <cstdint>

// (reflection, attenuation_db, brightness_db, log_compress and the scatterer field's lattice:
// the per-sample rules the CUDA twin shares)
#include "ultrasound/echo/echo_rules.h"

namespace pcisim::ultrasound {

// density (g/cm^3): rho = max(1 + HU / 1000, 0.0012)   [Schneider 2000, soft-tissue segment]
double density_g_cm3(double hu);
// speed of sound (m/s), piecewise linear through tissue classes (HU, c): air (-1000, 343),
// fat (-100, 1450), water (0, 1480), soft tissue (40, 1540), dense tissue (300, 1600),
// bone (1000, 3500), constant beyond   [Duck 1990; Szabo 2004 table 4.1]
double speed_of_sound_m_s(double hu);
// acoustic impedance (MRayl): Z = rho c   (rho in g/cm^3, c in km/s)
double impedance_mrayl(double hu);
// attenuation multiplier on the soft-tissue coefficient (0.54 dB/cm/MHz), piecewise linear in HU:
// fat (-100 to -30 HU) 1.1 (0.6), fluid (0 to 15 HU: urine, bile, cysts) 0.02 (water 0.0022
// dB/cm/MHz^2, rising with f^2: ~0.011 dB/cm/MHz at 5 MHz; this model's loss is linear in f),
// soft tissue (30 to 300 HU) 1, rising to 20 / 0.54 at 1000 HU (bone ~20)   [Szabo 2004 table
// 4.2; Duck 1990 ch. 4]. Fluid that barely attenuates is what brightens the tissue behind it
// (posterior enhancement) under a TGC set for soft tissue.
double attenuation_factor(double hu);
// diffuse backscatter (intensity, relative to a perfect reflector): sigma = 1e-4 s(HU), s
// piecewise linear: air 0, fat 1.5 (echogenic), fluid 0 HU 0.05 (anechoic), medulla 30 HU 0.15
// (the pyramids hypoechoic against the cortex, ~8 dB),
// soft tissue 60 HU 0.8, 150 HU and above 1. An assumption of this model (no CT physics gives
// it): fat bright, fluid dark, parenchyma grey, as B-mode shows them.
double backscatter(double hu);
// the tissue's scatterer in cell (i, j, k) of the undeformed CT (cells of speckle_cell_mm): a
// complex amplitude, circular Gaussian with E a = 0 and E|a|^2 = 1 (the sum of many random
// sub-resolution scatterers in the cell [Wagner 1983]), drawn from a fixed table of 4096 such
// values by a counter-based hash of (seed, i, j, k). Fixed in the tissue: it moves with it and
// does not flicker from frame to frame. Deterministic per seed.
std::complex<float> scatterer(uint64_t seed, int64_t i, int64_t j, int64_t k);
// the tissue's scatterer field at u (a point of the undeformed CT in cells, q / speckle_cell_mm):
// the lattice's amplitudes at the cell's 8 corners, trilinear, over the square root of the
// weights' squares, so it is continuous (tissue moved by less than a cell moves it smoothly) and
// its power is 1 everywhere (plain trilinear falls to 1/8 of it at a cell's centre, a grid the
// image would show): v(u) = sum w_c a_c / sqrt(sum w_c^2)
std::complex<float> scatterer_field(uint64_t seed, const double (&u)[3]);
// the same, with the 8 corners' amplitudes kept in `cell` between calls (echo_rules.h: the
// result is bit for bit scatterer_field's). One cache per seed
std::complex<float> scatterer_field(uint64_t seed, const double (&u)[3], ScattererCell* cell);
// the table the lattice's amplitudes are drawn from (kScatterers entries), for a GPU's copy
const Cf* scatterer_table();

}  // namespace pcisim::ultrasound
