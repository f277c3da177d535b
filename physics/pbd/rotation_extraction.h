#pragma once
// The rotational part R of a shape-matching moment matrix A_pq = R S (heart paper eq 9).
//
// Polar decomposition via a 3x3 SVD with a reflection fix, rather than Mueller et al.'s iterative
// quaternion method: the iterative method stops wherever R^T A is symmetric, which includes
// saddles (a warm start exactly 180 deg away, or an inverted cluster whose largest axis flipped),
// while A = U Sigma V^T, R = U diag(1, 1, det(U V^T)) V^T is the global maximiser of
// tr(R^T A) over proper rotations in one pass, for any A. det(R) = +1 always: an inverted cluster
// gets the rotation that un-inverts its thinnest axis. Rank-deficient A (coplanar clusters still
// give a unique R; collinear and coincident ones do not) is completed by the previous frame's
// rotation: a regulariser far below any real deformation picks the spin the data leave free, so
// such clusters keep their last orientation instead of jumping to an arbitrary SVD basis.
// The SVD is the CUDA twin's one-sided Jacobi (device_rotation.h), run on the CPU too; it agrees
// with Eigen's JacobiSVD to 3.7e-15 per entry on full-rank clusters, ~1e-7 on the free axes of
// collinear or coincident ones (tests/physics/pbd/device_twins_test.cc).
#include <Eigen/Core>

namespace pcisim::physics::pbd {

// fraction of the rest moment that the previous rotation contributes (bias on full-rank A)
inline constexpr double kRotationRegularisation = 1e-9;

// a: sum_i m_i p_i q_i^T (kg m^2); previous: last rotation (identity at first);
// rest_moment_kg_m2: sum_i m_i |q_i|^2 of the rest shape, the scale of a.
// Returns a proper rotation (orthonormal, det = +1) for every input, NaN included (then previous).
Eigen::Matrix3d extract_rotation(const Eigen::Matrix3d& a, const Eigen::Matrix3d& previous, double rest_moment_kg_m2);
// the same, its SVD started from right_vectors (the right singular vectors the last solve of this
// cluster found, identity at first; updated): the same R to rounding in fewer Jacobi sweeps
Eigen::Matrix3d extract_rotation(const Eigen::Matrix3d& a, const Eigen::Matrix3d& previous, double rest_moment_kg_m2,
                                 Eigen::Matrix3d* right_vectors);

}  // namespace pcisim::physics::pbd
