// eigen (through the public headers) trips nvcc's note on defaulted __host__ __device__ members
#pragma nv_diag_suppress 20012
#include "physics/pbd/pbd_cuda_solver.h"

#include <cuda_runtime.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "physics/pbd/device_constraints.h"
#include "physics/pbd/device_contacts.h"
#include "physics/pbd/device_rotation.h"
#include "physics/pbd/pbd_system.h"

namespace pcisim::physics::pbd {
namespace {

using device::ContactBody;
using device::ContactSlot;
using device::Mat3;
using device::Vec3;

constexpr int kThreads = 256;
// a cluster's slots are reduced in chunks of this many (one block each), so one global cluster
// of 50k particles spreads over ~200 blocks instead of serialising in one
constexpr int kChunk = 256;

void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess) throw std::runtime_error(std::string("pbd CUDA ") + what + ": " + cudaGetErrorString(e));
}

int blocks_for(long n) {
  return static_cast<int>((n + kThreads - 1) / kThreads);
}

template <class T>
struct DeviceArray {
  T* ptr = nullptr;
  size_t n = 0;
  DeviceArray() = default;
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  ~DeviceArray() {
    if (ptr) cudaFree(ptr);
  }
  void allocate(size_t count) {
    if (ptr) cudaFree(ptr), ptr = nullptr;
    n = count;
    if (n) check(cudaMalloc(&ptr, n * sizeof(T)), "cudaMalloc");
  }
  void upload(const T* host, size_t count) {
    allocate(count);
    if (n) check(cudaMemcpy(ptr, host, n * sizeof(T), cudaMemcpyHostToDevice), "upload");
  }
  void upload(const std::vector<T>& host) { upload(host.data(), host.size()); }
};

// --- kernels: one thread per particle, constraint or slot unless said otherwise ---

enum : uint8_t { kFree = 0, kPinned = 1, kDriven = 2, kQuarantined = 3 };
static_assert(static_cast<uint8_t>(ParticleState::kFree) == kFree &&
              static_cast<uint8_t>(ParticleState::kPinned) == kPinned &&
              static_cast<uint8_t>(ParticleState::kDriven) == kDriven &&
              static_cast<uint8_t>(ParticleState::kQuarantined) == kQuarantined);

// Algorithm 1 lines 1-5 (PbdSystem::predict)
__global__ void predict(int n, const uint8_t* state, double* x, double* xp, double* v, const double* start,
                        const double* target, double h, double fraction, bool last, Vec3 gravity, double drag) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  switch (state[i]) {
    case kFree: {
      const Vec3 vi = drag * device::load(v, i) + h * gravity;
      device::store(v, i, vi);
      device::store(xp, i, device::load(x, i) + h * vi);
      break;
    }
    case kDriven: {
      const Vec3 s = device::load(start, i), t = device::load(target, i);
      device::store(xp, i, last ? t : s + fraction * (t - s));
      break;
    }
    default:
      device::store(xp, i, device::load(x, i));
  }
}

// Algorithm 1 lines 23-26 with the NaN guard (PbdSystem::update, PbdSystem::quarantine)
__global__ void update(int n, uint8_t* state, double* x, double* xp, double* v, double* inv_mass, double inv_h) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  const Vec3 p = device::load(xp, i), xi = device::load(x, i);
  if (!device::finite(p)) {
    device::store(xp, i, xi);
    device::store(v, i, Vec3{});
    inv_mass[i] = 0.0;
    state[i] = kQuarantined;
    return;
  }
  device::store(v, i, inv_h * (p - xi));
  device::store(x, i, p);
}

// Jacobi, distance group: corrections into the constraint's own two slots (PbdSystem::solve_jacobi)
__global__ void project_distances(int count, const int2* ij, const double* rest_m, const double* compliance,
                                  const double* mean_inv, const double* min_inv, double* lambda, double* slot,
                                  const double* xp, const double* w, double inv_h2, double sor_w, bool per_particle) {
  const int k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k >= count) return;
  const int2 c = ij[k];
  double dl;
  Vec3 dxi, dxj;
  if (device::project_distance(device::load(xp, c.x), device::load(xp, c.y), w[c.x], w[c.y], rest_m[k],
                               compliance[k] * inv_h2, lambda[k], &dl, &dxi, &dxj)) {
    const double share = per_particle ? 1.0 : min_inv[k];
    lambda[k] += sor_w * (per_particle ? mean_inv[k] : share) * dl;
    device::store(slot, 2 * k, share * dxi);
    device::store(slot, 2 * k + 1, share * dxj);
  } else {
    device::store(slot, 2 * k, Vec3{});
    device::store(slot, 2 * k + 1, Vec3{});
  }
}

__global__ void project_bendings(int count, const int4* abcd, const double* rest_rad, const double* compliance,
                                 const double* mean_inv, const double* min_inv, double* lambda, double* slot,
                                 const double* xp, const double* w, double inv_h2, double sor_w, bool per_particle) {
  const int k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k >= count) return;
  const int4 c = abcd[k];
  const int idx[4] = {c.x, c.y, c.z, c.w};
  Vec3 xs[4], dx[4];
  double ws[4], dl;
  for (int m = 0; m < 4; ++m) xs[m] = device::load(xp, idx[m]), ws[m] = w[idx[m]];
  const bool ok = device::project_dihedral_bending(xs, ws, rest_rad[k], compliance[k] * inv_h2, lambda[k], &dl, dx);
  const double share = per_particle ? 1.0 : min_inv[k];
  if (ok) lambda[k] += sor_w * (per_particle ? mean_inv[k] : share) * dl;
  for (int m = 0; m < 4; ++m) device::store(slot, 4 * k + m, ok ? share * dx[m] : Vec3{});
}

// eq 7: x_i += w * sum(slots of i) / n_i, summed in the CPU's CSR order (JacobiGroup::apply)
__global__ void gather(int n, const int* offset, const int* order, const double* inv_count, const double* slot,
                       double* xp, double sor_w, bool divide_by_count) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n || offset[i] == offset[i + 1]) return;
  Vec3 sum;
  for (int k = offset[i]; k < offset[i + 1]; ++k) sum += device::load(slot, order[k]);
  device::store(xp, i, device::load(xp, i) + (divide_by_count ? sor_w * inv_count[i] : sor_w) * sum);
}

// sum of v over the block (any blockDim that is a multiple of 32, up to 1024); valid in thread 0
__device__ double block_sum(double v, double* shared32) {
  for (int o = 16; o > 0; o >>= 1) v += __shfl_down_sync(0xffffffffu, v, o);
  const int lane = threadIdx.x & 31, warp = threadIdx.x >> 5;
  __syncthreads();  // shared32 may still be read by the previous call
  if (lane == 0) shared32[warp] = v;
  __syncthreads();
  double total = 0.0;
  if (threadIdx.x == 0)
    for (int k = 0; k < int(blockDim.x >> 5); ++k) total += shared32[k];
  return total;
}

