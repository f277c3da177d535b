#pragma once
// Stage (g) of the CTA pipeline, first half (docs/modeling.md): the template heart placed under the
// patient's coronary tree. The template heart was built around the procedural coronary tree of
// phantom 1 (docs/heart.md), which runs on its epicardium; the similarity (rotation, uniform
// scale, translation) that carries that tree onto the patient's tree, found by iterative closest
// points (Besl and McKay 1992, the paper's ref. [9]) with Umeyama's closed form at each step, is
// the heart's pose. The points are the aortic root and every coronary branch (the paper joins heart
// and vessels by ICP on their shared aortic segment; with the whole tree the epicardial vessels
// also fix the heart's orientation). Start: no rotation, unit scale, the two trees' ostia (or
// centroids) on each other: CTAs are taken supine and stored in LPS, so a patient's heart is
// oriented roughly as the template's.
// The elastic part of (g), the placed mesh fitted to the CT's heart, is heart_elastic_fit.h.
#include "anatomy/heart/heart_pose.h"
#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::modeling {

struct HeartPlacementOptions {
  int iterations = 40;
  double sample_spacing_mm = 1.0;  // the patient's centerlines resampled at this step
  double trim_factor = 3.0;        // pairs farther apart than this times the median are left out
  double aorta_root_mm = 25.0;     // the aortic centerline's first this-many mm join the fit
  double min_scale = 0.7, max_scale = 1.4;
};

struct HeartPlacement {
  anatomy::HeartPose pose;
  double rms_mm = 0;  // residual over the kept pairs
  int pairs = 0;      // kept in the last step
  int iterations_run = 0;
};

// throws std::invalid_argument when the tree has fewer than 10 coronary points
HeartPlacement place_template_heart(const anatomy::VesselTree& patient_tree, const HeartPlacementOptions& options);

}  // namespace pcisim::modeling
