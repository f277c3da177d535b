#pragma once
// The probe's point-spread function (issue #32), Gaussian along each axis, one rule per function.
// Depths are the scanner's (time x 1540 m/s / 2). Sources (facts only): Szabo 2004, "Diagnostic
// Ultrasound Imaging", ch. 6-7 (the -6 dB one-way beam width at a focus, 1.02 lambda F#, the
// main lobe of a uniform aperture); Siegman 1986, "Lasers", ch. 17 (a Gaussian beam's width
// w(z) = w0 sqrt(1 + (z / zR)^2), zR = pi w0^2 / lambda); Wagner et al. 1983, IEEE Trans Sonics
// Ultrason 30:156 (speckle: the intensity's autocorrelation is the PSF's, so the speckle's size is
// the PSF's width).

namespace pcisim::ultrasound {

struct UsSettings;

// the scanner's nominal speed of sound (m/s): depth = c0 t / 2
inline constexpr double kNominalSpeedMS = 1540.0;
// FWHM = sqrt(8 ln 2) sigma for a Gaussian
inline constexpr double kFwhmPerSigma = 2.3548200450309493;

// axial (pulse-echo) sigma, mm: a Gaussian pulse of -6 dB fractional bandwidth B at f0 has
// sigma_t = sqrt(2 ln 2) / (pi B f0); in depth sigma_z = c0 sigma_t / 2
double axial_psf_sigma_mm(double frequency_mhz, double bandwidth);

// one-way lateral sigma of a beam focused at F-number F#, mm: FWHM 1.02 lambda F# (lambda = c0 / f0)
double focused_beam_sigma_mm(double frequency_mhz, double f_number);

// the transmit beam's sigma at depth d, mm: a Gaussian beam whose waist (w0 = sqrt(2) sigma_0, the
// 1/e^2 intensity radius) is focused_beam_sigma_mm at the transmit focus F:
//   sigma(d) = sigma_0 sqrt(1 + ((d - F) / zR)^2),  zR = pi w0^2 / lambda
double transmit_beam_sigma_mm(double frequency_mhz, double f_number, double focus_mm, double depth_mm);

// the receive F-number at depth d: dynamic focus with the aperture grown to keep F#, until the
// aperture is the probe's (aperture_mm): max(F#, d / aperture)
double receive_f_number(double f_number, double depth_mm, double aperture_mm);

// pulse-echo lateral sigma at depth d, mm: the PSF is the product of the transmit and the receive
// beams, 1 / sigma^2 = 1 / sigma_tx^2 + 1 / sigma_rx^2; the transmit beam focused at
// F#_tx = max(F#, focus / aperture) (its aperture is the probe's at most)
double lateral_psf_sigma_mm(const UsSettings& s, double depth_mm);

// the probe's largest aperture, mm: a linear array's width; a curvilinear one's chord
double probe_aperture_mm(const UsSettings& s);

}  // namespace pcisim::ultrasound