// shape matching eq 8, one block per chunk: partial sums of m and m x
__global__ void cluster_mass_partials(const int* chunk_begin, const int* chunk_end, const int* member,
                                      const double* mass, const double* xp, double* partial4) {
  __shared__ double sh[32];
  const int s = chunk_begin[blockIdx.x] + threadIdx.x;
  double m = 0.0;
  Vec3 mx;
  if (s < chunk_end[blockIdx.x]) {
    const int i = member[s];
    m = mass[i];
    mx = m * device::load(xp, i);
  }
  const double sums[4] = {block_sum(m, sh), block_sum(mx.x, sh), block_sum(mx.y, sh), block_sum(mx.z, sh)};
  if (threadIdx.x == 0)
    for (int k = 0; k < 4; ++k) partial4[4 * blockIdx.x + k] = sums[k];
}

// t = sum m x / sum m of cluster c, chunks summed in order (every caller gets the same bits)
__device__ Vec3 cluster_centre(int c, const int* cluster_chunks, const double* partial4) {
  double m = 0.0;
  Vec3 mx;
  for (int k = cluster_chunks[c]; k < cluster_chunks[c + 1]; ++k) {
    m += partial4[4 * k];
    mx += Vec3{partial4[4 * k + 1], partial4[4 * k + 2], partial4[4 * k + 3]};
  }
  return mx / m;
}

