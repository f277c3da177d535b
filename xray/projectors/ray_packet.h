#pragma once
// Eight rays at once on the CPU (AVX2): the pixels (c0 .. c0 + 7, r) marched in lockstep, each
// with its own samples exactly as ray::trilinear_ray takes them (setup_ray, for_each_run), the
// eight trilinear reads of a step gathered side by side. Neighbouring rays read neighbouring
// voxels, so a step's gathers mostly hit the lines the previous rays brought in. Positions are
// stepped as x(k) = x(t0 + dt/2) + k dt dx, so sums differ from trilinear_ray's in the last bits.
// The same for Joseph's method (slice_rays_x8). CPU only; the CUDA kernel runs trilinear_ray or
// slice_ray per pixel.
#include <cstdint>

#include "xray/projectors/ray_march.h"

namespace pcisim::xray::ray {

// the most samples a packet's rays may take; a packet with more goes back to trilinear_ray
inline constexpr int kPacketMaxSamples = 8192;

// true when this CPU runs the AVX2 path
bool packet_supported();

// line integrals of pixels (c0 + i, r), i < 8, into out[i]; all eight must lie on the detector,
// and the padded grid must hold fewer than 2^31 - 1 voxels (32-bit gather indices)
void trilinear_rays_x8(const GridView& g, const DetectorView& d, int c0, int r, float step_voxels, bool skip_empty,
                       float out[8]);

// the same eight pixels by Joseph's method (ray_march.h: slice_ray), the eight on one plane of the
// middle ray's major axis a step; four bilinear reads a sample, whole rows loaded and spread to
// the lanes where the eight points lie close (else gathered), and one brick walk for the eight
// where they stay within a brick of the middle ray. Sums differ from slice_ray's in the last bits
// (positions stepped). The same preconditions as trilinear_rays_x8
void slice_rays_x8(const GridView& g, const DetectorView& d, int c0, int r, bool skip_empty, float out[8]);

// what slice_rays_x8 did since the process started (all threads; relaxed counts, for tests and
// benchmarks): steps whose reads were row loads or gathers, and packets that walked the bricks
// once for the eight or lane by lane
struct SlicePacketCounts {
  int64_t row_steps = 0, gathered_steps = 0, shared_walks = 0, lane_walks = 0;
};
SlicePacketCounts slice_packet_counts();

}  // namespace pcisim::xray::ray
