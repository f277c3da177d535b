#include "ultrasound/echo/tissue_acoustics.h"

#include <cmath>

#include "ultrasound/echo/acoustic_model.h"
#include "ultrasound/echo/point_spread.h"

namespace pcisim::ultrasound {
namespace {

// the unit of TissueAcoustics::backscatter: the HU model's scale (acoustic_model.h: soft tissue
// at 150 HU and above scatters 1e-4 of a perfect reflector)
constexpr double kBackscatterUnit = 1e-4;

}  // namespace

// name, speed (m/s), density (g/cm^3), attenuation (dB/cm/MHz), backscatter (1e-4); sources in
// the header. The renal tissues share the kidney's speed and density (the cortex and the medulla
// differ by less than 1 %: no boundary echo between them, only their speckle's brightness)
const std::vector<TissueAcoustics>& tissue_acoustics_table() {
  static const std::vector<TissueAcoustics> table = {
      {"air", 343.0, 0.0012, 1.6, 0.0},
      {"water", 1482.0, 0.994, 0.011, 0.0},
      {"urine", 1551.0, 1.024, 0.011, 0.0005},
      {"blood", 1578.0, 1.050, 0.15, 0.001},
      {"renal vein", 1578.0, 1.050, 0.15, 0.001},
      {"renal artery", 1578.0, 1.050, 0.15, 0.001},
      {"fat", 1440.0, 0.911, 0.6, 1.5},
      {"perirenal fat", 1440.0, 0.911, 0.6, 1.5},
      // fat with the fibrous septa, vessels and lymphatics of the sinus: the brightest echoes
      {"renal sinus fat", 1440.0, 0.911, 0.6, 4.0},
      {"renal cortex", 1560.0, 1.066, 0.9, 0.5},
      {"renal medulla", 1560.0, 1.066, 0.9, 0.06},
      // a solid renal tumour: kidney-like, a little brighter than the cortex (an assumption)
      {"tumour", 1560.0, 1.066, 0.9, 1.0},
      {"muscle", 1588.0, 1.090, 1.1, 0.3},
      {"soft tissue", 1540.0, 1.060, kSoftTissueAttenuationDbCmMhz, 1.0},
      {"acrylic", 2750.0, 1.19, 1.3, 0.05},
      {"steel", 5900.0, 7.9, 1.0, 0.0},
  };
  return table;
}

const TissueAcoustics* find_tissue_acoustics(std::string_view name) {
  for (const TissueAcoustics& t : tissue_acoustics_table())
    if (t.name == name) return &t;
  return nullptr;
}

std::string known_tissue_names() {
  std::string out;
  for (const TissueAcoustics& t : tissue_acoustics_table()) out += (out.empty() ? "" : ", ") + t.name;
  return out;
}

// Z = rho c; c / c0; alpha / alpha_soft; sqrt(sigma)
Acoustics acoustics_of(const TissueAcoustics& t) {
  Acoustics a;
  a.impedance_mrayl = static_cast<float>(t.density_g_cm3 * t.speed_m_s * 1e-3);
  a.path_ratio = static_cast<float>(t.speed_m_s / kNominalSpeedMS);
  a.attenuation_factor = static_cast<float>(t.attenuation_db_cm_mhz / kSoftTissueAttenuationDbCmMhz);
  a.scatter_amplitude = static_cast<float>(std::sqrt(kBackscatterUnit * t.backscatter));
  return a;
}

Acoustics acoustics_of_hu(double hu) {
  Acoustics a;
  a.impedance_mrayl = static_cast<float>(impedance_mrayl(hu));
  a.path_ratio = static_cast<float>(speed_of_sound_m_s(hu) / kNominalSpeedMS);
  a.attenuation_factor = static_cast<float>(attenuation_factor(hu));
  a.scatter_amplitude = static_cast<float>(std::sqrt(backscatter(hu)));
  return a;
}

}  // namespace pcisim::ultrasound