// eq 9, one block per chunk: partial sums of A_pq = sum m (x - t) q^T
__global__ void cluster_moment_partials(const int* chunk_begin, const int* chunk_end, const int* chunk_cluster,
                                        const int* cluster_chunks, const double* partial4, const int* member,
                                        const double* mass, const double* xp, const double* rest_offset,
                                        double* partial9) {
  __shared__ double sh[32], t_m[3];
  if (threadIdx.x == 0) {
    const Vec3 c = cluster_centre(chunk_cluster[blockIdx.x], cluster_chunks, partial4);
    t_m[0] = c.x, t_m[1] = c.y, t_m[2] = c.z;
  }
  __syncthreads();
  const Vec3 t{t_m[0], t_m[1], t_m[2]};
  const int s = chunk_begin[blockIdx.x] + threadIdx.x;
  double a[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  if (s < chunk_end[blockIdx.x]) {
    const int i = member[s];
    const Vec3 mp = mass[i] * (device::load(xp, i) - t), q = device::load(rest_offset, s);
    const double qc[3] = {q.x, q.y, q.z};
    for (int col = 0; col < 3; ++col)
      a[3 * col] = mp.x * qc[col], a[3 * col + 1] = mp.y * qc[col], a[3 * col + 2] = mp.z * qc[col];
  }
  for (int k = 0; k < 9; ++k) {
    const double total = block_sum(a[k], sh);
    if (threadIdx.x == 0) partial9[9 * blockIdx.x + k] = total;
  }
}

// eqs 9-10, one thread per cluster: A_pq from its chunks, R by polar decomposition, t kept for the goals
__global__ void cluster_rotations(int count, const int* cluster_chunks, const double* partial4, const double* partial9,
                                  const double* rest_moment, Mat3* rotation, Vec3* centre) {
  const int c = blockIdx.x * blockDim.x + threadIdx.x;
  if (c >= count) return;
  Mat3 a;
  for (int k = cluster_chunks[c]; k < cluster_chunks[c + 1]; ++k)
    for (int e = 0; e < 9; ++e) a.m[e] += partial9[9 * k + e];
  rotation[c] = device::extract_rotation(a, rotation[c], rest_moment[c]);
  centre[c] = cluster_centre(c, cluster_chunks, partial4);
}

// eq 10 goals g = R q + t and eq 12 as XPBD, into the slot's own correction
__global__ void project_goals(int slots, const int* member, const int* slot_cluster, const double* rest_offset,
                              const Mat3* rotation, const Vec3* centre, const double* compliance, const double* min_inv,
                              const double* inv_count, const double* mass, const double* w, const double* xp,
                              double* lambda, double* slot, double h, double sor_w, bool per_particle) {
  const int s = blockIdx.x * blockDim.x + threadIdx.x;
  if (s >= slots) return;
  const int c = slot_cluster[s], i = member[s];
  const Vec3 goal = rotation[c] * device::load(rest_offset, s) + centre[c];
  Vec3 dl, dx;
  if (device::project_to_goal(device::load(xp, i), goal, w[i], mass[i], compliance[c], h, device::load(lambda, s), &dl,
                              &dx)) {
    const double share = per_particle ? 1.0 : min_inv[c];
    device::store(lambda, s, device::load(lambda, s) + (sor_w * (per_particle ? inv_count[i] : share)) * dl);
    device::store(slot, s, share * dx);
  } else {
    device::store(slot, s, Vec3{});
  }
}

// a * b, column by column
__device__ Mat3 mul(const Mat3& a, const Mat3& b) {
  Mat3 out;
  for (int c = 0; c < 3; ++c) out.set_col(c, a * b.col(c));
  return out;
}

// the cluster volume C = det(F) - 1, F = A_pq A_qq^-1 (ShapeMatchingClusters::volume_correction,
// its order of operations): dlambda from the members' gradients G q_i, summed in member order.
// False (no correction) when the cluster has none or the fit is degenerate
__device__ bool volume_rule(int c, const int* offset, const int* member, const Mat3& apq, const Mat3* aqq_inverse,
                            const double* volume_compliance, const double* rest_offset, const double* mass,
                            const double* w, double lambda, double h, double* dlambda, Mat3* gradient) {
  const double alpha = volume_compliance[c];
  if (alpha < 0.0) return false;
  const Mat3 f = mul(apq, aqq_inverse[c]);
  // cof(F) = det(F) F^-T, column by column from cross products (defined for a singular F too)
  Mat3 cof;
  cof.set_col(0, device::cross(f.col(1), f.col(2)));
  cof.set_col(1, device::cross(f.col(2), f.col(0)));
  cof.set_col(2, device::cross(f.col(0), f.col(1)));
  const double constraint = device::dot(f.col(0), cof.col(0)) - 1.0;
  const Mat3 g = mul(cof, aqq_inverse[c]);
  double denom = alpha / (h * h);
  for (int s = offset[c]; s < offset[c + 1]; ++s) {
    const int i = member[s];
    denom += w[i] * mass[i] * mass[i] * device::squared_norm(g * device::load(rest_offset, s));
  }
  if (!(denom > 0.0) || !std::isfinite(denom) || !std::isfinite(constraint)) return false;
  *dlambda = (-constraint - alpha / (h * h) * lambda) / denom;
  *gradient = g;
  return true;
}

// the volume group, one thread per cluster (clusters of several chunks): A_pq from its chunks, the
// rule, the multiplier advanced by the share the averaging delivers
__global__ void cluster_volumes(int count, const int* offset, const int* member, const int* cluster_chunks,
                                const double* partial9, const Mat3* aqq_inverse, const double* volume_compliance,
                                const double* delivered, const double* rest_offset, const double* mass, const double* w,
                                double* lambda, double* dlambda, Mat3* gradient, double h, double sor_w) {
  const int c = blockIdx.x * blockDim.x + threadIdx.x;
  if (c >= count) return;
  dlambda[c] = 0.0;
  Mat3 a;
  for (int k = cluster_chunks[c]; k < cluster_chunks[c + 1]; ++k)
    for (int e = 0; e < 9; ++e) a.m[e] += partial9[9 * k + e];
  double dl = 0.0;
  Mat3 g;
  if (!volume_rule(c, offset, member, a, aqq_inverse, volume_compliance, rest_offset, mass, w, lambda[c], h, &dl, &g))
    return;
  lambda[c] += sor_w * delivered[c] * dl;
  dlambda[c] = dl;
  gradient[c] = g;
}

// thread's slot of the cluster this block does (block c = cluster c), its member's mass,
// position and rest offset; mine is false for the threads past the cluster's slots
struct BlockSlot {
  bool mine = false;
  int s = 0, i = 0;
  double m = 0.0;
  Vec3 x, q;
};
__device__ BlockSlot block_slot(const int* offset, const int* member, const double* mass, const double* xp,
                                const double* rest_offset) {
  BlockSlot b;
  b.s = offset[blockIdx.x] + threadIdx.x;
  b.mine = b.s < offset[blockIdx.x + 1];
  if (!b.mine) return b;
  b.i = member[b.s];
  b.m = mass[b.i];
  b.x = device::load(xp, b.i);
  b.q = device::load(rest_offset, b.s);
  return b;
}

// the centre t (every thread) and A_pq = sum m (x - t) q^T (thread 0) of a cluster that fits one
// block (eqs 8-9), summed as cluster_mass_partials / cluster_moment_partials sum a one-chunk cluster;
// every thread of the block must call it (it synchronises)
__device__ void block_fit(const BlockSlot& b, double* sh, double* shared_t, Vec3* t, Mat3* apq) {
  const bool mine = b.mine;
  const double m = b.m;
  const Vec3 x = b.x, q = b.q;
  const Vec3 mx = m * x;
  const double sums[4] = {block_sum(m, sh), block_sum(mx.x, sh), block_sum(mx.y, sh), block_sum(mx.z, sh)};
  if (threadIdx.x == 0) {
    // cluster_centre's order: 0 + the chunk's sum, then the division
    const Vec3 c = (Vec3{} + Vec3{sums[1], sums[2], sums[3]}) / (0.0 + sums[0]);
    shared_t[0] = c.x, shared_t[1] = c.y, shared_t[2] = c.z;
  }
  __syncthreads();
  *t = Vec3{shared_t[0], shared_t[1], shared_t[2]};
  double a[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  if (mine) {
    const Vec3 mp = m * (x - *t);
    const double qc[3] = {q.x, q.y, q.z};
    for (int col = 0; col < 3; ++col)
      a[3 * col] = mp.x * qc[col], a[3 * col + 1] = mp.y * qc[col], a[3 * col + 2] = mp.z * qc[col];
  }
  for (int k = 0; k < 9; ++k) {
    const double total = block_sum(a[k], sh);
    if (threadIdx.x == 0) apq->m[k] = 0.0 + total;
  }
}

// eqs 8-10 and 12 for a cluster that fits one block (the kidney's do), one block per cluster:
// cluster_mass_partials, cluster_moment_partials, cluster_rotations and project_goals in one
// kernel, the same sums in the same order (a cluster of one chunk)
__global__ void cluster_goals_in_block(const int* offset, const int* member, const double* mass, const double* w,
                                       const double* xp, const double* rest_offset, const double* rest_moment,
                                       const double* compliance, const double* min_inv, const double* inv_count,
                                       Mat3* rotation, double* lambda, double* slot, double h, double sor_w,
                                       bool per_particle) {
  __shared__ double sh[32], shared_t[3], shared_r[9];
  const int c = blockIdx.x;
  const BlockSlot b = block_slot(offset, member, mass, xp, rest_offset);
  Vec3 t;
  Mat3 apq;
  block_fit(b, sh, shared_t, &t, &apq);
  const int s = b.s, i = b.i;
  if (threadIdx.x == 0) {
    const Mat3 r = device::extract_rotation(apq, rotation[c], rest_moment[c]);
    rotation[c] = r;
    for (int k = 0; k < 9; ++k) shared_r[k] = r.m[k];
  }
  __syncthreads();
  if (!b.mine) return;
  Mat3 r;
  for (int k = 0; k < 9; ++k) r.m[k] = shared_r[k];
  const Vec3 goal = r * b.q + t;
  Vec3 dl, dx;
  if (device::project_to_goal(b.x, goal, w[i], b.m, compliance[c], h, device::load(lambda, s), &dl, &dx)) {
    const double share = per_particle ? 1.0 : min_inv[c];
    device::store(lambda, s, device::load(lambda, s) + (sor_w * (per_particle ? inv_count[i] : share)) * dl);
    device::store(slot, s, share * dx);
  } else {
    device::store(slot, s, Vec3{});
  }
}

// the volume group for a cluster that fits one block, one block per cluster: the centre and A_pq
// as cluster_goals_in_block sums them, then cluster_volumes' rule (thread 0) and volume_slots
__global__ void cluster_volume_in_block(const int* offset, const int* member, const double* mass, const double* w,
                                        const double* xp, const double* rest_offset, const Mat3* aqq_inverse,
                                        const double* volume_compliance, const double* delivered, const double* min_inv,
                                        double* lambda, double* slot, double h, double sor_w, bool per_particle) {
  __shared__ double sh[32], shared_t[3], shared_g[9], shared_dl;
  const BlockSlot b = block_slot(offset, member, mass, xp, rest_offset);
  Vec3 t;
  Mat3 apq;  // the volume's F = A_pq A_qq^-1 needs no centre beyond A_pq's
  block_fit(b, sh, shared_t, &t, &apq);
  const int c = blockIdx.x;
  if (threadIdx.x == 0) {
    double dl = 0.0;
    Mat3 g;
    if (volume_rule(c, offset, member, apq, aqq_inverse, volume_compliance, rest_offset, mass, w, lambda[c], h, &dl,
                    &g)) {
      lambda[c] += sor_w * delivered[c] * dl;
      for (int k = 0; k < 9; ++k) shared_g[k] = g.m[k];
    }
    shared_dl = dl;
  }
  __syncthreads();
  if (!b.mine) return;
  const double dl = shared_dl;
  const double share = per_particle ? 1.0 : min_inv[c];
  if (dl == 0.0) {
    device::store(slot, b.s, Vec3{});
    return;
  }
  Mat3 g;
  for (int k = 0; k < 9; ++k) g.m[k] = shared_g[k];
  device::store(slot, b.s, share * ((w[b.i] * b.m * dl) * (g * b.q)));
}

// eq 7's gather (see gather), then the contact group for the particle: the last group of an
// iteration and the contacts in one kernel
__global__ void gather_then_contacts(int n, const int* offset, const int* order, const double* inv_count,
                                     const double* group_slot, double* xp, double sor_w, bool divide_by_count,
                                     int bodies, const ContactBody* body, const double* radius, const double* x,
                                     ContactSlot* slot, const uint8_t* active) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  Vec3 p = device::load(xp, i);
  if (offset[i] != offset[i + 1]) {
    Vec3 sum;
    for (int k = offset[i]; k < offset[i + 1]; ++k) sum += device::load(group_slot, order[k]);
    p = p + (divide_by_count ? sor_w * inv_count[i] : sor_w) * sum;
  }
  const Vec3 xi = device::load(x, i);
  for (int b = 0; b < bodies; ++b)
    if (active[i * bodies + b])
      device::project_contact(&slot[i * bodies + b], radius[i], body[b].mu_static, body[b].mu_kinetic, xi, &p);
  device::store(xp, i, p);
}

// each member's volume correction dx_i = w_i m_i dlambda G q_i into its slot, one thread per slot
__global__ void volume_slots(int slots, const int* member, const int* slot_cluster, const double* rest_offset,
                             const Mat3* gradient, const double* dlambda, const double* min_inv, const double* mass,
                             const double* w, double* slot, bool per_particle) {
  const int s = blockIdx.x * blockDim.x + threadIdx.x;
  if (s >= slots) return;
  const int c = slot_cluster[s], i = member[s];
  const double dl = dlambda[c];
  const double share = per_particle ? 1.0 : min_inv[c];
  if (dl == 0.0) {
    device::store(slot, s, Vec3{});
    return;
  }
  const Vec3 dx = (w[i] * mass[i] * dl) * (gradient[c] * device::load(rest_offset, s));
  device::store(slot, s, share * dx);
}

// [soft-tissue, Algorithm 1 lines 6-15] per particle: its contacts with each body
// (device::find_contact), then the stabilisation passes (device::stabilise_contact) on x and x*
__global__ void find_contacts(int n, int bodies, const ContactBody* body, const double* w, const double* radius,
                              double margin, int stabilisation_iterations, double* x, double* xp, ContactSlot* slot,
                              uint8_t* active, unsigned long long* stabilisation_max_bits) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  for (int b = 0; b < bodies; ++b) active[i * bodies + b] = 0;
  if (!(w[i] > 0.0)) return;  // pinned, driven or quarantined
  Vec3 xi = device::load(x, i), pi = device::load(xp, i);
  const double r = radius[i];
  bool any = false;
  for (int b = 0; b < bodies; ++b)
    if (device::find_contact(body[b], xi, pi, r, margin, &slot[i * bodies + b])) active[i * bodies + b] = 1, any = true;
  if (!any) return;
  double most = 0.0;
  for (int it = 0; it < stabilisation_iterations; ++it)
    for (int b = 0; b < bodies; ++b)
      if (active[i * bodies + b]) most = fmax(most, device::stabilise_contact(slot[i * bodies + b], r, &xi, &pi));
  if (most > 0.0) {
    device::store(x, i, xi);
    device::store(xp, i, pi);
    // a non-negative double orders as its bits do
    atomicMax(stabilisation_max_bits, static_cast<unsigned long long>(__double_as_longlong(most)));
  }
}

