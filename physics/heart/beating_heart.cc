#include "physics/heart/beating_heart.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <stdexcept>
#include <string>

#include "anatomy/heart/heart_frame.h"
#include "anatomy/heart/heart_mesh.h"
#include "anatomy/heart/heart_motion.h"
#include "anatomy/heart/synthetic_heart_motion.h"
#include "anatomy/heart/template_heart_surface.h"
#include "physics/pbd/grid_clusters.h"

namespace pcisim::physics {
namespace {

constexpr double kDensityKgPerM3 = 1050.0;  // myocardium

// no strings unless it fails: set_rate_bpm runs between steps and must not allocate
void check(const ParamRange& range, double value, const char* field) {
  if (!range.contains(value))
    throw std::invalid_argument(std::string("heart_beat.") + field + " must be in " + range.describe() + ", got " +
                                std::to_string(value));
}

void validate_rate(double rate_bpm) {
  check(kHeartRateBpm, rate_bpm, "rate_bpm");
}

void validate(const HeartBeatParams& p) {
  validate_rate(p.rate_bpm);
  check(kHeartSubsteps, p.substeps, "substeps");
  check(kHeartIterations, p.iterations, "iterations");
  check(kHeartSorW, p.sor_w, "sor_w");
  check(kHeartStretchComplianceMPerN, p.stretch_compliance_m_per_n, "stretch_compliance_m_per_n");
  check(kHeartBendCompliancePerNM, p.bend_compliance_per_n_m, "bend_compliance_per_n_m");
  check(kHeartShapeComplianceS2, p.shape_compliance_s2, "shape_compliance_s2");
  check(kHeartDampingPerS, p.damping_per_s, "damping_per_s");
  // local clusters smaller than a few tet edges hold too few particles to match a shape (and a
  // grid of sub-millimetre cubes over the heart would take for ever to fill)
  if (p.cluster_size_m != 0.0) check(kHeartClusterSizeM, p.cluster_size_m, "cluster_size_m");
}

anatomy::HeartMotion load_motion(const HeartBeatParams& p) {
  if (p.motion_file.empty()) return anatomy::make_synthetic_heart_motion();
  try {
    return anatomy::HeartMotion::read(p.motion_file);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("heart_beat.motion_file: ") + e.what());
  }
}

}  // namespace

struct BeatingHeart::Impl {
  HeartBeatParams params;
  anatomy::HeartMotion motion;
  pbd::PbdParams pbd;
  pbd::PbdSystem system;
  Eigen::Matrix3Xd rest_m;
  std::vector<std::array<int, 4>> tets;
  std::vector<std::array<int, 3>> epicardium, lv_endocardium;
  std::vector<int> driven, free;
  // each driven particle's displacement in every frame (column frame * driven + k): a step then
  // only blends four frames, the same sum displacement_m does, without the trilinear lookups
  Eigen::Matrix3Xd frame_displacement_m;
  double time_s = 0.0;
  double phase = 0.0;

