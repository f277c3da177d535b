#pragma once
// The kidney's particle model (soft-tissue paper, "Collision and data preparation" and "Weighted
// matrix blending"; issue #16 item 1): a closed surface is voxelised, particles are sampled from
// the occupied voxel centres by greedy removal, grouped into overlapping shape-matching clusters
// (pbd/grid_clusters), and the surface vertices and fiducials are skinned to up to four cluster
// frames. Built once; cluster_frames and skin_points allocate nothing.
#include <Eigen/Core>
#include <array>
#include <span>
#include <vector>

#include "anatomy/mesh/triangle_mesh.h"

namespace pcisim::physics::soft_tissue {

struct TissueModelSpec {
  double voxel_m = 1.0e-3;              // voxelisation grid spacing
  double particle_radius_m = 2.75e-3;   // greedy removal radius: particles are at least this far apart
  double cluster_spacing_factor = 2.0;  // cluster cube edge = factor x particle radius
  double cluster_overlap = 0.5;         // each cube grown by this fraction of its edge per side
  int cluster_min_members = 4;
  double tet_spacing_factor = 4.0;  // coarse tetrahedral grid: cube edge = factor x particle radius
};

constexpr int kMaxSkinClusters = 4;

// a point bound to up to four cluster frames: p = sum_k w_k (R_c p_local_k + c_c)
struct SkinBinding {
  int count = 0;
  std::array<int, kMaxSkinClusters> cluster{};
  std::array<double, kMaxSkinClusters> weight{};
  std::array<Eigen::Vector3d, kMaxSkinClusters> local_m{};  // rest point minus the cluster's rest centre
};

struct TissueModel {
  TissueModelSpec spec;
  Eigen::Matrix3Xd rest_m;                 // particle rest positions
  std::vector<std::vector<int>> clusters;  // members per cluster
  Eigen::Matrix3Xd cluster_rest_centre_m;  // equal-mass centre of each cluster at rest
  std::vector<SkinBinding> surface_skin;   // one per surface vertex
  std::vector<SkinBinding> fiducial_skin;  // one per fiducial
  // the coarse tetrahedral mesh: a regular grid of cubes, each cut into six tetrahedra around its
  // diagonal (Kuhn), kept where a tetrahedron holds a particle; its vertices skinned like the surface
  Eigen::Matrix3Xd tet_vertices_m;
  std::vector<std::array<int, 4>> tets;
  std::vector<SkinBinding> tet_skin;  // one per tet vertex
  // each particle's distance to the organ's surface at rest, searched up to the particle radius
  // (deeper particles read the radius): how far its contact sphere may reach before it passes
  // the skin (TissueParams::contact_surface)
  Eigen::VectorXd skin_depth_m;
  // voxelisation: occupied voxel centres (kept for tests and the tet embedding)
  Eigen::Matrix3Xd interior_voxels_m;
};

// Throws std::invalid_argument when the radius, the spacing or the cluster factor is not positive,
// or when the particle radius is larger than the organ (its smallest bounding-box extent); the
// message names the radius and the organ's size in mm.
TissueModel build_tissue_model(const anatomy::TriangleMesh& surface_m, std::span<const Eigen::Vector3d> fiducials_m,
                               const TissueModelSpec& spec = {});

// each cluster's current frame from shape matching: R from the polar decomposition of
// A = sum (x_i - c)(x0_i - c0)^T, c the current centre (equal masses)
struct ClusterFrames {
  std::vector<Eigen::Matrix3d> rotation;
  Eigen::Matrix3Xd centre_m;
  explicit ClusterFrames(const TissueModel& model);
};
void cluster_frames(const TissueModel& model, const Eigen::Matrix3Xd& x_m, ClusterFrames* frames);

// the skinned points' current positions into out_m (3 x bindings.size(), sized by the caller)
void skin_points(const ClusterFrames& frames, std::span<const SkinBinding> bindings, Eigen::Matrix3Xd* out_m);

}  // namespace pcisim::physics::soft_tissue