// the contact group after each iteration [soft-tissue, Algorithm 1 lines 17-21] (device::project_contact)
__global__ void project_contacts(int n, int bodies, const ContactBody* body, const double* radius, const double* x,
                                 double* xp, ContactSlot* slot, const uint8_t* active) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  bool any = false;
  for (int b = 0; b < bodies; ++b) any = any || active[i * bodies + b];
  if (!any) return;
  const Vec3 xi = device::load(x, i);
  Vec3 pi = device::load(xp, i);
  for (int b = 0; b < bodies; ++b)
    if (active[i * bodies + b])
      device::project_contact(&slot[i * bodies + b], radius[i], body[b].mu_static, body[b].mu_kinetic, xi, &pi);
  device::store(xp, i, pi);
}

// each block's sum of the contacts' forces on each body (device::contact_force_n) and their count:
// partial[(block * bodies + b) * 4 + {0, 1, 2}] the force, + 3 the count; kThreads a block
__global__ void contact_forces(int n, int bodies, const double* mass, const ContactSlot* slot, const uint8_t* active,
                               double inv_h2, double* partial) {
  __shared__ double sh[32];
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  for (int b = 0; b < bodies; ++b) {
    Vec3 f;
    double one = 0.0;
    if (i < n && active[i * bodies + b]) f = device::contact_force_n(slot[i * bodies + b], mass[i], inv_h2), one = 1.0;
    const double sums[4] = {block_sum(f.x, sh), block_sum(f.y, sh), block_sum(f.z, sh), block_sum(one, sh)};
    if (threadIdx.x == 0)
      for (int k = 0; k < 4; ++k) partial[(blockIdx.x * bodies + b) * 4 + k] = sums[k];
  }
}

struct Gather {
  DeviceArray<int> offset, order;
  DeviceArray<double> inv_count;
  void upload(const JacobiGroup& g) {
    offset.upload(g.offsets().data(), g.offsets().size());
    order.upload(g.slot_order().data(), g.slot_order().size());
    inv_count.upload(g.inverse_counts().data(), g.inverse_counts().size());
  }
};

}  // namespace

bool pbd_cuda_available(std::string* why) {
  int count = 0;
  const cudaError_t e = cudaGetDeviceCount(&count);
  if (e != cudaSuccess || count == 0) {
    if (why) *why = e != cudaSuccess ? cudaGetErrorString(e) : "no CUDA device";
    cudaGetLastError();  // clear it, so later CUDA calls do not report it again
    return false;
  }
  return true;
}

std::string pbd_cuda_device_name() {
  if (!pbd_cuda_available()) return {};
  int dev = 0;
  cudaDeviceProp prop{};
  if (cudaGetDevice(&dev) != cudaSuccess || cudaGetDeviceProperties(&prop, dev) != cudaSuccess) return {};
  return prop.name;
}

