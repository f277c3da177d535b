#include "modeling/cta/cta_pipeline.h"

#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <atomic>
#include <chrono>
#include <thread>

#include "modeling/cta/modeling_error.h"
#include "modeling/heart/heart_placement.h"
#include "realtime/percentile.h"

namespace pcisim::modeling {
namespace {

using Clock = std::chrono::steady_clock;
using Eigen::Vector3d;

// runs a stage, timing it and telling the progress callback
template <typename F>
void stage(CtaModel* m, const std::string& name, const StageProgress& progress, F&& body) {
  StageReport r;
  r.name = name;
  if (progress) progress(r, false);
  const auto t0 = Clock::now();
  body(r);
  r.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  if (progress) progress(r, true);
  m->stages.push_back(std::move(r));
}

std::vector<double> median_filter(const std::vector<double>& v, int window) {
  if (window < 2 || v.size() < 3) return v;
  std::vector<double> out(v.size()), w;
  const int h = window / 2;
  for (int i = 0; i < int(v.size()); ++i) {
    w.clear();
    for (int k = std::max(0, i - h); k <= std::min<int>(v.size() - 1, i + h); ++k) w.push_back(v[k]);
    out[i] = realtime::upper_median_in_place(std::span<double>(w));
  }
  return out;
}

}  // namespace

double memory_bytes_per_voxel(bool smoothed, bool tubes) {
  return 2.0 + 1.0 + (smoothed ? 4.0 : 0.0) + 0.25 * 28.0 + (tubes ? 0.25 * 28.0 : 0.0);
}

double estimated_memory_gb(const anatomy::Volume& ct, bool smoothed, bool tubes) {
  return double(ct.voxel_count()) * memory_bytes_per_voxel(smoothed, tubes) / 1e9;
}

CtaModel build_cta_model(const anatomy::Volume& ct, const std::vector<Vector3d>& seeds_mm,
                         const CtaPipelineOptions& options, const StageProgress& progress) {
  const bool smoothed = options.segmentation.smoothing_mm > 0, tubes = options.segmentation.tubes.enabled;
  if (const double need = estimated_memory_gb(ct, smoothed, tubes); need > options.memory_limit_gb) {
    throw ModelingError(fmt::format(
        "the CT's {} x {} x {} voxels would need about {:.2f} GB here ({:.0f} bytes a voxel), over the bound of {:.2f} "
        "GB: crop it to the heart or resample it",
        ct.dims[0], ct.dims[1], ct.dims[2], need, memory_bytes_per_voxel(smoothed, tubes), options.memory_limit_gb));
  }
  CtaPipelineOptions o = options;
  const int threads = o.threads > 0 ? o.threads : std::max(1u, std::thread::hardware_concurrency());
  o.segmentation.threads = o.clipping.threads = threads;
  o.checks.sample_spacing_mm = o.spline.sample_spacing_mm;  // the crossing check counts samples
  CtaModel m;

  // (a) and (b): the fill and its clipping, then, where the fill made a sponge at the aortic root,
  // both again on the smoothed CT (the robust fill)
  LumenSegmentation seg;
  Clipping clip;
  auto fill_and_clip = [&](const SegmentationOptions& so, const std::string& suffix) {
    stage(&m, "segmentation" + suffix, progress, [&](StageReport& r) {
      seg = segment_lumen(ct, seeds_mm, so);
      r.figures = {{"seed_hu", seg.seed_hu},
                   {"noise_hu", seg.noise_hu},
                   {"smoothed_noise_hu", seg.smoothed_noise_hu},
                   {"lower_hu", seg.lower_hu},
                   {"upper_hu", seg.upper_hu},
                   {"region_voxels", double(seg.region_voxels)},
                   {"tube_voxels", double(seg.tube_voxels)},
                   {"tube_s", seg.tube_seconds},
                   {"metal_pieces", double(seg.metal_pieces)},
                   {"metal_voxels", double(seg.metal_voxels)},
                   {"bridges", double(seg.bridges.size())},
                   {"bridging_s", seg.bridging_seconds},
                   {"level_set_iterations", double(seg.level_set_iterations)},
                   {"lumen_voxels", double(seg.mask.count())},
                   {"crop_voxels", double(seg.mask.grid.size())}};
      for (const Bridge& b : seg.bridges) {
        r.notes.push_back(fmt::format(
            "a gap of {:.1f} mm bridged from ({:.1f}, {:.1f}, {:.1f}) to ({:.1f}, {:.1f}, {:.1f}) mm: the lumen "
            "narrows there below what the CT resolves (a tight stenosis or an occlusion); the vessel goes on {:.0f} mm "
            "beyond",
            b.gap_mm, b.from_mm.x(), b.from_mm.y(), b.from_mm.z(), b.to_mm.x(), b.to_mm.y(), b.to_mm.z(),
            b.piece_length_mm));
      }
    });
    stage(&m, "clipping" + suffix, progress, [&](StageReport& r) {
      ClippingOptions co = o.clipping;
      co.throw_when_none = false;
      clip = clip_to_coronaries(seg, seeds_mm, co);
      r.figures = {{"large_voxels", double(clip.large.count())},
                   {"coronary_trees", double(clip.pieces.size())},
                   {"aortic_radius_mm", clip.aorta_at_seed.radius_m},
                   {"pieces_cut_away", double(clip.dropped.size())},
                   {"root_sponges", double(clip.root_sponges)}};
      for (const auto& p : clip.pieces) {
        r.notes.push_back(fmt::format("kept: {} voxels, ostium ({:.1f}, {:.1f}, {:.1f}) mm, reaching {:.1f} mm",
                                      p.voxels.size(), p.ostium_mm.x(), p.ostium_mm.y(), p.ostium_mm.z(), p.reach_mm));
      }
      for (const auto& d : clip.dropped) r.notes.push_back("cut away: " + d);
    });
  };
  fill_and_clip(o.segmentation, "");
  const RefillOptions& rf = o.refill;
  // (a tree's worth: its farthest voxel from its ostium, summed over the trees)
  auto summed_reach_mm = [](const Clipping& c) {
    double sum = 0;
    for (const CoronaryPiece& p : c.pieces) sum += p.reach_mm;
    return sum;
  };
  // the shortest tree's reach (infinite without trees)
  auto shortest_mm = [](const Clipping& c) {
    double least = std::numeric_limits<double>::infinity();
    for (const CoronaryPiece& p : c.pieces) least = std::min(least, p.reach_mm);
    return least;
  };
  // two trees or more, but one short: the trigger is that tree alone
  const bool for_short_tree = clip.pieces.size() >= 2 && shortest_mm(clip) < rf.short_tree_mm;
  if (rf.enabled && clip.root_sponges > 0 && (clip.pieces.size() < 2 || for_short_tree) &&
      o.segmentation.smoothing_mm <= 0) {
    // the smoothed copy of the CT must fit the memory bound too, and the first fill's crop beside
    // the second (7 bytes a voxel of the CT: estimated_memory_gb)
    if (const double need = estimated_memory_gb(ct, true, true) + double(ct.voxel_count()) * 7.0 / 1e9;
        need > o.memory_limit_gb) {
      m.stages.back().notes.push_back(fmt::format(
          "a sponge at the aortic root, but the fill on the smoothed CT would need {:.2f} GB, over the bound of "
          "{:.2f} GB: not tried",
          need, o.memory_limit_gb));
    } else {
      m.stages.back().notes.push_back(fmt::format(
          "{} coronary tree(s){} and {} sponge(s) of noise at the aortic root (the CT's noise strung a chamber or the "
          "myocardium near the lower threshold of {:.0f} HU into the fill, and a tree with it): filled again on the CT "
          "smoothed by {:.1f} mm{}",
          clip.pieces.size(),
          for_short_tree ? fmt::format(", one reaching only {:.0f} mm from its ostium,", shortest_mm(clip)) : "",
          clip.root_sponges, seg.lower_hu, rf.smoothing_mm,
          o.segmentation.tubes.enabled ? ", thin vessels grown along tubes" : ""));
      LumenSegmentation first_seg = std::move(seg);
      Clipping first_clip = std::move(clip);
      SegmentationOptions so = o.segmentation;
      so.smoothing_mm = rf.smoothing_mm;
      std::string second;  // why the second fill is not kept
      try {
        fill_and_clip(so, " (smoothed)");
        // the smoothed fill only where it finds more trees than the first (and, where a short tree
        // asked for it, reaching as far in all: not one more spurious piece beside trees it lost),
        // or as many reaching further_factor as far (the short tree's real one found)
        const double first_reach = summed_reach_mm(first_clip), reach = summed_reach_mm(clip);
        const bool more = clip.pieces.size() > first_clip.pieces.size() && (!for_short_tree || reach >= first_reach);
        const bool further = clip.pieces.size() == first_clip.pieces.size() && reach > rf.further_factor * first_reach;
        if (!more && !further)
          second = fmt::format(
              "the smoothed fill found {} tree(s) reaching {:.0f} mm in all, the first {} reaching {:.0f} mm",
              clip.pieces.size(), reach, first_clip.pieces.size(), first_reach);
      } catch (const ModelingError& e) {
        second = std::string("the smoothed fill failed: ") + e.what();
      }
      if (!second.empty()) {
        m.stages.back().notes.push_back(second + "; the first fill is kept");
        seg = std::move(first_seg);
        clip = std::move(first_clip);
      }
    }
  }
  if (clip.pieces.empty()) throw ModelingError(clip.none_found);

  // (c) centerlines, then the B-spline of each branch
  std::vector<ModelTree> trees;
  stage(&m, "centerlines", progress, [&](StageReport& r) {
    int branches = 0;
    double length = 0;
    for (const CoronaryPiece& piece : clip.pieces) {
      const std::vector<TracedBranch> traced = trace_centerlines(clip, piece, o.tracing);
      ModelTree t;
      t.ostium_mm = piece.ostium_mm;
      t.aortic_centre_mm = piece.aortic_centre_mm;
      for (const TracedBranch& tb : traced) {
        ModelBranch b;
        b.points_mm = fit_and_sample(tb.points_mm, o.spline);
        b.radius_mm = carry_along(tb.points_mm, tb.radius_mm, b.points_mm);
        b.parent = tb.parent;
        if (tb.parent >= 0) {
          // the join, on the parent's samples
          const Vector3d join = traced[tb.parent].points_mm[tb.parent_point];
          const auto& pp = t.branches[tb.parent].points_mm;
          int best = 0;
          for (size_t i = 0; i < pp.size(); ++i) {
            if ((pp[i] - join).squaredNorm() < (pp[best] - join).squaredNorm()) best = int(i);
          }
          b.parent_point = best;
          b.points_mm.front() = pp[best];
        }
        length += (b.points_mm.size() - 1) * o.spline.sample_spacing_mm;
        t.branches.push_back(std::move(b));
      }
      branches += int(t.branches.size());
      trees.push_back(std::move(t));
    }
    r.figures = {{"branches", double(branches)}, {"centerline_mm", length}};
  });

  // (d) radii from the cross-sections, on every sample, in parallel over branches
  stage(&m, "radii", progress, [&](StageReport& r) {
    std::vector<ModelBranch*> all;
    for (auto& t : trees) {
      for (auto& b : t.branches) all.push_back(&b);
    }
    std::atomic<size_t> next{0};
    std::atomic<int64_t> sections{0};
    auto work = [&] {
      RadiusWorkspace ws;
      for (size_t i = next++; i < all.size(); i = next++) {
        ModelBranch& b = *all[i];
        const size_t n = b.points_mm.size();
        std::vector<double> rad(n);
        for (size_t k = 0; k < n; ++k) {
          const Vector3d t = b.points_mm[std::min(k + 1, n - 1)] - b.points_mm[k > 0 ? k - 1 : 0];
          rad[k] = t.norm() > 0 ? cross_section_radius(seg.hu, b.points_mm[k], t, b.radius_mm[k], o.radius, &ws)
                                : b.radius_mm[k];
        }
        b.radius_mm = median_filter(rad, o.radius_median_window);
        sections += int64_t(n);
      }
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t) pool.emplace_back(work);
    work();
    for (auto& t : pool) t.join();
    r.figures = {{"cross_sections", double(sections.load())}};
  });

  stage(&m, "checks", progress, [&](StageReport& r) {
    int cut = 0, abrupt = 0, crossings = 0, beside = 0;
    for (auto& t : trees) {
      for (auto& n : drop_crossings(&t, o.checks)) {
        r.notes.push_back(n);
        ++crossings;
      }
      for (auto& n : drop_dark_branches(&t, seg.hu, o.checks)) {
        r.notes.push_back(n);
        ++cut;
      }
      for (auto& n : drop_parallel_branches(&t, o.checks)) {
        r.notes.push_back(n);
        ++beside;
      }
      for (auto& n : find_abrupt_ends(t, o.checks)) {
        r.notes.push_back(n);
        ++abrupt;
      }
    }
    r.figures = {{"veins_cut", double(cut)},
                 {"crossings_cut", double(crossings)},
                 {"beside_cut", double(beside)},
                 {"abrupt_ends", double(abrupt)}};
  });

  stage(&m, "labels", progress, [&](StageReport& r) {
    m.model.vessels = label_coronary_trees(clip.aorta, trees, o.labels);
    std::string names;
    for (const auto& b : m.model.vessels.branches) names += (names.empty() ? "" : " ") + b.name;
    r.notes.push_back("branches: " + names);
    r.figures = {{"branches", double(m.model.vessels.branches.size())}};
  });

  // (g) the template heart under the tree
  stage(&m, "heart", progress, [&](StageReport& r) {
    const HeartPlacement h = place_template_heart(m.model.vessels, o.heart);
    m.model.heart = h.pose;
    r.figures = {{"scale", h.pose.scale},
                 {"rms_mm", h.rms_mm},
                 {"pairs", double(h.pairs)},
                 {"iterations", double(h.iterations_run)}};
    // the template's heart centre is its origin: where the C-arm centres
    m.model.landmarks.push_back({"heart centre", h.pose.translation_m});
  });
  if (o.heart_fit.enabled) {
    stage(&m, "heart fit", progress, [&](StageReport& r) {
      // an optional refinement: when it cannot be done the case keeps the template as placed (no
      // heart.node; the world dents it under the tree as for any case without one)
      HeartElasticFit f;
      try {
        f = fit_heart_elastic(ct, m.model.vessels, m.model.heart, anatomy::template_heart_mesh(), o.heart_fit);
      } catch (const std::exception& e) {
        r.notes.push_back(std::string("heart fit not done: ") + e.what() + "; the template is kept as placed");
        return;
      }
      const anatomy::HeartMesh& t = anatomy::template_heart_mesh();
      const double worst_mm = 1e3 * (f.vertices_m - t.vertices_m).colwise().norm().maxCoeff();
      if (f.rounds_run == 0) {
        f.notes.push_back("no fit kept: the template stays as placed");
      } else if (!(worst_mm <= anatomy::kMaxFittedHeartMoveMm)) {
        f.notes.push_back(
            fmt::format("no fit kept: a vertex moved {:.1f} mm (more than {:.0f} mm in the template's "
                        "frame): the template stays as placed",
                        worst_mm, anatomy::kMaxFittedHeartMoveMm));
      } else {
        m.model.heart_vertices_m = f.vertices_m;
      }
      r.figures = {{"epicardial_vertices", double(f.epicardial_vertices)},
                   {"targets", double(f.targets)},
                   {"outliers", double(f.outliers)},
                   {"outline_before_mean_mm", f.outline_before_mean_mm},
                   {"outline_before_p95_mm", f.outline_before_p95_mm},
                   {"outline_after_mean_mm", f.outline_after_mean_mm},
                   {"outline_after_p95_mm", f.outline_after_p95_mm},
                   {"move_mean_mm", f.move_mean_mm},
                   {"move_max_mm", f.move_max_mm},
                   {"backoff", f.backoff},
                   {"min_tet_volume_ratio", f.min_tet_volume_ratio},
                   {"volume_placed_ml", f.volume_placed_ml},
                   {"volume_fitted_ml", f.volume_fitted_ml}};
      r.notes.insert(r.notes.end(), f.notes.begin(), f.notes.end());
    });
  }

  if (o.loft) {
    stage(&m, "loft", progress, [&](StageReport& r) {
      if (o.stitched) {
        anatomy::StitchedLumenStats st;
        m.model.lumen = anatomy::stitch_lumen(m.model.vessels, o.stitched_lumen, &st);
        r.figures = {{"vertices", double(m.model.lumen.vertices_m.size())},
                     {"triangles", double(m.model.lumen.triangles.size())},
                     {"components", double(anatomy::count_components(m.model.lumen))},
                     {"spacing_mm", st.spacing_m * 1e3},
                     {"memory_mb", st.memory_bytes / 1e6},
                     {"cavities_removed", double(st.cavities_removed)}};
      } else {
        m.model.lumen = anatomy::loft_lumen(m.model.vessels, o.lumen);
        r.figures = {{"vertices", double(m.model.lumen.vertices_m.size())},
                     {"triangles", double(m.model.lumen.triangles.size())},
                     {"components", double(anatomy::count_components(m.model.lumen))}};
      }
    });
  }

  // landmarks: the seeds and each tree's ostium
  for (size_t s = 0; s < seeds_mm.size(); ++s)
    m.model.landmarks.push_back({fmt::format("seed{}", s + 1), seeds_mm[s] * 1e-3});
  for (const auto& b : m.model.vessels.branches) {
    if (b.parent == 0 && !b.points.empty())
      m.model.landmarks.push_back({b.name + " ostium", b.points.front().position_m});
  }
  // the stenoses of the traced tree, as QCA measures them on its radius profile (lesions.json)
  m.model.lesions = anatomy::detect_lesions(m.model.vessels);
  m.model.ct_lumen_enhanced = true;
  return m;
}

}  // namespace pcisim::modeling
