#pragma once
// The soft-tissue FEM reference's mesh (pcisim-calibrate, pcisim-bench soft-tissue): a body-fitted
// tetrahedral mesh of the procedural kidney from TetGen (/usr/bin/tetgen, scripts/setup).
#include "anatomy/organ/kidney_phantom.h"
#include "physics/fem/static_fem.h"

namespace pcisim::bench {

// the kidney of `spec` (its analytic shape, the surface polygons re-made about spacing_m: the
// scene's 96 x 60 lat-long surface has slivers at the poles that TetGen may not coarsen; the chord
// error is ~0.1 mm at 4 mm) meshed into tets about spacing_m on a side (volume bound of the
// regular tet, radius-edge ratio <= 1.4; the surface may be refined, never moved). Metres.
// Throws std::runtime_error with TetGen's log when it fails or is missing.
physics::fem::FemMesh kidney_tetgen_mesh(const anatomy::KidneySpec& spec, double spacing_m);

}  // namespace pcisim::bench