struct PbdCudaSolver::Impl {
  int n = 0, distances = 0, bendings = 0, clusters = 0, slots = 0, chunks = 0;
  cudaStream_t stream = nullptr;
  cudaEvent_t ev[4] = {nullptr, nullptr, nullptr, nullptr};
  // particles
  DeviceArray<double> x, xp, v, start, target, mass, inv_mass;
  DeviceArray<uint8_t> state;
  // distance group
  DeviceArray<int2> d_ij;
  DeviceArray<double> d_rest, d_compliance, d_mean_inv, d_min_inv, d_lambda, d_slot;
  Gather d_gather;
  // bending group
  DeviceArray<int4> b_abcd;
  DeviceArray<double> b_rest, b_compliance, b_mean_inv, b_min_inv, b_lambda, b_slot;
  Gather b_gather;
  // clusters
  DeviceArray<int> member, slot_cluster, chunk_begin, chunk_end, chunk_cluster, cluster_chunks;
  DeviceArray<double> rest_offset, rest_moment, c_compliance, c_min_inv, c_lambda, c_slot, partial4, partial9;
  DeviceArray<Mat3> rotation;
  DeviceArray<Vec3> centre;
  Gather c_gather;
  DeviceArray<int> c_offset;  // each cluster's first slot, and the end
  // every cluster within one chunk: one block per cluster does its whole group (*_in_block)
  bool in_block = false;
  int block_threads = kChunk;  // the largest cluster's slots, rounded up to whole warps
  // cluster volumes (none when no cluster has one)
  bool volumes = false;
  DeviceArray<Mat3> v_aqq_inverse, v_gradient;
  DeviceArray<double> v_compliance, v_delivered, v_lambda, v_dlambda;
  std::vector<double> v_delivered_per_particle, v_delivered_per_constraint;  // uploaded to v_delivered by averaging
  std::vector<double> host_compliance, host_rotation;                        // staging, sized once
  // contacts (ContactProjector::device_setup): a slot per particle and body; the bodies of each
  // substep and the force partials per substep and block, sized when the substeps change
  int bodies = 0, stabilisation_iterations = 0;
  double margin_m = 0.0;
  std::vector<double> host_radius;  // the radii last uploaded
  DeviceArray<double> k_radius, k_partial;
  DeviceArray<ContactSlot> k_slot;
  DeviceArray<uint8_t> k_active;
  DeviceArray<ContactBody> k_body;
  DeviceArray<unsigned long long> k_stabilisation_max;
  std::vector<ContactBody> host_body;
  std::vector<double> host_partial;
  // the captured step and what it was captured for
  cudaGraphExec_t graph = nullptr;
  struct Key {
    double dt = 0, sor_w = 0, damping = 0, g[3] = {0, 0, 0};
    int substeps = 0, iterations = 0;
    JacobiAveraging averaging{};
    int bodies = 0, stabilisation_iterations = 0;
    double margin_m = 0.0;
    bool operator==(const Key& o) const {
      return dt == o.dt && sor_w == o.sor_w && damping == o.damping && g[0] == o.g[0] && g[1] == o.g[1] &&
             g[2] == o.g[2] && substeps == o.substeps && iterations == o.iterations && averaging == o.averaging &&
             bodies == o.bodies && stabilisation_iterations == o.stabilisation_iterations && margin_m == o.margin_m;
    }
  } key;

  ~Impl() {
    if (graph) cudaGraphExecDestroy(graph);
    for (auto& e : ev)
      if (e) cudaEventDestroy(e);
    if (stream) cudaStreamDestroy(stream);
  }

  // each chunk's partial sums of m, m x (partial4) and A_pq (partial9) at the current x*
  void chunk_sums() {
    cluster_mass_partials<<<chunks, kChunk, 0, stream>>>(chunk_begin.ptr, chunk_end.ptr, member.ptr, mass.ptr, xp.ptr,
                                                         partial4.ptr);
    cluster_moment_partials<<<chunks, kChunk, 0, stream>>>(chunk_begin.ptr, chunk_end.ptr, chunk_cluster.ptr,
                                                           cluster_chunks.ptr, partial4.ptr, member.ptr, mass.ptr,
                                                           xp.ptr, rest_offset.ptr, partial9.ptr);
  }

  // one Jacobi iteration (PbdSystem::solve_jacobi); with contacts, their group rides on the
  // iteration's last gather (gather_then_contacts)
  void solve_jacobi(double h, double sor_w, bool per_particle, const ContactBody* body) {
    const double inv_h2 = 1.0 / (h * h);
    const int last = volumes ? 3 : clusters > 0 ? 2 : bendings > 0 ? 1 : distances > 0 ? 0 : -1;
    auto gather_group = [&](const Gather& g, const double* group_slot, int group) {
      if (group == last && bodies > 0)
        gather_then_contacts<<<blocks_for(n), kThreads, 0, stream>>>(
            n, g.offset.ptr, g.order.ptr, g.inv_count.ptr, group_slot, xp.ptr, sor_w, per_particle, bodies, body,
            k_radius.ptr, x.ptr, k_slot.ptr, k_active.ptr);
      else
        gather<<<blocks_for(n), kThreads, 0, stream>>>(n, g.offset.ptr, g.order.ptr, g.inv_count.ptr, group_slot,
                                                       xp.ptr, sor_w, per_particle);
    };
    if (distances > 0) {
      project_distances<<<blocks_for(distances), kThreads, 0, stream>>>(
          distances, d_ij.ptr, d_rest.ptr, d_compliance.ptr, d_mean_inv.ptr, d_min_inv.ptr, d_lambda.ptr, d_slot.ptr,
          xp.ptr, inv_mass.ptr, inv_h2, sor_w, per_particle);
      gather_group(d_gather, d_slot.ptr, 0);
    }
    if (bendings > 0) {
      project_bendings<<<blocks_for(bendings), kThreads, 0, stream>>>(
          bendings, b_abcd.ptr, b_rest.ptr, b_compliance.ptr, b_mean_inv.ptr, b_min_inv.ptr, b_lambda.ptr, b_slot.ptr,
          xp.ptr, inv_mass.ptr, inv_h2, sor_w, per_particle);
      gather_group(b_gather, b_slot.ptr, 1);
    }
    if (clusters > 0) {
      if (in_block) {
        cluster_goals_in_block<<<clusters, block_threads, 0, stream>>>(
            c_offset.ptr, member.ptr, mass.ptr, inv_mass.ptr, xp.ptr, rest_offset.ptr, rest_moment.ptr,
            c_compliance.ptr, c_min_inv.ptr, c_gather.inv_count.ptr, rotation.ptr, c_lambda.ptr, c_slot.ptr, h, sor_w,
            per_particle);
      } else {
        chunk_sums();
        cluster_rotations<<<blocks_for(clusters), kThreads, 0, stream>>>(
            clusters, cluster_chunks.ptr, partial4.ptr, partial9.ptr, rest_moment.ptr, rotation.ptr, centre.ptr);
        project_goals<<<blocks_for(slots), kThreads, 0, stream>>>(
            slots, member.ptr, slot_cluster.ptr, rest_offset.ptr, rotation.ptr, centre.ptr, c_compliance.ptr,
            c_min_inv.ptr, c_gather.inv_count.ptr, mass.ptr, inv_mass.ptr, xp.ptr, c_lambda.ptr, c_slot.ptr, h, sor_w,
            per_particle);
      }
      gather_group(c_gather, c_slot.ptr, 2);
    }
    if (volumes) {
      // the volumes as one more group over the same slots, reading the positions the shapes left
      if (in_block) {
        cluster_volume_in_block<<<clusters, block_threads, 0, stream>>>(
            c_offset.ptr, member.ptr, mass.ptr, inv_mass.ptr, xp.ptr, rest_offset.ptr, v_aqq_inverse.ptr,
            v_compliance.ptr, v_delivered.ptr, c_min_inv.ptr, v_lambda.ptr, c_slot.ptr, h, sor_w, per_particle);
      } else {
        chunk_sums();
        cluster_volumes<<<blocks_for(clusters), kThreads, 0, stream>>>(
            clusters, c_offset.ptr, member.ptr, cluster_chunks.ptr, partial9.ptr, v_aqq_inverse.ptr, v_compliance.ptr,
            v_delivered.ptr, rest_offset.ptr, mass.ptr, inv_mass.ptr, v_lambda.ptr, v_dlambda.ptr, v_gradient.ptr, h,
            sor_w);
        volume_slots<<<blocks_for(slots), kThreads, 0, stream>>>(slots, member.ptr, slot_cluster.ptr, rest_offset.ptr,
                                                                 v_gradient.ptr, v_dlambda.ptr, c_min_inv.ptr, mass.ptr,
                                                                 inv_mass.ptr, c_slot.ptr, per_particle);
      }
      gather_group(c_gather, c_slot.ptr, 3);
    }
    if (last < 0 && bodies > 0)
      project_contacts<<<blocks_for(n), kThreads, 0, stream>>>(n, bodies, body, k_radius.ptr, x.ptr, xp.ptr, k_slot.ptr,
                                                               k_active.ptr);
  }

