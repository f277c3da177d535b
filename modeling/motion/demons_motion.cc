#include "modeling/motion/demons_motion.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "anatomy/heart/heart_mesh.h"

namespace pcisim::modeling {
std::vector<FloatImage> sequence_images(const std::vector<anatomy::Volume>& frames) {
  if (frames.size() < 2)
    throw std::invalid_argument("motion: a sequence needs at least 2 frames, got " + std::to_string(frames.size()));
  std::vector<FloatImage> out;
  out.reserve(frames.size());
  for (size_t f = 0; f < frames.size(); ++f) {
    if (const std::string bad = anatomy::validate(frames[f]); !bad.empty())
      throw std::invalid_argument("motion: frame " + std::to_string(f) + ": " + bad);
    out.push_back(crop_hu(frames[f], {0, 0, 0}, frames[f].dims));  // the whole frame
    if (const std::string d = grid_difference(out.back().grid, out.front().grid); !d.empty())
      throw std::invalid_argument("motion: frame " + std::to_string(f) + ": " + d + " (frame 0's grid)");
  }
  return out;
}

double residual_rms(const FloatImage& fixed, const FloatImage& moving, const DisplacementImage* u) {
  const ImageGrid& g = fixed.grid;
  double sum = 0.0;
  for (int64_t k = 0; k < g.dims[2]; ++k)
    for (int64_t j = 0; j < g.dims[1]; ++j)
      for (int64_t i = 0; i < g.dims[0]; ++i) {
        const int64_t n = g.index(i, j, k);
        float m = moving.v[n];
        if (u) {
          Eigen::Vector3d c = moving.grid.continuous_index(g.physical_mm(Eigen::Vector3d(i, j, k)) +
                                                           Eigen::Vector3d(u->x.v[n], u->y.v[n], u->z.v[n]));
          for (int a = 0; a < 3; ++a) c[a] = std::clamp(c[a], 0.0, static_cast<double>(moving.grid.dims[a] - 1));
          m = moving.at(c, 0.0f);
        }
        const double d = double(fixed.v[n]) - m;
        sum += d * d;
      }
  return std::sqrt(sum / static_cast<double>(g.size()));
}

double heart_overlap(const ImageGrid& g, const anatomy::HeartPose& pose) {
  const Eigen::Matrix3Xd& v = anatomy::template_heart_mesh().vertices_m;
  long inside = 0;
  for (Eigen::Index c = 0; c < v.cols(); ++c) {
    const Eigen::Vector3d ijk = g.continuous_index(1e3 * pose.to_case(v.col(c)));
    bool in = true;
    for (int a = 0; a < 3; ++a) in = in && ijk[a] >= -0.5 && ijk[a] <= g.dims[a] - 0.5;
    inside += in;
  }
  return v.cols() ? double(inside) / double(v.cols()) : 0.0;
}

std::vector<std::string> order_frame_files(std::vector<std::string> paths) {
  struct Named {
    std::string path, prefix, name;
    long number = -1;  // -1: no number
  };
  std::vector<Named> files;
  for (const std::string& p : paths) {
    Named n{p, "", std::filesystem::path(p).filename().string()};
    const std::string stem = std::filesystem::path(p).stem().string();
    size_t k = stem.size();
    while (k > 0 && std::isdigit(static_cast<unsigned char>(stem[k - 1]))) --k;
    if (k < stem.size() && stem.size() - k <= 9) {
      n.prefix = stem.substr(0, k);
      n.number = std::stol(stem.substr(k));
    }
    files.push_back(n);
  }
  const auto numbered = std::count_if(files.begin(), files.end(), [](const Named& n) { return n.number >= 0; });
  if (numbered == 0) {
    std::sort(paths.begin(), paths.end());
    return paths;
  }
  for (const Named& n : files) {
    if (n.number < 0)
      throw std::invalid_argument(fmt::format(
          "motion: '{}' has no frame number while the other files do: a sequence folder holds its frames only",
          n.name));
    if (n.prefix != files.front().prefix)
      throw std::invalid_argument(
          fmt::format("motion: '{}' and '{}' name two sequences: a folder holds one", files.front().name, n.name));
  }
  std::sort(files.begin(), files.end(), [](const Named& a, const Named& b) { return a.number < b.number; });
  for (size_t i = 1; i < files.size(); ++i) {
    if (files[i].number == files[i - 1].number)
      throw std::invalid_argument(fmt::format("motion: frame number {} appears twice ({} and {})", files[i].number,
                                              files[i - 1].name, files[i].name));
    if (files[i].number != files[i - 1].number + 1)
      throw std::invalid_argument(fmt::format(
          "motion: frame number {} is missing ({} is followed by {}): a lost phase would put every later frame at "
          "the wrong phase; supply it or renumber the sequence",
          files[i - 1].number + 1, files[i - 1].name, files[i].name));
  }
  std::vector<std::string> out;
  for (const Named& n : files) out.push_back(n.path);
  return out;
}

anatomy::HeartMotion recover_heart_motion(const std::vector<anatomy::Volume>& frames, double cycle_s,
                                          const anatomy::MotionGrid& grid, const anatomy::HeartPose& pose,
                                          const DemonsOptions& options, std::vector<MotionFrameReport>* reports,
                                          const std::function<void(const MotionFrameReport&)>& progress) {
  if (const std::string bad = validate(options); !bad.empty()) throw std::invalid_argument("motion: demons " + bad);
  const std::vector<FloatImage> images = sequence_images(frames);
  if (const double share = heart_overlap(images[0].grid, pose); share < kMinHeartOverlap) {
    throw std::invalid_argument(fmt::format(
        "motion: only {:.0f} % of the heart lies inside the images (at least {:.0f} % needed): the sequence does not "
        "show this case's heart (check --heart, or the images' origin and direction)",
        100.0 * share, 100.0 * kMinHeartOverlap));
  }
  const long nodes = grid.node_count();
  std::vector<float> data(images.size() * static_cast<size_t>(nodes) * 3, 0.0f);  // frame 0: no motion
  const Eigen::Matrix3d back = pose.rotation.transpose() / pose.scale;            // case -> template, per length
  for (size_t f = 1; f < images.size(); ++f) {
    MotionFrameReport r;
    r.frame = static_cast<int>(f);
    const auto t0 = std::chrono::steady_clock::now();
    const DisplacementImage u = diffeomorphic_demons(images[0], images[f], options, &r.metric);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.rms_before = residual_rms(images[0], images[f], nullptr);
    r.rms_after = residual_rms(images[0], images[f], &u);
    // each grid node: where its rest point lies in the images, the field there, back to the template
    float* out = data.data() + f * static_cast<size_t>(nodes) * 3;
    for (int k = 0; k < grid.dims.z(); ++k)
      for (int j = 0; j < grid.dims.y(); ++j)
        for (int i = 0; i < grid.dims.x(); ++i) {
          const Eigen::Vector3d rest_m = grid.origin_m + grid.spacing_m.cwiseProduct(Eigen::Vector3d(i, j, k));
          const Eigen::Vector3d d_m = back * (1e-3 * u.at_mm(1e3 * pose.to_case(rest_m)));
          for (int a = 0; a < 3; ++a) *out++ = static_cast<float>(d_m[a]);
        }
    if (reports) reports->push_back(r);
    if (progress) progress(r);
  }
  return anatomy::HeartMotion(grid, static_cast<int>(images.size()), cycle_s, std::move(data));
}

}  // namespace pcisim::modeling
