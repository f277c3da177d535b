#include "xray/fluoro/beating_background.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <stdexcept>
#include <string>
#include <thread>

#ifdef PCISIM_HAVE_CUDA
#include "xray/projectors/cuda_projector.h"
#endif

namespace pcisim::xray {

struct BeatingBackground::Gpu {
#ifdef PCISIM_HAVE_CUDA
  std::vector<std::unique_ptr<CudaTrilinearProjector>> bins;
#endif
};

std::string validate(const BeatingBackgroundOptions& o) {
  if (std::string bad = validate(o.warp); !bad.empty()) return "warp." + bad;
  if (o.fill_per_frame < 0 || o.fill_per_frame > 64) return "fill_per_frame must be in [0, 64]";
  if (!(o.projector.step_voxels > 0)) return "projector.step_voxels must be > 0";
  if (o.change_stride != 1 && o.change_stride != 2 && o.change_stride != 4) return "change_stride must be 1, 2 or 4";
  if (!(o.change_cache_mib >= 0 && o.change_cache_mib <= 1 << 20)) return "change_cache_mib must be in [0, 2^20]";
  return {};
}

namespace {

const BeatingBackgroundOptions& checked(const BeatingBackgroundOptions& o) {
  if (std::string bad = validate(o); !bad.empty()) throw std::invalid_argument("BeatingBackground: " + bad);
  return o;
}

}  // namespace

BeatingBackground::BeatingBackground(const AttenuationVolume& ct, const BeatSamples& samples,
                                     const BeatingBackgroundOptions& options,
                                     std::shared_ptr<const BeatChanges> changes)
    : options_(checked(options)),
      warp_(ct, samples, options.warp),
      change_(warp_.make_change_volume()),
      projector_(change_, options.projector),
      bin_images_(warp_.bins()),
      filled_(warp_.bins(), 0) {
  if (changes) {
    // another background's: one per bin, each over this warp's box
    bool fits = static_cast<int>(changes->size()) == bins();
    for (size_t b = 0; fits && b < changes->size(); ++b)
      fits = (*changes)[b].dims() == change_.dims() && (*changes)[b].index_offset() == change_.index_offset() &&
             (*changes)[b].index_from_physical() == change_.index_from_physical();
    if (!fits)
      throw std::invalid_argument("BeatingBackground: the shared changes are not one per bin of this warp's box");
    changes_ = std::move(changes);
  } else {
    const double mib = double(change_.padded_count()) * sizeof(float) * bins() / (1 << 20);
    if (mib > options_.change_cache_mib) return;
    // every bin's change now, bins split over two threads (each writes its own volume)
    auto written = std::make_shared<BeatChanges>();
    written->reserve(bins());
    for (int b = 0; b < bins(); ++b) written->push_back(warp_.make_change_volume());
    std::exception_ptr failed[2];
    auto write = [this, &written, &failed](int first) {
      try {
        for (int b = first; b < bins(); b += 2) warp_.write_change(b, &(*written)[b]);
      } catch (...) {
        failed[first] = std::current_exception();
      }
    };
    std::thread other(write, 1);
    write(0);
    other.join();
    for (const auto& e : failed)
      if (e) std::rethrow_exception(e);
    changes_ = std::move(written);
  }
  if (!options_.gpu) return;
#ifdef PCISIM_HAVE_CUDA
  std::string why;
  if (!CudaTrilinearProjector::available(&why)) throw std::runtime_error("BeatingBackground: no GPU: " + why);
  gpu_ = std::make_unique<Gpu>();
  for (const AttenuationVolume& c : *changes_)
    gpu_->bins.push_back(std::make_unique<CudaTrilinearProjector>(c, options_.projector));
#else
  throw std::runtime_error("BeatingBackground: the GPU needs a build with CUDA");
#endif
}

const AttenuationVolume& BeatingBackground::change(int bin) {
  if (changes_) return (*changes_)[bin];
  warp_.write_change(bin, &change_);
  return change_;
}

BeatingBackground::~BeatingBackground() = default;

void BeatingBackground::set_pose(const DetectorGeometry& g, const Image& static_projection, int quick_stride) {
  if (static_projection.width != g.width || static_projection.height != g.height)
    throw std::invalid_argument(
        "BeatingBackground::set_pose: the static projection's size differs from the detector's");
  if (quick_stride < 0 || quick_stride > 8)
    throw std::invalid_argument("BeatingBackground::set_pose: quick_stride must be 0-8, not " +
                                std::to_string(quick_stride));
  geometry_ = g;
  for (Image& im : bin_images_) {
    if (im.width != g.width || im.height != g.height) im.resize(g.width, g.height);
    std::copy(static_projection.pixels.begin(), static_projection.pixels.end(), im.pixels.begin());
  }
  static_ = static_projection;  // (the same size from pose to pose: no allocation)
  if (scratch_.width != g.width || scratch_.height != g.height) scratch_.resize(g.width, g.height);
  coarse_geometry_ = coarse_detector(g, options_.change_stride);
  if (coarse_.width != coarse_geometry_.width || coarse_.height != coarse_geometry_.height)
    coarse_.resize(coarse_geometry_.width, coarse_geometry_.height);
  quick_stride_ = quick_stride > options_.change_stride ? quick_stride : 0;
  if (quick_stride_) {
    quick_geometry_ = coarse_detector(g, quick_stride_);
    if (quick_.width != quick_geometry_.width || quick_.height != quick_geometry_.height)
      quick_.resize(quick_geometry_.width, quick_geometry_.height);
  }
  std::fill(filled_.begin(), filled_.end(), kEmpty);
}

// bin image = static projection + the projection of the bin's change: on the change detector,
// or (while the pose's static projection is a quick one) on the quick one
void BeatingBackground::fill(int bin) {
  const AttenuationVolume& dmu = change(bin);
  std::vector<float>& p = bin_images_[bin].pixels;
  if (filled_[bin] != kEmpty) std::copy(static_.pixels.begin(), static_.pixels.end(), p.begin());
  // project the change: the GPU's copy of it, or this projector on the CPU
  auto project = [&](const DetectorGeometry& g, Image* out) {
#ifdef PCISIM_HAVE_CUDA
    if (gpu_) {
      gpu_->bins[bin]->project(g, out);
      return;
    }
#endif
    projector_.project(dmu, g, out);
  };
  const int s = options_.change_stride;
  if (quick_stride_) {
    project(quick_geometry_, &quick_);
    upsample_bilinear(quick_, quick_stride_, &bin_images_[bin], /*add=*/true);
  } else if (s == 1) {
    project(geometry_, &scratch_);
    for (size_t i = 0; i < p.size(); ++i) p[i] += scratch_.pixels[i];
  } else {
    project(coarse_geometry_, &coarse_);
    upsample_bilinear(coarse_, s, &bin_images_[bin], /*add=*/true);
  }
  filled_[bin] = quick_stride_ ? kQuick : kWhole;
  ++bin_projections_;
}

void BeatingBackground::replace_static(const Image& old_projection, const Image& new_projection) {
  if (old_projection.pixels.size() != new_projection.pixels.size() ||
      static_.pixels.size() != new_projection.pixels.size())
    throw std::invalid_argument("BeatingBackground::replace_static: the projections' sizes differ from the pose's");
  // a bin not yet filled is the static projection itself (bit for bit, as set_pose leaves it:
  // bins agree exactly off the heart's box); a filled one takes the difference
  for (int bin = 0; bin < bins(); ++bin) {
    std::vector<float>& p = bin_images_[bin].pixels;
    if (filled_[bin] == kEmpty) {
      std::copy(new_projection.pixels.begin(), new_projection.pixels.end(), p.begin());
      continue;
    }
    for (size_t i = 0; i < p.size(); ++i) p[i] += new_projection.pixels[i] - old_projection.pixels[i];
  }
  std::copy(new_projection.pixels.begin(), new_projection.pixels.end(), static_.pixels.begin());
  // the bins filled quickly stay in use until fill_ahead() projects them again
  quick_stride_ = 0;
}

void BeatingBackground::at_phase(double phase, Image* out) {
  if (bin_images_.empty() || bin_images_[0].width != geometry_.width || geometry_.width == 0)
    throw std::logic_error("BeatingBackground::at_phase before set_pose");
  const int n = bins();
  double f = phase - std::floor(phase);
  if (!std::isfinite(f)) f = 0;
  const double x = f * n;
  int a = static_cast<int>(std::floor(x)) % n;
  const int b = (a + 1) % n;
  double t = x - std::floor(x);
  if (!options_.interpolate) {
    if (t >= 0.5) a = b;
    t = 0;
  }
  if (filled_[a] == kEmpty) fill(a);
  if (out->width != geometry_.width || out->height != geometry_.height) out->resize(geometry_.width, geometry_.height);
  const std::vector<float>& pa = bin_images_[a].pixels;
  if (t == 0) {
    std::copy(pa.begin(), pa.end(), out->pixels.begin());
    return;
  }
  if (filled_[b] == kEmpty) fill(b);
  const std::vector<float>& pb = bin_images_[b].pixels;
  // a + t (b - a): exactly a wherever the two bins agree (off the heart's box, bit for bit)
  const float wb = static_cast<float>(t);
  for (size_t i = 0; i < pa.size(); ++i) out->pixels[i] = pa[i] + wb * (pb[i] - pa[i]);
}

int BeatingBackground::fill_ahead() {
  int done = 0;
  // the bins the pose lacks, then (once its static projection is whole) those filled quickly
  for (const char state : {kEmpty, kQuick})
    for (int bin = 0; bin < bins() && done < options_.fill_per_frame; ++bin) {
      if (filled_[bin] != state || (state == kQuick && quick_stride_)) continue;
      fill(bin);
      ++done;
    }
  return done;
}

int BeatingBackground::filled_bins() const {
  int k = 0;
  for (const char f : filled_) k += f == kWhole ? 1 : 0;
  return k;
}

}  // namespace pcisim::xray