  // the kernels of one PbdSystem::step_on_cpu, in its order
  void enqueue_step(double dt_s, const PbdParams& p) {
    const int substeps = std::max(p.substeps, 1);
    const double h = dt_s / substeps;
    const double drag = 1.0 / (1.0 + std::max(p.damping_per_s, 0.0) * h);
    const Vec3 g{p.gravity_m_per_s2.x(), p.gravity_m_per_s2.y(), p.gravity_m_per_s2.z()};
    const bool per_particle = p.averaging == JacobiAveraging::kPerParticle;
    const int blocks = blocks_for(n);
    check(cudaMemcpyAsync(start.ptr, x.ptr, 3 * sizeof(double) * n, cudaMemcpyDeviceToDevice, stream), "copy start");
    if (bodies > 0)
      check(cudaMemsetAsync(k_stabilisation_max.ptr, 0, sizeof(unsigned long long), stream), "memset stabilisation");
    for (int s = 0; s < substeps; ++s) {
      predict<<<blocks, kThreads, 0, stream>>>(n, state.ptr, x.ptr, xp.ptr, v.ptr, start.ptr, target.ptr, h,
                                               static_cast<double>(s + 1) / substeps, s + 1 == substeps, g, drag);
      const ContactBody* body = k_body.ptr + static_cast<size_t>(s) * bodies;
      if (bodies > 0)
        find_contacts<<<blocks, kThreads, 0, stream>>>(n, bodies, body, inv_mass.ptr, k_radius.ptr, margin_m,
                                                       stabilisation_iterations, x.ptr, xp.ptr, k_slot.ptr,
                                                       k_active.ptr, k_stabilisation_max.ptr);
      if (distances > 0) check(cudaMemsetAsync(d_lambda.ptr, 0, sizeof(double) * distances, stream), "memset");
      if (bendings > 0) check(cudaMemsetAsync(b_lambda.ptr, 0, sizeof(double) * bendings, stream), "memset");
      if (slots > 0) check(cudaMemsetAsync(c_lambda.ptr, 0, 3 * sizeof(double) * slots, stream), "memset");
      if (volumes) check(cudaMemsetAsync(v_lambda.ptr, 0, sizeof(double) * clusters, stream), "memset");
      // the last iteration is not over-relaxed (see PbdSystem::step_on_cpu)
      for (int it = 0; it < p.iterations; ++it)
        solve_jacobi(h, it + 1 == p.iterations ? 1.0 : p.sor_w, per_particle, body);
      if (bodies > 0)
        contact_forces<<<blocks, kThreads, 0, stream>>>(n, bodies, mass.ptr, k_slot.ptr, k_active.ptr, 1.0 / (h * h),
                                                        k_partial.ptr + static_cast<size_t>(s) * blocks * bodies * 4);
      update<<<blocks, kThreads, 0, stream>>>(n, state.ptr, x.ptr, xp.ptr, v.ptr, inv_mass.ptr, 1.0 / h);
    }
  }
};

