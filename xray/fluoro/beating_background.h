#pragma once
// The fluoroscopy background that beats: per C-arm pose, the static CT's projection plus, per
// phase bin, the projection of that bin's change of attenuation (heart_warp.h) over the box
// around the heart only. Line integrals are linear in mu, so
//   P(warped CT) = P(static CT) + P(mu(x - v_b(x)) - mu(x)),
// and the second term walks only the rays through the heart's box. A frame takes the two bins
// around its phase and blends them linearly (or the nearer one). Bins are projected when a frame
// first needs them, plus a few more per frame until the pose has all of them.
#include <memory>
#include <vector>

#include "xray/fluoro/heart_warp.h"
#include "xray/geometry/detector_geometry.h"
#include "xray/projectors/image.h"
#include "xray/projectors/trilinear_projector.h"

namespace pcisim::xray {

struct BeatingBackgroundOptions {
  HeartWarpParams warp;
  bool interpolate = true;  // blend the two bins around the phase; false: the nearer bin
  int fill_per_frame = 1;   // bins projected ahead per frame until the pose has every bin
  // the change is projected on a detector of every change_stride-th pixel (1, 2 or 4) and
  // upsampled bilinearly: about change_stride^2 times cheaper; the moving edges blur a little
  // (2: 0.0175 against 0.0163 % RMSE at 16 bins, a third of the projection time:
  // docs/benchmarks/xray-beating.md)
  int change_stride = 2;
  // every bin's change is written once, at construction, when they all fit in this many MiB
  // (a pose change then only projects them); otherwise each is written when projected
  double change_cache_mib = 512;
  TrilinearOptions projector{.step_voxels = 1.0};  // for the changes (CPU)
  // project the changes on the GPU (a CUDA build with a device; each bin's change is uploaded
  // once; only when the changes are cached, else the CPU projects them); throws at construction
  // when asked for and no device is there
  bool gpu = false;
};

// empty when usable, otherwise the field and its range
std::string validate(const BeatingBackgroundOptions& options);

// every bin's change of attenuation, written once (HeartWarp::write_change): the same for every
// background over the same CT, samples and warp, so backgrounds may share them (a dataset's jobs)
using BeatChanges = std::vector<AttenuationVolume>;

class BeatingBackground {
 public:
  // keeps a reference to ct (the static attenuation the renderer projects); builds the warp.
  // `changes`: every bin's change made by another background over the same CT, samples and warp
  // (changes()), used instead of writing them; null: written here (when they fit
  // change_cache_mib). Throws std::invalid_argument when they are not one per bin of the warp's box
  BeatingBackground(const AttenuationVolume& ct, const BeatSamples& samples, const BeatingBackgroundOptions& options,
                    std::shared_ptr<const BeatChanges> changes = nullptr);
  ~BeatingBackground();

  int bins() const { return warp_.bins(); }
  const HeartWarp& warp() const { return warp_; }

  // a new pose: `static_projection` is the static CT's line integrals for g (copied); every bin
  // is projected again when needed. quick_stride (0-8; used when coarser than change_stride): the
  // static projection is a quick one (a C-arm move's), and so are the bins filled until
  // replace_static() gives the whole one: their changes on the detector of every quick_stride-th
  // pixel, projected again afterwards by fill_ahead()
  void set_pose(const DetectorGeometry& g, const Image& static_projection, int quick_stride = 0);
  // the same pose's static projection made again (a move's quick one made whole): every bin,
  // filled or not, takes the difference; the changes are not projected again (the quick bins'
  // are, by fill_ahead())
  void replace_static(const Image& old_projection, const Image& new_projection);

  // the background's line integrals at `phase` (any real; taken mod 1) into out (sized like the
  // pose's image); projects the bins it needs that the pose lacks. Allocates nothing once every
  // bin of the first pose is filled.
  void at_phase(double phase, Image* out);
  // projects up to fill_per_frame bins the pose still lacks (then, once its static projection is
  // whole, those filled quickly); returns how many it projected
  int fill_ahead();

  int filled_bins() const;  // the bins filled at the change detector's resolution
  bool changes_cached() const { return changes_ != nullptr; }
  // the bins' changes, to share with another background (null when not cached)
  std::shared_ptr<const BeatChanges> changes() const { return changes_; }
  bool on_gpu() const { return gpu_ != nullptr; }
  int64_t bin_projections() const { return bin_projections_; }

 private:
  void fill(int bin);
  const AttenuationVolume& change(int bin);

  BeatingBackgroundOptions options_;
  HeartWarp warp_;
  AttenuationVolume change_;                    // scratch when the changes are not cached
  std::shared_ptr<const BeatChanges> changes_;  // per bin, when cached (perhaps another's)
  struct Gpu;                                   // per bin, the change uploaded (CUDA builds)
  std::unique_ptr<Gpu> gpu_;
  TrilinearProjector projector_;
  DetectorGeometry geometry_;
  std::vector<Image> bin_images_;                            // static + change, per bin
  static constexpr char kEmpty = 0, kWhole = 1, kQuick = 2;  // a bin's state (filled_)
  std::vector<char> filled_;
  Image static_;  // the pose's static projection
  Image scratch_, coarse_, quick_;
  DetectorGeometry coarse_geometry_, quick_geometry_;
  int quick_stride_ = 0;  // > 0 while the static projection is a quick one
  int64_t bin_projections_ = 0;
};

}  // namespace pcisim::xray
