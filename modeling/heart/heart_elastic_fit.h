#pragma once
// Stage (g) of the CTA pipeline, second half (docs/modeling.md): the placed template heart's
// tetrahedral mesh registered elastically toward the heart this CT shows. The paper registers its
// template to the CT volumetrically (its ref. [8]); here the epicardium is pulled to the heart's
// outline and the rest of the mesh follows:
//   1. the outline: the CT averaged over blocks of about block_mm (noise down), with the coronary
//      lumens and a clearance around them painted out (they run on the heart, in fat); the heart
//      is where that field is above tissue_hu (myocardium and blood), outside it below (epicardial
//      fat, lung);
//   2. each epicardial vertex looks along its normal, search_mm in and out, for the nearest
//      crossing from heart to outside (heart for run_mm behind it, outside for run_mm ahead: noise
//      is no outline); a target more than outlier_mm from the median of its
//      neighbours' (two rings) is dropped;
//   3. the epicardium's displacement d minimises
//        sum_i w_i |d_i - t_i|^2 + smoothing * sum_edges |d_i - d_j|^2
//      (w_i = 1 where vertex i found the outline at t_i along its normal, 0 elsewhere: those take
//      their neighbours');
//   4. the rest of the mesh follows harmonically: the graph Laplacian over the tets' edges is zero
//      at every vertex off the epicardium;
//   5. rounds from the moved surface; at the end the whole displacement is scaled back, if need be,
//      until every tetrahedron keeps min_tet_volume_fraction of its volume (and its orientation).
#include <Eigen/Core>
#include <string>
#include <vector>

#include "anatomy/heart/heart_mesh.h"
#include "anatomy/heart/heart_pose.h"
#include "anatomy/vessel/vessel_tree.h"
#include "anatomy/volume/volume.h"
#include "modeling/image/image3.h"

namespace pcisim::modeling {

struct HeartElasticFitOptions {
  bool enabled = true;
  // heart (myocardium 40..100, blood, enhanced chambers) above, epicardial fat (-100) and lung below
  double tissue_hu = -30;
  double block_mm = 1.0;   // the CT averaged over blocks of about this size (per axis, whole voxels)
  double search_mm = 15;   // along each epicardial normal, in and out
  double step_mm = 0.25;   // sampling step of that search
  double run_mm = 2.0;     // a crossing counts with heart this far behind it and outside this far ahead
  double outlier_mm = 8;   // a target this far from its neighbours' median is dropped
  double smoothing = 2.0;  // weight of the surface's edges against the targets (step 3)
  int rounds = 4;
  double vessel_clearance_mm = 1.0;      // painted out around each coronary lumen (radius + this)
  double min_tet_volume_fraction = 0.1;  // the backoff's bound (step 5)
};

struct HeartElasticFit {
  Eigen::Matrix3Xd vertices_m;  // the fitted rest shape in the template's frame (metres)
  int epicardial_vertices = 0;
  int targets = 0;   // epicardial vertices that found the outline in the last round
  int outliers = 0;  // targets dropped in the last round
  int rounds_run = 0;
  // distance along the normals from the epicardium to the outline, over the vertices that found
  // it: with the template as placed, and fitted (what the fit leaves)
  double outline_before_mean_mm = 0, outline_before_p95_mm = 0;
  double outline_after_mean_mm = 0, outline_after_p95_mm = 0;
  double move_mean_mm = 0, move_max_mm = 0;           // vertices' displacement, case frame
  double backoff = 1;                                 // fraction of the displacement kept (1: all)
  double min_tet_volume_ratio = 1;                    // smallest fitted / placed tet volume
  double volume_placed_ml = 0, volume_fitted_ml = 0;  // enclosed by the epicardium, case frame
  std::vector<std::string> notes;
};

// the heart's outline field on blocks of about o.block_mm over the physical box [lo_mm, hi_mm]
// (clamped to the CT): mean HU, coronary lumens (every branch but "aorta") painted out at
// o.tissue_hu - 100
FloatImage heart_outline_field(const anatomy::Volume& ct, const Eigen::Vector3d& lo_mm, const Eigen::Vector3d& hi_mm,
                               const anatomy::VesselTree& tree, const HeartElasticFitOptions& o);

// signed distance along `normal` (unit, mm) from p_mm to the nearest crossing of the field from
// above o.tissue_hu to below it within +-o.search_mm; NaN when there is none
double outline_along_normal_mm(const FloatImage& field, const Eigen::Vector3d& p_mm, const Eigen::Vector3d& normal,
                               const HeartElasticFitOptions& o);

// the template mesh (template frame) placed by `pose` and fitted to the CT; rounds_run == 0 when
// nothing was fitted (the outline not found, or every scale crushes a tet: vertices as placed, a
// note says why). Throws std::invalid_argument when the placed heart lies outside the CT,
// std::runtime_error when a sparse system is singular
HeartElasticFit fit_heart_elastic(const anatomy::Volume& ct, const anatomy::VesselTree& tree,
                                  const anatomy::HeartPose& pose, const anatomy::HeartMesh& template_mesh,
                                  const HeartElasticFitOptions& o);

}  // namespace pcisim::modeling