PbdCudaSolver::PbdCudaSolver(const PbdSystem& sys) : impl_(std::make_unique<Impl>()) {
  std::string why;
  if (!pbd_cuda_available(&why)) throw std::invalid_argument("pbd: solver kJacobiCuda needs a CUDA device: " + why);
  if (!sys.finalized()) throw std::logic_error("pbd: finalize() before building the CUDA solver");
  Impl& d = *impl_;
  check(cudaStreamCreateWithFlags(&d.stream, cudaStreamNonBlocking), "stream");
  for (auto& e : d.ev) check(cudaEventCreate(&e), "event");
  const Particles& p = sys.particles_;
  d.n = p.size();
  d.x.allocate(3 * d.n);
  d.xp.allocate(3 * d.n);
  d.v.allocate(3 * d.n);
  d.start.allocate(3 * d.n);
  d.target.allocate(3 * d.n);
  d.inv_mass.allocate(d.n);
  d.state.allocate(d.n);
  d.mass.upload(p.mass_kg.data(), d.n);

  d.distances = static_cast<int>(sys.distance_.size());
  {
    std::vector<int2> ij;
    std::vector<double> rest, compliance;
    for (const auto& c : sys.distance_)
      ij.push_back({c.i, c.j}), rest.push_back(c.rest_m), compliance.push_back(c.compliance_m_per_n);
    d.d_ij.upload(ij);
    d.d_rest.upload(rest);
    d.d_compliance.upload(compliance);
    d.d_mean_inv.upload(sys.distance_mean_inv_count_.data(), d.distances);
    d.d_min_inv.upload(sys.distance_min_inv_count_.data(), d.distances);
    d.d_lambda.allocate(d.distances);
    d.d_slot.allocate(6 * d.distances);
    d.d_gather.upload(sys.distance_group_);
  }
  d.bendings = static_cast<int>(sys.bending_.size());
  {
    std::vector<int4> abcd;
    std::vector<double> rest, compliance;
    for (const auto& c : sys.bending_)
      abcd.push_back({c.a, c.b, c.c, c.d}), rest.push_back(c.rest_angle_rad),
          compliance.push_back(c.compliance_per_n_m);
    d.b_abcd.upload(abcd);
    d.b_rest.upload(rest);
    d.b_compliance.upload(compliance);
    d.b_mean_inv.upload(sys.bending_mean_inv_count_.data(), d.bendings);
    d.b_min_inv.upload(sys.bending_min_inv_count_.data(), d.bendings);
    d.b_lambda.allocate(d.bendings);
    d.b_slot.allocate(12 * d.bendings);
    d.b_gather.upload(sys.bending_group_);
  }
  const ShapeMatchingClusters& cl = sys.clusters_;
  d.clusters = cl.count();
  d.slots = cl.slot_count();
  {
    std::vector<int> member(d.slots), slot_cluster(d.slots), chunk_begin, chunk_end, chunk_cluster, cluster_chunks{0};
    std::vector<double> rest_moment(d.clusters);
    for (int c = 0; c < d.clusters; ++c) {
      for (int s = cl.begin(c); s < cl.end(c); ++s) member[s] = cl.member(s), slot_cluster[s] = c;
      for (int s = cl.begin(c); s < cl.end(c); s += kChunk)
        chunk_begin.push_back(s), chunk_end.push_back(std::min(s + kChunk, cl.end(c))), chunk_cluster.push_back(c);
      cluster_chunks.push_back(static_cast<int>(chunk_begin.size()));
      rest_moment[c] = cl.rest_moment_kg_m2(c);
    }
    d.chunks = static_cast<int>(chunk_begin.size());
    d.in_block = d.chunks == d.clusters;
    int largest = 1;
    for (int c = 0; c < d.clusters; ++c) largest = std::max(largest, cl.end(c) - cl.begin(c));
    d.block_threads = std::min(kChunk, (largest + 31) / 32 * 32);
    std::vector<int> offset{0};
    for (int c = 0; c < d.clusters; ++c) offset.push_back(cl.end(c));
    d.c_offset.upload(offset);
    d.member.upload(member);
    d.slot_cluster.upload(slot_cluster);
    d.chunk_begin.upload(chunk_begin);
    d.chunk_end.upload(chunk_end);
    d.chunk_cluster.upload(chunk_cluster);
    d.cluster_chunks.upload(cluster_chunks);
    d.rest_offset.upload(cl.rest_offsets_m().data(), 3 * static_cast<size_t>(d.slots));
    d.rest_moment.upload(rest_moment);
    d.c_min_inv.upload(sys.cluster_min_inv_count_.data(), d.clusters);
    d.c_compliance.allocate(d.clusters);
    d.c_lambda.allocate(3 * d.slots);
    d.c_slot.allocate(3 * d.slots);
    d.partial4.allocate(4 * static_cast<size_t>(d.chunks));
    d.partial9.allocate(9 * static_cast<size_t>(d.chunks));
    d.rotation.allocate(d.clusters);
    d.centre.allocate(d.clusters);
    d.c_gather.upload(sys.cluster_group_);
    d.host_compliance.assign(d.clusters, 0.0);
    d.host_rotation.assign(9 * static_cast<size_t>(d.clusters), 0.0);
    // the volumes: A_qq^-1, compliance and the share the averaging delivers (PbdSystem::solve_jacobi)
    d.volumes = cl.any_volume();
    if (d.volumes) {
      std::vector<Mat3> aqq(d.clusters);
      std::vector<double> compliance(d.clusters), delivered(d.clusters);
      for (int c = 0; c < d.clusters; ++c) {
        std::copy_n(cl.rest_aqq_inverse(c).data(), 9, aqq[c].m);
        compliance[c] = cl.volume_compliance_per_j(c);
        double sum = 0.0;
        for (int s = cl.begin(c); s < cl.end(c); ++s) sum += sys.cluster_group_.inverse_count(cl.member(s));
        delivered[c] = sum / (cl.end(c) - cl.begin(c));
      }
      d.v_aqq_inverse.upload(aqq);
      d.v_compliance.upload(compliance);
      d.v_delivered_per_particle = delivered;
      d.v_delivered_per_constraint.assign(sys.cluster_min_inv_count_.data(),
                                          sys.cluster_min_inv_count_.data() + d.clusters);
      d.v_delivered.allocate(d.clusters);
      d.v_lambda.allocate(d.clusters);
      d.v_dlambda.allocate(d.clusters);
      d.v_gradient.allocate(d.clusters);
    }
  }
  check(cudaDeviceSynchronize(), "upload");
}

PbdCudaSolver::~PbdCudaSolver() = default;

