#pragma once
// Heart motion from a 4-D image sequence (heart paper section 4): the end-diastolic frame
// (frame 0) is registered to every other frame by diffeomorphic demons, and each frame's
// displacement field is sampled on a motion grid in the template heart's frame, giving the motion
// file the beating heart reads (anatomy/heart/heart_motion.h, docs/heart.md). Frame f of F is at
// phase f / F over one cycle; the demons field u of frame f satisfies frame0(x) ~ frame_f(x + u(x)),
// so u(x) is where the tissue at x at end-diastole has gone: the displacement of rest point x.
#include <functional>
#include <string>
#include <vector>

#include "anatomy/heart/heart_motion.h"
#include "anatomy/heart/heart_pose.h"
#include "anatomy/volume/volume.h"
#include "modeling/image/itk_filters.h"

namespace pcisim::modeling {

struct MotionFrameReport {
  int frame = 0;
  double seconds = 0.0;     // wall time of this frame's registration
  double metric = 0.0;      // the demons' mean squared difference at the end
  double rms_before = 0.0;  // RMS intensity difference frame 0 vs frame f, over the frame
  double rms_after = 0.0;   // the same with frame f pulled back by the field: the residual
};

// the frames as float images; throws std::invalid_argument naming the first frame whose grid
// (dims, spacing, origin, direction) differs from frame 0's, or when there are fewer than 2
std::vector<FloatImage> sequence_images(const std::vector<anatomy::Volume>& frames);

// RMS of fixed(x) - moving(x + u(x)) over fixed's voxels (moving trilinear, clamped at its edge)
double residual_rms(const FloatImage& fixed, const FloatImage& moving, const DisplacementImage* u);

// the share (0-1) of the template heart's mesh vertices, placed by the pose, that lie inside the
// image grid: the images must show the heart whose motion they give
double heart_overlap(const ImageGrid& images, const anatomy::HeartPose& pose);
constexpr double kMinHeartOverlap = 0.9;

// a sequence folder's volume files in phase order. Names ending in a number (frame_7, frame_007)
// are ordered by that number, which must run without a gap or a repeat and after one common
// prefix; names without numbers are ordered by name. Throws std::invalid_argument naming the file
// for a missing or repeated number (every later frame would sit at the wrong phase), a file
// without a number among numbered ones, or a second prefix (another sequence in the folder).
std::vector<std::string> order_frame_files(std::vector<std::string> paths);

// registers frame 0 to each frame and samples the fields on `grid` (template frame, metres): a
// grid node r is looked up at pose.to_case(r) in the images (case frame, mm) and the displacement
// brought back to the template frame. Refused (std::invalid_argument, with the figure) when less
// than kMinHeartOverlap of the heart lies in the images. Frame 0's field is zero. progress (if given) is called after
// each frame; reports (if given) receives one report per frame from 1 on.
anatomy::HeartMotion recover_heart_motion(const std::vector<anatomy::Volume>& frames, double cycle_s,
                                          const anatomy::MotionGrid& grid, const anatomy::HeartPose& pose,
                                          const DemonsOptions& options,
                                          std::vector<MotionFrameReport>* reports = nullptr,
                                          const std::function<void(const MotionFrameReport&)>& progress = {});

}  // namespace pcisim::modeling
