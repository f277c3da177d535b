#pragma once
// Bending across a shared edge as a dihedral-angle constraint C = theta - theta0.
// Dihedral rather than isometric bending: isometric bending (Bergou 2006) has a constant
// Hessian only about a flat rest state, and the heart wall and the vessels on it are curved at
// rest; the dihedral angle keeps any rest angle, is rotation and translation invariant (so it
// conserves momentum) and its cost is a few cross products.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace pcisim::physics::pbd {

// triangles (a, b, c) and (b, a, d) share the edge a-b; c and d are the wings
struct DihedralBendingConstraint {
  int a = 0, b = 0, c = 0, d = 0;
  double rest_angle_rad = 0.0;
  double compliance_per_n_m = 0.0;  // alpha, rad per (N m)
};

// Signed dihedral angle (0 when flat, +-pi when folded shut) and its gradient for a, b, c, d.
// False when a triangle or the edge is degenerate, where the angle has no gradient.
bool dihedral_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                    const Eigen::Vector3d& d, double* theta_rad, Eigen::Vector3d grad[4]);

// One XPBD projection (soft-tissue paper eqs 3-5 with alpha~ = alpha / dt^2); x and w are
// ordered a, b, c, d. Returns false when there is nothing finite to do.
bool project_dihedral_bending(const Eigen::Vector3d x[4], const double w[4], double rest_angle_rad, double alpha_tilde,
                              double lambda, double* dlambda, Eigen::Vector3d dx[4]);

// theta - theta0 wrapped into (-pi, pi], so a rest angle near +-pi does not jump by 2 pi
double wrapped_angle_error(double theta_rad, double rest_rad);

}  // namespace pcisim::physics::pbd
