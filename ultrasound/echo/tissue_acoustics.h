#pragma once
// Acoustic properties per named tissue (issue #32 item 1), for a case whose organ carries a tissue
// map (anatomy/organ/organ.h): each voxel's tissue gives its speed of sound, density, attenuation
// and scattering directly, instead of the HU rules of acoustic_model.h. Sources (facts only):
// speed of sound and density, the IT'IS Foundation tissue database v4.1 (Hasgall et al. 2022,
// averages over Duck 1990 and later measurements): fat 1440 m/s, 0.911 g/cm^3; kidney 1560,
// 1.066; blood 1578, 1.050; urine 1551, 1.024; muscle 1588, 1.090; water 1482, 0.994; air 343,
// 0.0012. Attenuation (dB/cm/MHz): Szabo 2004 "Diagnostic Ultrasound Imaging" table 4.1 and
// Duck 1990 ch. 4: fat ~0.6, kidney 0.8-1.0 (0.9 taken), muscle ~1.1, blood ~0.15, water 0.0022 f (so ~0.011
// at 5 MHz, this model's loss being linear in f); acrylic 2750 m/s, 1.19 g/cm^3, ~1.3
// dB/cm/MHz and steel 5900 m/s, 7.9 g/cm^3 (Selfridge 1985, IEEE Trans Sonics Ultrason 32:381).
// Backscatter: how bright each tissue is against the others as a sonographer sees it (Rumack,
// Wilson, Charboneau, "Diagnostic Ultrasound", 4th ed., 2011, the kidney: the cortex hypoechoic
// to liver and spleen, the medullary pyramids hypoechoic to the cortex, the sinus echogenic from
// its fat; blood and urine anechoic, their backscatter tens of dB under tissue's, Shung 2006
// "Diagnostic Ultrasound: Imaging and Blood Flow Measurements"). The numbers are this model's,
// chosen to keep those ranks with steps of 6-10 dB; the HU model's 1e-4 scale is their unit.
#include <string>
#include <string_view>
#include <vector>

namespace pcisim::ultrasound {

// the attenuation the probe's setting (UsSettings::attenuation_db_per_cm_mhz) stands for: a
// tissue's loss is its own coefficient times setting / this (the default setting: as published)
constexpr double kSoftTissueAttenuationDbCmMhz = 0.54;

struct TissueAcoustics {
  std::string name;
  double speed_m_s = 1540.0;
  double density_g_cm3 = 1.0;
  double attenuation_db_cm_mhz = kSoftTissueAttenuationDbCmMhz;
  double backscatter = 1.0;  // diffuse backscatter (intensity) in units of 1e-4 of a perfect reflector
};

// what the echo model needs at one point: Z = rho c (MRayl); c / c0 (the path per screen
// sample); the attenuation over the soft tissue's; the scatterers' amplitude sqrt(sigma)
struct Acoustics {
  float impedance_mrayl = 0.0f;
  float path_ratio = 1.0f;
  float attenuation_factor = 1.0f;
  float scatter_amplitude = 0.0f;
};

// every tissue this model knows, by name (those of the kidney phantom and a few more)
const std::vector<TissueAcoustics>& tissue_acoustics_table();
// the row named `name`, or nullptr
const TissueAcoustics* find_tissue_acoustics(std::string_view name);
// the known names, comma-separated (for error messages)
std::string known_tissue_names();

Acoustics acoustics_of(const TissueAcoustics& tissue);
// the HU rules of acoustic_model.h as the same four numbers (a case without a tissue map)
Acoustics acoustics_of_hu(double hu);

}  // namespace pcisim::ultrasound
