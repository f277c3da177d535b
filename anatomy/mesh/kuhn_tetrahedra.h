#pragma once
// The six tetrahedra of a cube around its diagonal 0-7 (Kuhn's subdivision), cube corner
// c = x + 2y + 4z: every cube cuts its faces along the same diagonals as its neighbours, so the
// tetrahedra of a grid of cubes conform across cubes. Each is positively oriented:
// det(v1 - v0, v2 - v0, v3 - v0) > 0 on the unit cube. Used by the stitched lumen's marching
// tetrahedra (anatomy/vessel/lumen_surface.cc) and the soft tissue's embedding mesh
// (physics/soft_tissue/tissue_model.cc).
namespace pcisim::anatomy {

inline constexpr int kKuhnTetrahedra[6][4] = {{0, 1, 3, 7}, {0, 5, 1, 7}, {0, 3, 2, 7},
                                              {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 6, 4, 7}};

}  // namespace pcisim::anatomy
