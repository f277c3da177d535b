#include "ultrasound/echo/point_spread.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "ultrasound/probe/us_settings.h"

namespace pcisim::ultrasound {

double axial_psf_sigma_mm(double frequency_mhz, double bandwidth) {
  const double sigma_t_us = std::sqrt(2.0 * std::numbers::ln2) / (std::numbers::pi * bandwidth * frequency_mhz);
  return 0.5 * (kNominalSpeedMS * 1e-3) * sigma_t_us;  // (mm/us) x us
}

double focused_beam_sigma_mm(double frequency_mhz, double f_number) {
  const double lambda_mm = kNominalSpeedMS * 1e-3 / frequency_mhz;
  return 1.02 * lambda_mm * f_number / kFwhmPerSigma;
}

double transmit_beam_sigma_mm(double frequency_mhz, double f_number, double focus_mm, double depth_mm) {
  const double lambda_mm = kNominalSpeedMS * 1e-3 / frequency_mhz;
  const double sigma0 = focused_beam_sigma_mm(frequency_mhz, f_number);
  const double w0 = std::numbers::sqrt2 * sigma0;
  const double z_r = std::numbers::pi * w0 * w0 / lambda_mm;
  const double u = (depth_mm - focus_mm) / z_r;
  return sigma0 * std::sqrt(1.0 + u * u);
}

double receive_f_number(double f_number, double depth_mm, double aperture_mm) {
  return std::max(f_number, depth_mm / aperture_mm);
}

double probe_aperture_mm(const UsSettings& s) {
  if (s.geometry == ProbeGeometry::kLinear) return s.width_mm;
  return 2.0 * s.radius_of_curvature_mm * std::sin(0.5 * s.fan_angle_deg * std::numbers::pi / 180.0);
}

double lateral_psf_sigma_mm(const UsSettings& s, double depth_mm) {
  const double aperture = probe_aperture_mm(s);
  // the transmit aperture is the probe's at most too: a deep focus is focused at F / aperture
  const double tx =
      transmit_beam_sigma_mm(s.frequency_mhz, receive_f_number(s.f_number, s.focus_mm, aperture), s.focus_mm, depth_mm);
  const double rx = focused_beam_sigma_mm(s.frequency_mhz, receive_f_number(s.f_number, depth_mm, aperture));
  return 1.0 / std::sqrt(1.0 / (tx * tx) + 1.0 / (rx * rx));
}

}  // namespace pcisim::ultrasound
