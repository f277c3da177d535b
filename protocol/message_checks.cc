#include "protocol/message_checks.h"

#include <cmath>
#include <string>

#include "protocol/probe_ranges.h"

namespace pcisim::protocol {
namespace {

template <class... T>
bool finite(T... v) {
  return (std::isfinite(static_cast<double>(v)) && ...);
}

// a name that may reach a JSON text (the remote page) or a log: well-formed UTF-8 (RFC 3629: no
// overlong forms, no surrogates, nothing past U+10FFFF), no NUL
bool utf8(const std::string& s) {
  size_t i = 0;
  const size_t n = s.size();
  while (i < n) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c == 0) return false;
    if (c < 0x80) {
      ++i;
      continue;
    }
    int more = 0;
    uint32_t cp = 0, least = 0;
    if ((c & 0xe0) == 0xc0) {
      more = 1, cp = c & 0x1f, least = 0x80;
    } else if ((c & 0xf0) == 0xe0) {
      more = 2, cp = c & 0x0f, least = 0x800;
    } else if ((c & 0xf8) == 0xf0) {
      more = 3, cp = c & 0x07, least = 0x10000;
    } else {
      return false;
    }
    if (i + static_cast<size_t>(more) >= n) return false;  // cut short
    for (int k = 1; k <= more; ++k) {
      const auto d = static_cast<unsigned char>(s[i + k]);
      if ((d & 0xc0) != 0x80) return false;
      cp = cp << 6 | (d & 0x3f);
    }
    if (cp < least || cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff)) return false;
    i += static_cast<size_t>(more) + 1;
  }
  return true;
}

}  // namespace

bool is_well_formed(const pcisim_lcm::instrument_state_t& m) {
  // finite, and within what a hand on a guidewire can do (10 m of wire, 10 m/s, 1000 rad/s): a
  // finite but absurd rate would overflow the passivity observer's energy
  return finite(m.insertion_mm, m.rotation_rad, m.insertion_rate_mm_s, m.rotation_rate_rad_s) &&
         std::abs(m.insertion_mm) <= 1e4 && std::abs(m.insertion_rate_mm_s) <= 1e4 &&
         std::abs(m.rotation_rate_rad_s) <= 1e3 && std::abs(m.rotation_rad) <= 1e6;
}

bool is_well_formed(const pcisim_lcm::force_command_t& m) {
  return finite(m.axial_force_n, m.torque_nmm, m.axial_stiffness_n_per_mm, m.torsional_stiffness_nmm_per_rad) &&
         m.axial_stiffness_n_per_mm >= 0.0 && m.torsional_stiffness_nmm_per_rad >= 0.0;
}

bool is_well_formed(const pcisim_lcm::session_command_t& m) {
  return finite(m.primary_angle_deg, m.secondary_angle_deg, m.contrast_ml, m.contrast_ml_s);
}

bool is_well_formed(const pcisim_lcm::wire_state_t& m) {
  if (m.num_nodes < 0 || m.node_mm.size() != static_cast<size_t>(m.num_nodes) || !utf8(m.tip_branch)) return false;
  for (const auto& p : m.node_mm)
    if (!finite(p[0], p[1], p[2])) return false;
  if (m.contact_force_n.size() != static_cast<size_t>(m.num_nodes)) return false;
  for (const auto& f : m.contact_force_n)
    if (!finite(f[0], f[1], f[2])) return false;
  return finite(m.sim_time_s, m.insertion_mm, m.rotation_rad, m.tip_mm[0], m.tip_mm[1], m.tip_mm[2], m.heart_phase,
                m.tip_force_n, m.hub_force_n, m.hub_torque_nm);
}

bool is_well_formed(const pcisim_lcm::sim_status_t& m) {
  if (m.num_effects < 0 || m.contrast_injections < 0) return false;
  for (double v : m.effect_step_ms_p50)
    if (!finite(v)) return false;
  for (const std::string& name : m.effect_name)
    if (!utf8(name)) return false;
  if (!finite(m.fluoro_time_s, m.carm_primary_deg, m.carm_secondary_deg, m.contrast_ml)) return false;
  return finite(m.haptic_rate_hz, m.haptic_period_us_p50, m.haptic_period_us_p99, m.haptic_period_us_p999,
                m.haptic_period_us_max, m.haptic_compute_us_p50, m.haptic_compute_us_p99, m.haptic_compute_us_max,
                m.physics_rate_hz, m.physics_step_ms_p50, m.physics_step_ms_p99, m.physics_step_ms_max, m.xray_fps);
}