  Impl(const HeartBeatParams& p, const anatomy::HeartMesh& mesh, const HeartTissueScaling& scaling)
      : params(p), motion(load_motion(p)) {
    // particles: the vertices some tet uses, in file order
    std::vector<int> to_particle(mesh.vertices_m.cols(), -1);
    for (const auto& t : mesh.tets)
      for (int v : t) to_particle[v] = 0;
    int n = 0;
    for (int& id : to_particle)
      if (id == 0) id = n++;
    rest_m.resize(3, n);
    for (int v = 0; v < mesh.vertices_m.cols(); ++v)
      if (to_particle[v] >= 0) rest_m.col(to_particle[v]) = mesh.vertices_m.col(v);

    // mass: a quarter of each tet's volume to each of its vertices
    std::vector<double> mass_kg(n, 0.0);
    for (const auto& t : mesh.tets) {
      std::array<int, 4> q;
      for (int k = 0; k < 4; ++k) q[k] = to_particle[t[k]];
      const Eigen::Vector3d a = rest_m.col(q[0]);
      const double volume_m3 =
          std::abs((rest_m.col(q[1]) - a).cross(rest_m.col(q[2]) - a).dot(rest_m.col(q[3]) - a)) / 6.0;
      for (int k = 0; k < 4; ++k) mass_kg[q[k]] += 0.25 * kDensityKgPerM3 * volume_m3;
      tets.push_back(q);
    }
    std::vector<double> compliance_scale(n, 1.0);
    for (int i = 0; i < n; ++i) {
      // errors name the particle and where it is, so a bad mesh or scaling can be found
      auto where = [&] {
        const Eigen::Vector3d x_mm = 1e3 * rest_m.col(i);
        char text[96];
        std::snprintf(text, sizeof text, "heart particle %d at (%.1f, %.1f, %.1f) mm", i, x_mm.x(), x_mm.y(), x_mm.z());
        return std::string(text);
      };
      if (!(mass_kg[i] > 0.0)) throw std::invalid_argument(where() + ": its tetrahedra have no volume");
      if (scaling.mass_scale) {
        const double m = scaling.mass_scale(rest_m.col(i));
        if (!(m > 0.0) || !std::isfinite(m))
          throw std::invalid_argument(where() + ": mass scale must be finite and > 0, got " + std::to_string(m));
        mass_kg[i] *= m;
      }
      if (scaling.compliance_scale) {
        compliance_scale[i] = scaling.compliance_scale(rest_m.col(i));
        if (!(compliance_scale[i] >= 0.0) || !std::isfinite(compliance_scale[i]))
          throw std::invalid_argument(where() + ": compliance scale must be finite and >= 0, got " +
                                      std::to_string(compliance_scale[i]));
      }
    }
    for (int i = 0; i < n; ++i) system.add_particle(rest_m.col(i), mass_kg[i]);

    // the ventricles' myocardium is driven (heart paper section 4, fig 6); the rest is free
    // (below the AV plane: anatomy::ventricular_points, the points motion from images is measured at)
    std::vector<bool> is_driven(n, false);
    for (int i : anatomy::ventricular_points(rest_m)) is_driven[i] = true;
    for (int i = 0; i < n; ++i) {
      if (is_driven[i]) {
        system.drive(i);
        driven.push_back(i);
      } else {
        free.push_back(i);
      }
    }
    // a constraint among driven particles only would never move anything: left out
    auto any_free = [&](std::initializer_list<int> ids) {
      return std::any_of(ids.begin(), ids.end(), [&](int i) { return !is_driven[i]; });
    };
    auto scale = [&](std::initializer_list<int> ids) {
      double s = 0.0;
      for (int i : ids) s = std::max(s, compliance_scale[i]);
      return s;
    };

    // stretch: one spring per tet edge
    std::set<std::pair<int, int>> edges;
    for (const auto& t : tets)
      for (int a = 0; a < 4; ++a)
        for (int b = a + 1; b < 4; ++b) edges.insert(std::minmax(t[a], t[b]));
    for (const auto& [i, j] : edges)
      if (any_free({i, j})) system.add_distance(i, j, p.stretch_compliance_m_per_n * scale({i, j}));

    // twist: for two tets sharing a face, a spring between their far vertices; it spans the
    // shared face, so shearing or twisting the pair about that face stretches it
    std::map<std::array<int, 3>, int> face_far;
    std::set<std::pair<int, int>> twist;
    for (const auto& t : tets)
      for (int k = 0; k < 4; ++k) {
        std::array<int, 3> f = {t[(k + 1) % 4], t[(k + 2) % 4], t[(k + 3) % 4]};
        std::sort(f.begin(), f.end());
        auto [it, inserted] = face_far.emplace(f, t[k]);
        if (!inserted && it->second != t[k]) {
          const auto pair = std::minmax(it->second, t[k]);
          if (!edges.count(pair)) twist.insert(pair);
        }
      }
    for (const auto& [i, j] : twist)
      if (any_free({i, j})) system.add_distance(i, j, p.stretch_compliance_m_per_n * scale({i, j}));

    // surfaces, in particle indices
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
      const std::array<int, 3> tri = {to_particle[mesh.faces[f][0]], to_particle[mesh.faces[f][1]],
                                      to_particle[mesh.faces[f][2]]};
      if (mesh.face_markers[f] == anatomy::kEpicardium) epicardium.push_back(tri);
      if (mesh.face_markers[f] == anatomy::kLvEndocardium) lv_endocardium.push_back(tri);
    }
    if (epicardium.empty() || lv_endocardium.empty())
      throw std::invalid_argument("heart mesh: no epicardium (marker 1) or LV endocardium (marker 2) faces");

    // bend: a dihedral spring on every pair of epicardial triangles that share an edge
    std::map<std::pair<int, int>, std::pair<int, int>> wing;  // edge -> (first wing, second wing)
    for (const auto& t : epicardium)
      for (int k = 0; k < 3; ++k) {
        const auto e = std::minmax(t[k], t[(k + 1) % 3]);
        auto [it, inserted] = wing.emplace(e, std::pair{t[(k + 2) % 3], -1});
        if (!inserted) it->second.second = t[(k + 2) % 3];
      }
    for (const auto& [e, w] : wing)
      if (w.second >= 0 && any_free({e.first, e.second, w.first, w.second}))
        system.add_bending(e.first, e.second, w.first, w.second,
                           p.bend_compliance_per_n_m * scale({e.first, e.second, w.first, w.second}));

