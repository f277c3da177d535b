#pragma once
// Fits the template heart under a coronary tree. Where the template does not match the vessels, the
// heart paper deforms it toward the patient's CTA heart (volumetric registration, its ref. [8]);
// a case modelled from a CTA carries that fit (modeling/heart/heart_elastic_fit.h, the case's
// heart_vertices_m) and skips this; without one this is a local stand-in. The template was designed around phantom
// seed 1; other seeds run their LM or RCA up to ~2.4 mm into it. A branch that sinks deeper than
// the tolerance is lifted clear: the epicardium under it is dented radially until the vessel
// touches it, the dent fading along the surface and into the wall. A tree the template already
// fits leaves the mesh untouched.
#include "anatomy/heart/heart_mesh.h"
#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::physics {

struct HeartFitParams {
  double tolerance_m = 0.5e-3;  // a branch sunk no deeper than this is left alone
  // full dent within this distance (along the surface) of a sunken point: more than the template's
  // largest facet circumradius (~3.8 mm), so every facet under the vessel sinks whole
  double core_m = 4.0e-3;
  double fade_m = 8.0e-3;    // then fading to none over this distance
  double depth_m = 10.0e-3;  // and fading to none this far into the wall
};

struct HeartFitReport {
  int branches_lifted = 0;
  int vertices_moved = 0;
  double max_dent_m = 0.0;  // deepest radial move of a vertex
};

// how far the centerline point (patient frame, metres) lies above the designed epicardium, minus
// its radius: negative when the vessel sinks into the heart (radial, from the heart centre)
double clearance_above_epicardium_m(const anatomy::CenterlinePoint& point);

// dents mesh->vertices_m where a non-aorta branch sinks deeper than params.tolerance_m
HeartFitReport fit_heart_under_tree(const anatomy::VesselTree& tree, const HeartFitParams& params,
                                    anatomy::HeartMesh* mesh);

}  // namespace pcisim::physics