bool is_well_formed(const pcisim_lcm::session_metrics_t& m) {
  if (m.cine_runs < 0 || m.fluoro_pulses < 0 || m.cine_frames < 0 || m.contrast_injections < 0 || m.force_events < 0 ||
      m.prolapse_events < 0 || m.buckling_events < 0 || m.wire_restarts < 0 || !utf8(m.target_branch))
    return false;
  if (!finite(m.target_reached_s)) return false;
  for (double v : {m.procedure_time_s, m.fluoro_time_s, m.cine_time_s, m.contrast_ml, m.air_kerma_mgy, m.dap_gycm2,
                   m.tip_path_mm, m.tip_path_projected_mm, m.tip_path_in_vessels_mm, m.wrong_branch_s,
                   m.peak_tip_force_n, m.tip_force_above_threshold_s})
    if (!finite(v) || v < 0.0) return false;
  return true;
}

bool is_well_formed(const pcisim_lcm::xray_frame_t& m) {
  if (m.width < 0 || m.height < 0 || m.num_bytes < 0 || m.num_wire_points < 0) return false;
  using F = pcisim_lcm::xray_frame_t;
  // raw grey frames must hold exactly width x height pixels; PNG is compressed; nothing else exists
  if (m.pixel_format != F::FORMAT_GRAY8 && m.pixel_format != F::FORMAT_GRAY16 && m.pixel_format != F::FORMAT_PNG)
    return false;
  const int64_t bytes_per_pixel = m.pixel_format == F::FORMAT_GRAY16 ? 2 : m.pixel_format == F::FORMAT_GRAY8 ? 1 : 0;
  if (bytes_per_pixel && int64_t{m.width} * m.height * bytes_per_pixel != m.num_bytes) return false;
  for (int k = 0; k < 3; ++k)
    if (!finite(m.source_mm[k], m.detector_center_mm[k], m.detector_u[k], m.detector_v[k])) return false;
  for (const auto& p : m.wire_mm)
    if (!finite(p[0], p[1], p[2])) return false;
  for (const std::string& name : m.contrast_branches)
    if (!utf8(name)) return false;
  return finite(m.primary_angle_deg, m.secondary_angle_deg, m.source_to_image_mm, m.source_to_axis_mm, m.pixel_mm,
                m.sim_time_s);
}

bool is_well_formed(const pcisim_lcm::probe_state_t& m) {
  const auto& p = m.position_mm;
  const auto& q = m.orientation_wxyz;
  if (!finite(p[0], p[1], p[2], q[0], q[1], q[2], q[3], m.depth_mm, m.gain_db)) return false;
  if (!is_probe_position_mm(p[0], p[1], p[2])) return false;
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  return std::abs(norm - 1.0) <= kProbeQuaternionNormTolerance && is_probe_depth_mm(m.depth_mm) &&
         is_probe_gain_db(m.gain_db);
}

bool is_well_formed(const pcisim_lcm::us_frame_t& m) {
  using F = pcisim_lcm::us_frame_t;
  if (m.width <= 0 || m.height <= 0 || m.width > 4096 || m.height > 4096) return false;
  if (m.pixel_format != F::FORMAT_GRAY8 || int64_t{m.width} * m.height != m.num_bytes) return false;
  if (m.geometry != F::GEOMETRY_LINEAR && m.geometry != F::GEOMETRY_CURVILINEAR) return false;
  for (int k = 0; k < 3; ++k)
    if (!finite(m.origin_mm[k], m.beam[k], m.lateral[k], m.probe_force_n[k])) return false;
  const auto dot = [](const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  // pixel -> world takes beam and lateral as an orthonormal pair: a lateral along the beam has no plane
  if (std::abs(dot(m.beam, m.beam) - 1.0) > 1e-3 || std::abs(dot(m.lateral, m.lateral) - 1.0) > 1e-3 ||
      std::abs(dot(m.beam, m.lateral)) > 1e-3)
    return false;
  if (!finite(m.depth_mm, m.width_mm, m.fan_angle_deg, m.radius_of_curvature_mm, m.gain_db, m.frequency_mhz,
              m.sim_time_s))
    return false;
  // the renderer's ranges (docs/ultrasound.md); the other geometry's fields are not read, only not negative
  if (!(m.depth_mm > 0.0 && m.depth_mm <= 300.0) || m.width_mm < 0.0 || m.fan_angle_deg < 0.0 ||
      m.radius_of_curvature_mm < 0.0)
    return false;
  if (std::abs(m.gain_db) > 60.0 || m.frequency_mhz < 1.0 || m.frequency_mhz > 20.0) return false;
  if (m.geometry == F::GEOMETRY_LINEAR) return m.width_mm > 0.0 && m.width_mm <= 200.0;
  return m.fan_angle_deg > 0.0 && m.fan_angle_deg <= 150.0 && m.radius_of_curvature_mm > 0.0 &&
         m.radius_of_curvature_mm <= 200.0;
}

}  // namespace pcisim::protocol
