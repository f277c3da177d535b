#pragma once
// Contacts of PBD particles with rigid bodies given as intersections of half-spaces (a support
// plane, a kinematic convex probe): the rules of [soft-tissue, Algorithm 1 lines 6-22], one
// function each, on device::Vec3 so that the CPU (soft_tissue/tissue_contacts.cc) and the CUDA
// solver (pbd_cuda_solver.cu) run the same code. Every correction goes to the particle: the
// bodies are static or kinematic (infinite mass).
#include <algorithm>

#include "physics/pbd/device_math.h"

namespace pcisim::physics::pbd::device {

constexpr int kMaxContactFaces = 8;   // a cuboid probe has 6
constexpr int kMaxContactBodies = 2;  // the slots a particle has: one per body

// a plane in world coordinates, its free side normal . x >= offset_m (normal unit, out of the solid)
struct ContactFace {
  Vec3 normal{0.0, 0.0, 1.0};
  double offset_m = 0.0;
};

// one body over one substep: its faces where it is at the substep's end, and its motion over the
// substep (x moved with the body: end_rotation start_rotation^T (x - start_position) + end_position)
struct ContactBody {
  int faces = 0;
  ContactFace face[kMaxContactFaces];
  bool moving = false;
  Mat3 start_rotation, end_rotation;
  Vec3 start_position_m, end_position_m;
  double mu_static = 0.0, mu_kinetic = 0.0;
};

// one particle's contact with one body during a substep
struct ContactSlot {
  ContactFace plane;      // the face it is held against
  Vec3 surface_shift_m;   // the body's motion at the particle over the substep
  double normal_m = 0.0;  // normal correction so far this substep
  Vec3 friction_m;        // friction correction so far this substep
};

PCISIM_HD inline Vec3 transpose_times(const Mat3& a, Vec3 v) {
  return {dot(a.col(0), v), dot(a.col(1), v), dot(a.col(2), v)};
}

// gap of a particle (a sphere of radius r about x) to a plane, negative when it penetrates:
//   C(x) = n . x - d - r
PCISIM_HD inline double plane_gap_m(Vec3 x_m, const ContactFace& plane, double radius_m) {
  return dot(plane.normal, x_m) - plane.offset_m - radius_m;
}

// non-penetration, the inequality C(x) >= 0 [soft-tissue eq 2] projected by [soft-tissue eqs 4-5]
// with grad C = n and the other body's inverse mass 0: lambda = -C / w, dx = w lambda n, i.e.
// dx = -min(C, 0) n, all of it to the particle [soft-tissue, Algorithm 1 lines 12 and 19].
// Returns the normal correction's length, >= 0.
PCISIM_HD inline double non_penetration_m(const ContactFace& plane, double radius_m, Vec3* x_m) {
  const double c = plane_gap_m(*x_m, plane, radius_m);
  if (!(c < 0.0)) return 0.0;
  *x_m = *x_m - c * plane.normal;
  return -c;
}

// Coulomb friction as a positional correction (the paper's "shape friction" [soft-tissue,
// Table 1], as in FleX: Macklin et al. 2014, the paper's ref [16]; the form of [guidewire eq
// 17-18] with separate static and kinetic coefficients):
// slip = the tangential relative displacement of the contact over the substep, dn = the
// normal correction it received. Static: |slip| <= mu_s dn, the slip is undone (dx = -slip);
// kinetic: otherwise, the slip is shortened by mu_k dn (dx = -slip min(1, mu_k dn / |slip|)).
PCISIM_HD inline Vec3 coulomb_friction_m(Vec3 slip_m, double normal_correction_m, double mu_static, double mu_kinetic) {
  const double len = norm(slip_m);
  if (!(len > 0.0)) return Vec3{};
  if (len <= mu_static * normal_correction_m) return -1.0 * slip_m;
  return (-std::min(1.0, mu_kinetic * normal_correction_m / len)) * slip_m;
}

// the face of least penetration [soft-tissue, "Collision and data preparation": the probe is a
// convex body, an intersection of half-spaces]: a point is pushed out through the face whose
// plane is nearest, i.e. the largest signed distance n_i . x - d_i (inside, all are <= 0);
// outside, the same face is the one that separates it best. Ties go to the lowest index. Returns
// the face index (-1 when there are no faces) and writes its signed distance.
PCISIM_HD inline int least_penetration_face(const ContactFace* faces, int count, Vec3 x_m, double* signed_distance_m) {
  int best = -1;
  double best_d = 0.0;
  for (int i = 0; i < count; ++i) {
    const double d = dot(faces[i].normal, x_m) - faces[i].offset_m;
    if (best < 0 || d > best_d) best = i, best_d = d;  // strict: a tie keeps the first face
  }
  *signed_distance_m = best_d;
  return best;
}

// [soft-tissue, Algorithm 1 lines 6-9] a candidate contact: the particle's start x or predicted
// x* is within its contact distance plus a margin of the body. The face is chosen from where the
// particle starts the substep, against the body where it is at the end: the body pushes a
// particle it has moved onto back out of the side it came from. Fills the slot (its corrections
// zeroed) and returns true, or returns false.
PCISIM_HD inline bool find_contact(const ContactBody& body, Vec3 x_m, Vec3 xp_m, double radius_m, double margin_m,
                                   ContactSlot* slot) {
  double d_start = 0.0, d_pred = 0.0;
  const int face = least_penetration_face(body.face, body.faces, x_m, &d_start);
  least_penetration_face(body.face, body.faces, xp_m, &d_pred);
  if (face < 0 || !(std::min(d_start, d_pred) - radius_m < margin_m)) return false;
  slot->plane = body.face[face];
  // the body's motion at the particle over the substep, for the relative slip of friction
  slot->surface_shift_m = body.moving
                              ? body.end_rotation * transpose_times(body.start_rotation, x_m - body.start_position_m) +
                                    body.end_position_m - x_m
                              : Vec3{};
  slot->normal_m = 0.0;
  slot->friction_m = Vec3{};
  return true;
}

// [soft-tissue, Algorithm 1 lines 10-15] stabilisation: the contact solved on the start position
// x and the same correction added to x and x*, so x* - x (the velocity) is unchanged: overlap that
// exists at the start of the substep is removed without launching the particle. Returns the move.
PCISIM_HD inline double stabilise_contact(const ContactSlot& slot, double radius_m, Vec3* x_m, Vec3* xp_m) {
  Vec3 x = *x_m;
  const double moved = non_penetration_m(slot.plane, radius_m, &x);
  if (moved == 0.0) return 0.0;
  *xp_m = *xp_m + (x - *x_m);
  *x_m = x;
  return moved;
}

// the contact group of [soft-tissue, Algorithm 1 lines 17-21], one contact: non-penetration on
// x*, then Coulomb friction on the slip relative to the body (x the substep's start)
PCISIM_HD inline void project_contact(ContactSlot* slot, double radius_m, double mu_static, double mu_kinetic, Vec3 x_m,
                                      Vec3* xp_m) {
  Vec3 p = *xp_m;
  slot->normal_m += non_penetration_m(slot->plane, radius_m, &p);
  if (slot->normal_m > 0.0 && mu_static > 0.0) {
    // slip without friction = the slip now minus what friction already took away
    const Vec3 d = p - x_m - slot->surface_shift_m;
    const Vec3 slip = (d - dot(slot->plane.normal, d) * slot->plane.normal) - slot->friction_m;
    const Vec3 total = coulomb_friction_m(slip, slot->normal_m, mu_static, mu_kinetic);
    p = p + (total - slot->friction_m);
    slot->friction_m = total;
  }
  *xp_m = p;
}

// force the particle's contact puts on the body: -(the momentum the contact gave the particle) / h;
// a correction dx is a velocity change dx / h [soft-tissue eq 6], so F = -m dx / h^2
PCISIM_HD inline Vec3 contact_force_n(const ContactSlot& slot, double mass_kg, double inv_h2) {
  return (-mass_kg * inv_h2) * (slot.normal_m * slot.plane.normal + slot.friction_m);
}

}  // namespace pcisim::physics::pbd::device