void PbdCudaSolver::run_step(PbdSystem& sys, double dt_s, const PbdParams& params, ContactProjector* contacts) {
  Impl& d = *impl_;
  Particles& p = sys.particles_;
  const ShapeMatchingClusters& cl = sys.clusters_;
  if (p.size() != d.n || cl.slot_count() != d.slots || static_cast<int>(sys.distance_.size()) != d.distances ||
      static_cast<int>(sys.bending_.size()) != d.bendings)
    throw std::logic_error("pbd: the CUDA solver was built for another system");
  const size_t n3 = 3 * sizeof(double) * d.n;
  const int quarantined_before = sys.quarantined_now();
  const int substeps = std::max(params.substeps, 1);
  const int blocks = blocks_for(d.n);
  // the contacts: their setup (radii uploaded when they come from another projector), and this
  // step's bodies substep by substep
  ContactProjector::DeviceSetup setup;
  if (contacts) {
    if (!contacts->device_setup(&setup)) throw std::invalid_argument("pbd: these contacts are solved on the CPU only");
    if (setup.particles != d.n || setup.bodies < 1 || setup.bodies > device::kMaxContactBodies || !setup.radius_m)
      throw std::logic_error("pbd: the contacts were made for another system");
  }
  // the radii compared by value (a new projector may sit where the last one was)
  const bool new_radii =
      setup.bodies > 0 && !std::equal(d.host_radius.begin(), d.host_radius.end(), setup.radius_m, setup.radius_m + d.n);
  if (setup.bodies != d.bodies || new_radii) {
    if (d.graph) cudaGraphExecDestroy(d.graph), d.graph = nullptr;  // it points at the old arrays
    d.bodies = setup.bodies;
    d.host_radius.assign(setup.radius_m, setup.radius_m + (d.bodies > 0 ? d.n : 0));
    if (d.bodies > 0) {
      d.k_radius.upload(d.host_radius);
      d.k_slot.allocate(static_cast<size_t>(d.n) * d.bodies);
      d.k_active.allocate(static_cast<size_t>(d.n) * d.bodies);
      d.k_stabilisation_max.allocate(1);
      d.host_body.clear();  // sized below
    }
  }
  d.margin_m = setup.margin_m;
  d.stabilisation_iterations = setup.stabilisation_iterations;
  if (d.bodies > 0 && d.host_body.size() != static_cast<size_t>(substeps) * d.bodies) {
    d.host_body.assign(static_cast<size_t>(substeps) * d.bodies, ContactBody{});
    d.host_partial.assign(static_cast<size_t>(substeps) * blocks * d.bodies * 4, 0.0);
    d.k_body.allocate(d.host_body.size());
    d.k_partial.allocate(d.host_partial.size());
    if (d.graph) cudaGraphExecDestroy(d.graph), d.graph = nullptr;  // it points at the old arrays
  }
  if (d.bodies > 0) contacts->device_bodies(substeps, d.host_body.data());
  // what the caller may have changed since the last step, as it is now
  for (int c = 0; c < d.clusters; ++c) {
    d.host_compliance[c] = cl.compliance_s2(c);
    std::copy_n(cl.rotation(c).data(), 9, d.host_rotation.data() + 9 * c);
  }
  cudaStream_t st = d.stream;
  check(cudaEventRecord(d.ev[0], st), "event");
  if (d.n > 0) {
    check(cudaMemcpyAsync(d.x.ptr, p.position_m.data(), n3, cudaMemcpyHostToDevice, st), "upload x");
    check(cudaMemcpyAsync(d.v.ptr, p.velocity_m_per_s.data(), n3, cudaMemcpyHostToDevice, st), "upload v");
    check(cudaMemcpyAsync(d.target.ptr, sys.drive_target_m_.data(), n3, cudaMemcpyHostToDevice, st), "upload targets");
    check(cudaMemcpyAsync(d.inv_mass.ptr, p.inv_mass_per_kg.data(), sizeof(double) * d.n, cudaMemcpyHostToDevice, st),
          "upload w");
    check(cudaMemcpyAsync(d.state.ptr, p.state.data(), d.n, cudaMemcpyHostToDevice, st), "upload states");
  }
  if (d.bodies > 0)
    check(cudaMemcpyAsync(d.k_body.ptr, d.host_body.data(), sizeof(ContactBody) * d.host_body.size(),
                          cudaMemcpyHostToDevice, st),
          "upload contact bodies");
  if (d.clusters > 0) {
    check(cudaMemcpyAsync(d.c_compliance.ptr, d.host_compliance.data(), sizeof(double) * d.clusters,
                          cudaMemcpyHostToDevice, st),
          "upload compliance");
    check(
        cudaMemcpyAsync(d.rotation.ptr, d.host_rotation.data(), sizeof(Mat3) * d.clusters, cudaMemcpyHostToDevice, st),
        "upload rotations");
  }
  check(cudaEventRecord(d.ev[1], st), "event");
  if (d.n > 0) {
    // one graph per (dt, params): launching ~10 kernels per iteration one by one costs more
    // than the work itself on small bodies
    Impl::Key key{dt_s,
                  params.sor_w,
                  params.damping_per_s,
                  {params.gravity_m_per_s2.x(), params.gravity_m_per_s2.y(), params.gravity_m_per_s2.z()},
                  params.substeps,
                  params.iterations,
                  params.averaging,
                  d.bodies,
                  d.stabilisation_iterations,
                  d.margin_m};
    if (!d.graph || !(key == d.key)) {
      if (d.graph) cudaGraphExecDestroy(d.graph), d.graph = nullptr;
      if (d.volumes) {
        const std::vector<double>& delivered = params.averaging == JacobiAveraging::kPerParticle
                                                   ? d.v_delivered_per_particle
                                                   : d.v_delivered_per_constraint;
        check(cudaMemcpyAsync(d.v_delivered.ptr, delivered.data(), sizeof(double) * d.clusters, cudaMemcpyHostToDevice,
                              st),
              "upload volume shares");
      }
      cudaGraph_t g = nullptr;
      check(cudaStreamBeginCapture(st, cudaStreamCaptureModeThreadLocal), "begin capture");
      d.enqueue_step(dt_s, params);
      check(cudaStreamEndCapture(st, &g), "end capture");
      const cudaError_t e = cudaGraphInstantiate(&d.graph, g, 0);
      cudaGraphDestroy(g);
      check(e, "graph instantiate");
      d.key = key;
    }
    check(cudaGraphLaunch(d.graph, st), "graph launch");
  }
  check(cudaEventRecord(d.ev[2], st), "event");
  if (d.n > 0) {
    check(cudaMemcpyAsync(p.position_m.data(), d.x.ptr, n3, cudaMemcpyDeviceToHost, st), "download x");
    check(cudaMemcpyAsync(p.velocity_m_per_s.data(), d.v.ptr, n3, cudaMemcpyDeviceToHost, st), "download v");
    check(cudaMemcpyAsync(p.inv_mass_per_kg.data(), d.inv_mass.ptr, sizeof(double) * d.n, cudaMemcpyDeviceToHost, st),
          "download w");
    check(cudaMemcpyAsync(p.state.data(), d.state.ptr, d.n, cudaMemcpyDeviceToHost, st), "download states");
  }
  if (d.clusters > 0)
    check(
        cudaMemcpyAsync(d.host_rotation.data(), d.rotation.ptr, sizeof(Mat3) * d.clusters, cudaMemcpyDeviceToHost, st),
        "download rotations");
  unsigned long long stabilisation_bits = 0;
  if (d.bodies > 0 && d.n > 0) {
    check(cudaMemcpyAsync(d.host_partial.data(), d.k_partial.ptr, sizeof(double) * d.host_partial.size(),
                          cudaMemcpyDeviceToHost, st),
          "download contact forces");
    check(cudaMemcpyAsync(&stabilisation_bits, d.k_stabilisation_max.ptr, sizeof(stabilisation_bits),
                          cudaMemcpyDeviceToHost, st),
          "download stabilisation");
  }
  check(cudaEventRecord(d.ev[3], st), "event");
  check(cudaEventSynchronize(d.ev[3]), "step");
  check(cudaGetLastError(), "kernels");
  float ms[3] = {0, 0, 0};
  for (int k = 0; k < 3; ++k) check(cudaEventElapsedTime(&ms[k], d.ev[k], d.ev[k + 1]), "elapsed");
  timings_ = {ms[0], ms[1], ms[2], d.graph != nullptr};
  // after an update x* equals x (a quarantined particle's x* is its frozen x)
  p.predicted_m = p.position_m;
  for (int c = 0; c < d.clusters; ++c)
    cl.set_rotation(c, Eigen::Map<const Eigen::Matrix3d>(d.host_rotation.data() + 9 * c));
  sys.quarantined_total_ += sys.quarantined_now() - quarantined_before;
  if (d.bodies > 0) {
    // each body's force: the mean over the substeps of its sum over the blocks; its contacts: the last substep's
    Eigen::Vector3d force[device::kMaxContactBodies];
    int count[device::kMaxContactBodies] = {};
    for (int b = 0; b < d.bodies; ++b) {
      force[b].setZero();
      for (int s = 0; s < substeps; ++s) {
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        double contacts_now = 0.0;
        for (int k = 0; k < blocks; ++k) {
          const double* q = d.host_partial.data() + ((static_cast<size_t>(s) * blocks + k) * d.bodies + b) * 4;
          sum += Eigen::Vector3d(q[0], q[1], q[2]);
          contacts_now += q[3];
        }
        force[b] += sum;
        if (s + 1 == substeps) count[b] = static_cast<int>(contacts_now);
      }
      force[b] /= substeps;
    }
    double stabilisation_max_m = 0.0;
    std::memcpy(&stabilisation_max_m, &stabilisation_bits, sizeof(stabilisation_max_m));
    contacts->device_results(force, count, stabilisation_max_m);
  }
}

}  // namespace pcisim::physics::pbd
