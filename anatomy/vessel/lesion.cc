#include "anatomy/vessel/lesion.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <fmt/format.h>

namespace pcisim::anatomy {
namespace {

// a quadratic d(s) = c0 + c1 s + c2 s^2 by least squares over the points `use` marks (a line, or a
// constant, when too few points span too little for a curve)
Eigen::Vector3d fit_reference(const std::vector<double>& s, const std::vector<double>& d,
                              const std::vector<char>& use) {
  int n = 0;
  for (char u : use) n += u != 0;
  const int terms = n >= 8 ? 3 : n >= 3 ? 2 : 1;
  Eigen::MatrixXd a(n, terms);
  Eigen::VectorXd b(n);
  int row = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    if (!use[i]) continue;
    for (int t = 0; t < terms; ++t) a(row, t) = std::pow(s[i], t);
    b(row++) = d[i];
  }
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  if (n == 0) return c;
  c.head(terms) = a.colPivHouseholderQr().solve(b);
  return c;
}

double evaluate(const Eigen::Vector3d& c, double s) {
  return c[0] + c[1] * s + c[2] * s * s;
}

}  // namespace

std::vector<Lesion> detect_lesions(const VesselTree& tree, const LesionDetection& options) {
  std::vector<Lesion> found;
  for (const VesselBranch& branch : tree.branches) {
    const size_t n = branch.points.size();
    if (static_cast<int>(n) < options.min_points) continue;
    // the radius profile in mm along the arc length
    std::vector<double> s(n, 0.0), d(n, 0.0);
    for (size_t i = 0; i < n; ++i) {
      if (i > 0) s[i] = s[i - 1] + 1e3 * (branch.points[i].position_m - branch.points[i - 1].position_m).norm();
      d[i] = 2e3 * branch.points[i].radius_m;
    }
    // a running median (shorter windows at the ends) finds the runs and the healthy wall; the
    // narrowest point of a run is the traced profile's own (a median flattens a short lesion's tip)
    std::vector<double> raw = d;
    if (options.median_points > 1) {
      const int half = options.median_points / 2;
      std::vector<double> smooth(n), window;
      window.reserve(static_cast<size_t>(2 * half + 1));
      for (size_t i = 0; i < n; ++i) {
        window.clear();
        const size_t lo = i >= static_cast<size_t>(half) ? i - half : 0, hi = std::min(n - 1, i + half);
        for (size_t k = lo; k <= hi; ++k) window.push_back(d[k]);
        std::nth_element(window.begin(), window.begin() + window.size() / 2, window.end());
        smooth[i] = window[window.size() / 2];
      }
      raw.swap(d);
      d.swap(smooth);
    }
    // the healthy wall: fitted to every point, then to those not narrowed against the last fit
    std::vector<char> use(n, 1);
    Eigen::Vector3d c = fit_reference(s, d, use);
    for (int round = 1; round < options.fit_rounds; ++round) {
      for (size_t i = 0; i < n; ++i) use[i] = d[i] >= options.healthy_fraction * evaluate(c, s[i]);
      c = fit_reference(s, d, use);
    }
    // runs narrowed past the edge, reported where they reach the lesion's stenosis
    std::vector<double> ds(n);
    for (size_t i = 0; i < n; ++i) {
      const double ref = evaluate(c, s[i]);
      ds[i] = ref > 0.0 ? 100.0 * (1.0 - d[i] / ref) : 0.0;
    }
    for (size_t i = 0; i < n;) {
      if (!(ds[i] >= options.edge_stenosis_pct)) {  // (NaN too: a radius that is not a number)
        ++i;
        continue;
      }
      size_t end = i, narrowest = i;
      while (end < n && ds[end] >= options.edge_stenosis_pct) {
        if (raw[end] < raw[narrowest]) narrowest = end;
        ++end;
      }
      const double reference = evaluate(c, s[narrowest]);
      const double stenosis = reference > 0.0 ? 100.0 * (1.0 - raw[narrowest] / reference) : 0.0;
      const bool referable =
          s[i] - s.front() >= options.healthy_margin_mm && s.back() - s[end - 1] >= options.healthy_margin_mm;
      if (stenosis >= options.min_stenosis_pct && referable) {
        Lesion l;
        l.branch = branch.name;
        l.position_mm = s[narrowest];
        // the extent between the first and last narrowed points, half a spacing beyond each
        const double before = i > 0 ? 0.5 * (s[i] - s[i - 1]) : 0.0;
        const double after = end < n ? 0.5 * (s[end] - s[end - 1]) : 0.0;
        l.length_mm = s[end - 1] - s[i] + before + after;
        l.minimal_lumen_diameter_mm = raw[narrowest];
        l.reference_diameter_mm = reference;
        l.diameter_stenosis_pct = stenosis;
        found.push_back(l);
      }
      i = end;
    }
  }
  return found;
}

std::string validate_lesion(const Lesion& l, const VesselTree& tree) {
  const int b = tree.find(l.branch);
  if (b < 0) return fmt::format("branch: '{}' is not a branch of the case's vessels", l.branch);
  const double length_mm = 1e3 * branch_length_m(tree.branches[b]);
  const auto finite = [](double v) { return std::isfinite(v); };
  if (!finite(l.position_mm) || l.position_mm < 0.0 || l.position_mm > length_mm + 1e-6)
    return fmt::format("position_mm: expected an arc length within {}'s {:.1f} mm, got {}", l.branch, length_mm,
                       l.position_mm);
  if (!finite(l.length_mm) || l.length_mm < 0.0 || l.length_mm > length_mm + 1e-6)
    return fmt::format("length_mm: expected 0 to {:.1f} mm (the branch's length), got {}", length_mm, l.length_mm);
  if (!finite(l.reference_diameter_mm) || l.reference_diameter_mm <= 0.0 || l.reference_diameter_mm > 50.0)
    return fmt::format("reference_diameter_mm: expected (0, 50] mm, got {}", l.reference_diameter_mm);
  if (!finite(l.minimal_lumen_diameter_mm) || l.minimal_lumen_diameter_mm < 0.0 ||
      l.minimal_lumen_diameter_mm > l.reference_diameter_mm)
    return fmt::format("minimal_lumen_diameter_mm: expected 0 to the reference diameter ({} mm), got {}",
                       l.reference_diameter_mm, l.minimal_lumen_diameter_mm);
  const double pct = 100.0 * (1.0 - l.minimal_lumen_diameter_mm / l.reference_diameter_mm);
  if (!finite(l.diameter_stenosis_pct) || std::abs(l.diameter_stenosis_pct - pct) > 0.5)
    return fmt::format("diameter_stenosis_pct: expected 100 (1 - MLD / reference) = {:.1f}, got {}", pct,
                       l.diameter_stenosis_pct);
  if (!finite(l.calcified_fraction) || l.calcified_fraction < 0.0 || l.calcified_fraction > 1.0)
    return fmt::format("calcified_fraction: expected [0, 1], got {}", l.calcified_fraction);
  if (!finite(l.eccentricity) || l.eccentricity < 0.0 || l.eccentricity > 1.0)
    return fmt::format("eccentricity: expected [0, 1], got {}", l.eccentricity);
  return {};
}

}  // namespace pcisim::anatomy
