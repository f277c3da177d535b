#pragma once
// B-mode ultrasound from the preoperative CT through the deformed tissue (issue #16 item 4;
// soft-tissue paper, "Weighted matrix blending"): each image sample in the deformed configuration
// is carried to the undeformed CT through the tet holding it (outside every tet the CT is sampled
// where the sample is: the organ's surroundings are undeformed), its HU give impedance,
// scattering and attenuation (echo/acoustic_model.h), and each scanline accumulates what is
// transmitted. render() returns the display image (display_pixel_to_world in
// probe/us_settings.h: beam space for a linear probe, the scan-converted fan for a curvilinear
// one); beam_image() the beam-space one (pixel_to_world). The constructor and set_mesh()
// allocate; render() and set_imaging() allocate nothing.
#include <cstdint>
#include <string>
#include <vector>

#include "anatomy/volume/volume.h"
#include "ultrasound/mapping/tet_locator.h"
#include "ultrasound/mapping/tet_snapshot.h"
#include "ultrasound/probe/us_settings.h"

namespace pcisim::ultrasound {

// 8-bit grey, row-major, row 0 nearest the transducer, column 0 at the -lateral end
struct BModeImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> pixels;
};

// 8-bit grey PNG through png/; throws std::runtime_error naming the path
void write_png(const std::string& path, const BModeImage& image);

class BModeRenderer {
 public:
  // validates the settings (std::invalid_argument naming the field) and the CT; keeps a
  // reference to ct, which must outlive the renderer
  BModeRenderer(const anatomy::Volume& ct, const UsSettings& settings);

  // the scanner's depth and overall gain from now on (the probe's knobs); throws
  // std::invalid_argument naming the field when out of range (us_settings.h), changing nothing
  void set_imaging(double depth_mm, double gain_db);

  // the deformed mesh's topology: builds the tet lookup grid (allocates)
  void set_mesh(const TetSnapshot& mesh);
  // one frame; deformed == nullptr: undeformed CT. A deformed snapshot must have the topology of
  // set_mesh() (set_mesh() is called on first use).
  const BModeImage& render(const ProbePose& pose, uint64_t seed, const TetSnapshot* deformed = nullptr);

  // the last frame's echo intensity per pixel (row-major; relative to a perfect reflector at the
  // face, after attenuation and transmission, before gain, TGC and compression)
  const std::vector<float>& echo_intensity() const { return echo_; }
  // the last frame in beam space (column = scanline, row = depth sample)
  const BModeImage& beam_image() const { return beam_; }
  const UsSettings& settings() const { return settings_; }
  // axial window over which the impedance change is taken: max(2 wavelengths, CT voxel)
  double pulse_length_mm() const { return pulse_mm_; }

 private:
  void build_geometry();
  double sample_hu(const Eigen::Vector3d& p_mm) const;
  void render_scanline(int column);
  void scan_convert();

  const anatomy::Volume& ct_;
  UsSettings settings_;
  Eigen::Matrix3d world_to_index_;
  double pulse_mm_ = 1.0;
  std::vector<double> offset_lateral_, offset_beam_;  // per pixel, probe frame (mm)
  TetLocator locator_;
  bool have_mesh_ = false;
  std::vector<double> hu_, z_;   // per pixel, column-major (scanline by scanline)
  std::vector<double> speckle_;  // per pixel: the speckle of the tissue the sample maps to
  std::vector<float> echo_;
  BModeImage beam_, image_;
  // curvilinear display: per display pixel the beam-space cell (-1 outside the fan) and weights
  std::vector<int> convert_index_;
  std::vector<float> convert_fx_, convert_fy_;
};

}  // namespace pcisim::ultrasound