    // one global shape-matching cluster over every particle (heart paper eqs 7-10)
    std::vector<int> all(n);
    for (int i = 0; i < n; ++i) all[i] = i;
    system.add_cluster(all, p.shape_compliance_s2);
    // local clusters where they can act: those holding at least one free particle
    if (p.cluster_size_m > 0.0) {
      for (const auto& members : pbd::grid_clusters(rest_m, p.cluster_size_m, 0.25))
        if (std::any_of(members.begin(), members.end(), [&](int i) { return !is_driven[i]; }))
          system.add_cluster(members, p.shape_compliance_s2);
    }
    system.finalize();

    pbd.substeps = p.substeps;
    pbd.iterations = p.iterations;
    pbd.solver = p.solver;
    pbd.sor_w = p.sor_w;
    // each constraint's impulse stays balanced: momentum kept as in Gauss-Seidel (docs/pbd.md)
    pbd.averaging = pbd::JacobiAveraging::kPerConstraint;
    pbd.damping_per_s = p.damping_per_s;

    const int nd = static_cast<int>(driven.size());
    frame_displacement_m.resize(3, static_cast<Eigen::Index>(motion.frames()) * nd);
    for (int f = 0; f < motion.frames(); ++f)
      for (int k = 0; k < nd; ++k)
        frame_displacement_m.col(f * nd + k) = motion.frame_displacement_m(f, rest_m.col(driven[k]));

    // start at phase 0 exactly on the sequence
    for (int i : driven) {
      const Eigen::Vector3d x = driven_position(i, 0.0);
      system.particles().position_m.col(i) = x;
      system.particles().predicted_m.col(i) = x;
      system.particles().last_finite_m.col(i) = x;
      system.set_driven_target(i, x);
    }
  }

  Eigen::Vector3d driven_position(int i, double at_phase) const {
    return rest_m.col(i) + motion.displacement_m(rest_m.col(i), at_phase);
  }
};

BeatingHeart::BeatingHeart(const HeartBeatParams& params) : BeatingHeart(params, HeartTissueScaling{}) {}

BeatingHeart::BeatingHeart(const HeartBeatParams& params, const HeartTissueScaling& scaling)
    : BeatingHeart(params, anatomy::template_heart_mesh(), scaling) {}

BeatingHeart::BeatingHeart(const HeartBeatParams& params, const anatomy::HeartMesh& mesh,
                           const HeartTissueScaling& scaling) {
  validate(params);
  impl_ = std::make_unique<Impl>(params, mesh, scaling);
}

BeatingHeart::~BeatingHeart() = default;

void BeatingHeart::step(double dt_s) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) return;
  Impl& m = *impl_;
  m.time_s += dt_s;
  // accumulate the phase itself (not time * rate) so it stays exact over days of beating
  m.phase += dt_s * m.params.rate_bpm / 60.0;
  m.phase -= std::floor(m.phase);
  if (m.phase >= 1.0) m.phase = 0.0;
  const anatomy::HeartMotion::FrameWeights w = m.motion.frame_weights(m.phase);
  const int nd = static_cast<int>(m.driven.size());
  for (int k = 0; k < nd; ++k) {
    const int i = m.driven[k];
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    for (int j = 0; j < 4; ++j) d += w.weight[j] * m.frame_displacement_m.col(w.frame[j] * nd + k);
    m.system.set_driven_target(i, m.rest_m.col(i) + d);
  }
  m.system.step(dt_s, m.pbd);
}

void BeatingHeart::set_rate_bpm(double rate_bpm) {
  validate_rate(rate_bpm);
  impl_->params.rate_bpm = rate_bpm;
}

double BeatingHeart::phase() const {
  return impl_->phase;
}
double BeatingHeart::time_s() const {
  return impl_->time_s;
}
const Eigen::Matrix3Xd& BeatingHeart::positions_m() const {
  return impl_->system.particles().position_m;
}
const Eigen::Matrix3Xd& BeatingHeart::rest_positions_m() const {
  return impl_->rest_m;
}
std::span<const std::array<int, 3>> BeatingHeart::epicardium() const {
  return impl_->epicardium;
}
std::span<const int> BeatingHeart::driven() const {
  return impl_->driven;
}
std::span<const int> BeatingHeart::free_particles() const {
  return impl_->free;
}
std::span<const std::array<int, 4>> BeatingHeart::tets() const {
  return impl_->tets;
}
std::span<const std::array<int, 3>> BeatingHeart::lv_endocardium() const {
  return impl_->lv_endocardium;
}
const anatomy::HeartMotion& BeatingHeart::motion() const {
  return impl_->motion;
}
Eigen::Vector3d BeatingHeart::driven_position_m(int i, double phase) const {
  return impl_->driven_position(i, phase);
}
const pbd::PbdSystem& BeatingHeart::system() const {
  return impl_->system;
}
pbd::PbdSystem& BeatingHeart::system() {
  return impl_->system;
}
const HeartBeatParams& BeatingHeart::params() const {
  return impl_->params;
}

}  // namespace pcisim::physics
