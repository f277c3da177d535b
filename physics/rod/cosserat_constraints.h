#pragma once
// The two constraints of the discrete Cosserat rod (Kugelstadt & Schoemer 2016, "Position and
// orientation based Cosserat rods", SCA 2016; cited below as [cosserat, <constraint>]): a stretch-shear
// constraint per segment couples its two end nodes to its orientation quaternion, a bend-twist
// constraint per pair of neighbouring segments couples their quaternions. Each is written once
// as a strain (used by the static solver, rod_statics.h, through the energy) and once as an XPBD
// projection (used by the dynamic step). The paper's text is not in the shared papers folder:
// the constraint names are the paper's; its section and equation numbers are not cited because
// we could not check them here, and the derivations of the projections below are ours.
//
// Energies: stretch-shear 1/2 l Gamma_m^T diag(GA, GA, EA) Gamma_m per segment, bend-twist
// 1/2 l_b Omega^T diag(EI, EI, GJ) Omega per pair, so the XPBD compliances are the inverses of
// l K (Macklin et al. 2016, XPBD, eq 4: alpha = K^-1 for the potential 1/2 C^T alpha^-1 C).
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace pcisim::physics::rod {

// [cosserat, stretch-shear constraint] Gamma = (p2 - p1) / l - d3(q), d3(q) = q e3 q^-1: zero
// when the segment has its rest length and the material frame's third director is its
// tangent. Returned in the material frame of q (shear x, shear y, stretch z).
Eigen::Vector3d stretch_shear_strain(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, const Eigen::Quaterniond& q,
                                     double rest_length_m);

// [cosserat, bend-twist constraint] Omega = (2 / l_b) Im(conj(q1) q2) - Omega_0, the discrete
// Darboux vector (bend x, bend y, twist z in q1's frame) minus its rest value; of q2 and -q2
// (the same rotation) the one giving the shorter relative rotation is taken (the paper takes
// the one nearer the rest value, which is wrong for a curved rest shape: cosserat_constraints.cc)
Eigen::Vector3d bend_twist_strain(const Eigen::Quaterniond& q1, const Eigen::Quaterniond& q2, double dual_length_m,
                                  const Eigen::Vector3d& rest_darboux_per_m);

// One XPBD update (Macklin et al. 2016, eq 18: dlambda = -(C + alpha~ lambda) / (grad C W
// grad C^T + alpha~)) of the stretch-shear constraint. With q a unit quaternion, the gradient
// of d3 with respect to q's four components satisfies J J^T = 4 I (ours: J^T v = 2 v q e3^*),
// so the 3x3 system is diagonal in the material frame and each component is solved on its own:
//   dlambda_k = -(Gamma_k + a~_k lambda_k) / ((w1 + w2) / l^2 + 4 wq [k = shear only] + a~_k)
//   dp1 = -w1 / l R dlambda, dp2 = +w2 / l R dlambda, dq = -2 wq (R dlambda_shear) q e3^*
// Deviation from the paper, which weights all three components with 4 wq: the stretch
// component along d3 cannot be taken up by turning a unit quaternion (its gradient is along q
// and the normalisation removes it). With the paper's weights a thin rod (wq >> w / l^2) does
// not hold its length under large steps: the default wire at 1/3 s steps under gravity ended
// with its nodes metres apart.
// alpha_tilde: compliance / h^2 per material component; lambda accumulates over the substep.
void project_stretch_shear(Eigen::Vector3d& p1, double w1, Eigen::Vector3d& p2, double w2, Eigen::Quaterniond& q,
                           double wq, double rest_length_m, const Eigen::Vector3d& alpha_tilde,
                           Eigen::Vector3d& lambda);

// One XPBD update of the bend-twist constraint. The gradients of Im(conj(q1) q2) . v are
// -q2 v (for q1) and q1 v (for q2) (ours), each with J J^T = I, so again a diagonal system:
//   dlambda_k = -(Omega_k + a~_k lambda_k) / (4 (w1 + w2) / l_b^2 + a~_k)
//   dq1 = -w1 (2 / l_b) q2 dlambda, dq2 = +w2 (2 / l_b) q1 dlambda   (q2 sign-flipped as above)
void project_bend_twist(Eigen::Quaterniond& q1, double w1, Eigen::Quaterniond& q2, double w2, double dual_length_m,
                        const Eigen::Vector3d& rest_darboux_per_m, const Eigen::Vector3d& alpha_tilde,
                        Eigen::Vector3d& lambda);

// The constraints' Jacobians for the direct solve (cosserat_rod.h, solver kDirect), with respect
// to the node positions and a small world-frame rotation dtheta of each frame (q <- q + 1/2
// (0, dtheta) q). The stretch-shear strain is taken in the world frame there,
// Gamma_w = (p2 - p1) / l - d3(q) (the same energy: its compliance is rotated with q):
//   dGamma_w / dp1 = -I / l,  dGamma_w / dp2 = I / l,  dGamma_w / dtheta = [d3]x
// (d3 <- d3 + dtheta x d3). Returns [d3]x.
Eigen::Matrix3d stretch_shear_rotation_jacobian(const Eigen::Quaterniond& q);

// The bend-twist strain's Jacobian with respect to q2's rotation, B = dOmega / dtheta2
// = (s / l_b) (w I - [v]x) R1^T for conj(q1) q2 = (w, v) and s the sign chosen as above; with
// respect to q1's rotation it is -B (turning both frames together leaves Omega unchanged). The
// strain itself (as bend_twist_strain) goes to *strain.
Eigen::Matrix3d bend_twist_jacobian(const Eigen::Quaterniond& q1, const Eigen::Quaterniond& q2, double dual_length_m,
                                    const Eigen::Vector3d& rest_darboux_per_m, Eigen::Vector3d* strain);

}  // namespace pcisim::physics::rod
