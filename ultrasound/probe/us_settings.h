#pragma once
// What the ultrasound machine is set to and where the probe is (issue #16 item 4). The renderer
// works in beam space (column c = one scanline, row r = one depth sample: pixel_to_world) and
// shows a display image (display_pixel_to_world): the same for a linear probe, the fan
// scan-converted into its bounding rectangle for a curvilinear one.
#include <Eigen/Core>

namespace pcisim::ultrasound {

enum class ProbeGeometry { kLinear, kCurvilinear };
// where a frame is drawn: the CPU (over `threads` threads) or the GPU (render/cuda_bmode.h: the
// same kernels; needs a CUDA build, a visible device and the case's tissue map)
enum class UsRenderer { kCpu, kCuda };

// the scanner's depth and gain ranges (validate() and whoever turns the knobs at run time)
inline constexpr double kUsMaxDepthMm = 300.0;  // (0, max]
inline constexpr double kUsMaxGainDb = 60.0;    // [-max, max]

struct UsSettings {
  ProbeGeometry geometry = ProbeGeometry::kLinear;
  double width_mm = 40.0;                // linear: aperture width, (0, 200]
  double fan_angle_deg = 60.0;           // curvilinear: total fan angle, (0, 150]
  double radius_of_curvature_mm = 40.0;  // curvilinear: radius of the transducer face, (0, 200]
  double depth_mm = 60.0;                // image depth below the transducer face, (0, 300]
  int width_px = 256;                    // scanlines, [8, 2048]
  int height_px = 256;                   // samples per scanline, [8, 4096]
  double gain_db = 0.0;                  // overall gain, [-60, 60]
  // time-gain compensation per cm of depth, [-20, 40]; 2 x attenuation x frequency (5.4 here)
  // cancels the soft tissue's round-trip attenuation
  double tgc_db_per_cm = 5.4;
  double frequency_mhz = 5.0;               // centre frequency, [1, 20]
  double attenuation_db_per_cm_mhz = 0.54;  // soft tissue, [0, 5] (Szabo 2004 table 4.1: ~0.5-0.7)
  double dynamic_range_db = 60.0;           // log-compression window, [10, 120]
  // the lattice of the tissue's scatterer field in the undeformed tissue, [0.02, 2] (issue #32;
  // echo/acoustic_model.h scatterer_field): the speckle's grain is the point-spread function's
  // where the cell is well under it; the pattern follows tissue moved by less than a sample where
  // the cell spans two samples or more (finer, it changes instead: the samples meet other cells)
  double speckle_cell_mm = 0.25;
  // the pulse-echo -6 dB fractional bandwidth: the axial point-spread function, [0.1, 1.5]
  double bandwidth = 0.5;
  // receive F-number (dynamic receive focus: the aperture grows with depth up to the probe's
  // width) and the transmit F-number at the transmit focus: the lateral point-spread function
  double f_number = 2.0;
  double focus_mm = 30.0;  // transmit focus depth, (0, 300]
  // specular echoes fall off with the angle between the beam and the boundary's normal as
  // cos^n (intensity), [0, 64]: a smooth boundary is bright where the beam meets it square
  double specular_exponent = 6.0;
  // threads a frame is spread over, the calling one counted, [1, kUsMaxThreads]: each pass's
  // scanlines (or rows) are handed out one at a time; the image is the same whatever the count
  int threads = 1;
  UsRenderer renderer = UsRenderer::kCpu;
};

// the ranges of the imaging fields above that validate() and the scene loader share
inline constexpr double kUsBandwidthMin = 0.1, kUsBandwidthMax = 1.5;
inline constexpr double kUsFNumberMin = 0.5, kUsFNumberMax = 10.0;
inline constexpr double kUsSpecularExponentMax = 64.0;
inline constexpr int kUsMaxThreads = 8;

// the probe in CT (LPS, mm): origin = centre of the transducer face on the skin, beam = into the
// body, lateral = along the array (made orthogonal to beam)
struct ProbePose {
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d beam = Eigen::Vector3d::UnitY();
  Eigen::Vector3d lateral = Eigen::Vector3d::UnitX();
};

// throws std::invalid_argument naming the first bad field and its range
void validate(const UsSettings& s);
// throws std::invalid_argument when beam or lateral is zero, not finite or they are parallel
void validate(const ProbePose& p);

// Pixel -> world (mm), for labels. Column c, row r (pixel centres at integers; fractional allowed):
//   t = (c + 0.5) / width_px - 0.5,  d = (r + 0.5) / height_px * depth_mm
//   linear:       x = origin + t * width_mm * lateral + d * beam
//   curvilinear:  theta = t * fan_angle, apex = origin - Rc * beam,
//                 x = apex + (Rc + d) * (cos(theta) * beam + sin(theta) * lateral)
// lateral is first made orthogonal to beam and both are normalised.
Eigen::Vector3d pixel_to_world(const UsSettings& s, const ProbePose& p, double col, double row);

// Display pixel -> world (mm). Linear: pixel_to_world. Curvilinear: the fan's bounding rectangle,
// width_px x height_px pixels, in the plane (x along lateral, y along beam from the face's centre):
//   X = (Rc + depth) sin(fan / 2),  y0 = Rc (cos(fan / 2) - 1),  y1 = depth
//   x = -X + (c + 0.5) / width_px * 2X,  y = y0 + (r + 0.5) / height_px * (y1 - y0)
//   world = origin + x * lateral + y * beam
Eigen::Vector3d display_pixel_to_world(const UsSettings& s, const ProbePose& p, double col, double row);
// the beam-space (scanline, sample) of a display pixel, fractional; false outside the fan
// (curvilinear: theta = atan2(x, y + Rc), d = |(x, y + Rc)| - Rc, then pixel_to_world inverted)
bool display_to_beam(const UsSettings& s, double col, double row, double* beam_col, double* beam_row);

}  // namespace pcisim::ultrasound
