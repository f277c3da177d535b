#pragma once
// pcisim-bench xray's comparison with plastimatch (issue #36 item 3): the same volume, written as a
// MetaImage, projected by `plastimatch drr` (exact, Siddon) on the same C-arm geometry in the same
// run, timed per image and checked against pcisim's own exact projection of that geometry.
#include <string>

#include "anatomy/volume/volume.h"
#include "xray/geometry/c_arm.h"
#include "xray/projectors/attenuation_volume.h"
#include "xray/projectors/image.h"

namespace pcisim::bench {

struct PlastimatchRun {
  bool ran = false;
  std::string why;      // why not, when it did not run
  std::string command;  // the command line of the timed run
  std::string version;  // plastimatch --version's first line
  int images = 0;       // timed runs, one image each (with -n, plastimatch makes one image a run)
  // median ms per image: plastimatch's own "Total time" (the projection, after it has read the
  // volume), and the whole process's wall time (reading the 256 MiB volume included)
  double per_image_ms = 0, process_ms = 0;
  double volume_mib = 0;  // the float mu volume plastimatch reads
  // plastimatch's image against pcisim's exact one (pcisim's pixel order): Pearson correlation,
  // the least-squares scale plastimatch's line integrals need to match pcisim's (their HU -> mu
  // conversions differ), and the RMSE after that scale, relative to pcisim's largest value
  double correlation = 0, scale = 0, rmse_rel = 0;
  double first_row_share = 0;  // of the squared differences, the share in the detector's first row
};

// the first `plastimatch` on PATH, or empty
std::string find_plastimatch();

// the attenuation `mu` of `grid` (its voxels' mu per mm, written to work_dir as float, so both
// programs project the same values: plastimatch's own HU conversion differs from pcisim's) seen
// on `c_arm` at `pose`, projected by plastimatch's exact algorithm (-P none) with the same source,
// isocentre, detector plane and pixels, `images` times; `reference` is pcisim's exact projection
// of that geometry (its line integrals, row-major as xray::Image holds them)
PlastimatchRun run_plastimatch_drr(const std::string& plastimatch, const xray::AttenuationVolume& mu,
                                   const anatomy::Volume& grid, const xray::CArmSpec& c_arm, const xray::CArmPose& pose,
                                   const xray::Image& reference, const std::string& work_dir, int images);

}  // namespace pcisim::bench
