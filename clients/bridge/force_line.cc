#include "clients/bridge/force_line.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>

namespace pcisim::clients {
namespace {

// value x scale, rounded half away from zero, clamped to +-limit; 0 when not finite
int64_t to_units(double value, double scale, int64_t limit) {
  const double v = value * scale;
  if (!std::isfinite(v)) return 0;
  const double clamped = std::clamp(v, -static_cast<double>(limit), static_cast<double>(limit));
  return static_cast<int64_t>(std::llround(clamped));
}

// one space-separated signed integer
bool field(const char*& p, const char* end, int64_t& out) {
  if (p == end || *p != ' ') return false;
  while (p < end && *p == ' ') ++p;
  const auto r = std::from_chars(p, end, out);
  if (r.ec != std::errc() || r.ptr == p) return false;
  p = r.ptr;
  return true;
}

}  // namespace

size_t format_force_line(const ForceSetpoint& f, int64_t seq, char* buf) {
  // N -> mN; N mm -> uN m (1 N mm = 1e-3 N m = 1000 uN m)
  const long long axial = to_units(f.axial_n, 1e3, kMaxAxialMilliNewton);
  const long long torque = to_units(f.torque_nmm, 1e3, kMaxTorqueMicroNewtonMetre);
  const int n =
      std::snprintf(buf, kForceLineMaxBytes, "F %lld %lld %lld\n", axial, torque, static_cast<long long>(seq));
  return n > 0 ? std::min(static_cast<size_t>(n), kForceLineMaxBytes - 1) : 0;
}

bool parse_force_line(std::string_view line, ForceLine& out) {
  const char* p = line.data();
  const char* end = p + line.size();
  if (end > p && end[-1] == '\r') --end;
  if (end - p < 2 || p[0] != 'F') return false;
  ++p;
  ForceLine f;
  if (!field(p, end, f.axial_mn) || !field(p, end, f.torque_unm) || !field(p, end, f.seq)) return false;
  while (p < end && *p == ' ') ++p;
  if (p != end) return false;
  // explicit comparisons: std::abs of INT64_MIN is undefined
  if (f.axial_mn < -kMaxAxialMilliNewton || f.axial_mn > kMaxAxialMilliNewton ||
      f.torque_unm < -kMaxTorqueMicroNewtonMetre || f.torque_unm > kMaxTorqueMicroNewtonMetre)
    return false;
  out = f;
  return true;
}

}  // namespace pcisim::clients
