#pragma once
// The lookup of TetLocator (tet_locator.h) as plain arrays, written once for the CPU renderer and
// its CUDA twin: which deformed tet holds a point, and where that point was in the undeformed CT.
#include "ultrasound/echo/echo_rules.h"  // PCISIM_HD

namespace pcisim::ultrasound {

// the locator's arrays (host or device pointers): per tet its current edge matrix's inverse and
// its rest edges (9 doubles each, column-major), its first vertex now and at rest (3 each), and
// whether it is usable now; a uniform grid over the current tets' bounds, CSR (the tets of cell i
// are entries[cell_start[i] .. cell_start[i+1]))
struct LocatorView {
  int tet_count = 0;
  const double* inv_current = nullptr;
  const double* v0_current = nullptr;
  const double* edges_rest = nullptr;
  const double* v0_rest = nullptr;
  const unsigned char* valid = nullptr;
  int dims[3] = {1, 1, 1};
  double lo[3] = {0, 0, 0}, inv_cell[3] = {1, 1, 1};
  const int* cell_start = nullptr;
  const int* entries = nullptr;
};

// barycentric coordinates in the deformed tet t, lambda = E_current^-1 (p - v0), reused in the rest
// tet: rest = r0 + E_rest lambda [soft-tissue paper, "Weighted matrix blending"]; inside when every
// coordinate is >= 0 (to 1e-9)
PCISIM_HD inline bool rest_point_in_tet(const LocatorView& v, int t, const double (&p)[3], double (&rest)[3]) {
  if (!v.valid[t]) return false;
  constexpr double kEps = 1e-9;
  const double* m = v.inv_current + 9 * t;
  const double* o = v.v0_current + 3 * t;
  const double d[3] = {p[0] - o[0], p[1] - o[1], p[2] - o[2]};
  double l[3];
  for (int i = 0; i < 3; ++i) l[i] = m[i] * d[0] + m[i + 3] * d[1] + m[i + 6] * d[2];
  if (!(l[0] >= -kEps && l[1] >= -kEps && l[2] >= -kEps && l[0] + l[1] + l[2] <= 1.0 + kEps)) return false;
  const double* e = v.edges_rest + 9 * t;
  const double* r = v.v0_rest + 3 * t;
  for (int i = 0; i < 3; ++i) rest[i] = r[i] + (e[i] * l[0] + e[i + 3] * l[1] + e[i + 6] * l[2]);
  return true;
}

// true and the rest-space point when p (current configuration) lies in a tet; the tet in *hint is
// tried first (a scanline's next sample is mostly in its predecessor's tet) and the one found is
// left there (-1: none yet)
PCISIM_HD inline bool rest_point(const LocatorView& v, const double (&p)[3], double (&rest)[3], int* hint) {
  if (v.tet_count == 0) return false;
  if (*hint >= 0 && *hint < v.tet_count && rest_point_in_tet(v, *hint, p, rest)) return true;
  int c[3];
  for (int k = 0; k < 3; ++k) {
    const double u = (p[k] - v.lo[k]) * v.inv_cell[k];
    if (!(u >= 0.0 && u <= v.dims[k])) return false;
    c[k] = static_cast<int>(u) < v.dims[k] - 1 ? static_cast<int>(u) : v.dims[k] - 1;
  }
  const int cell = c[0] + v.dims[0] * (c[1] + v.dims[1] * c[2]);
  for (int e = v.cell_start[cell]; e < v.cell_start[cell + 1]; ++e)
    if (rest_point_in_tet(v, v.entries[e], p, rest)) {
      *hint = v.entries[e];
      return true;
    }
  return false;
}

}  // namespace pcisim::ultrasound
