#pragma once
// Every malformed shape of every pcisim LCM message, for the tests that show no handler in any
// program lets one through or falls over, and for pcisim-lcm-flood (scripts/soak). The shapes:
// truncation at every byte, trailing bytes, a wrong fingerprint, and for each string length and array count 0, -1,
// INT32_MIN, just past the end, INT32_MAX and 1e8. Length fields are found in a valid encoding by their known
// neighbours.
#include <cstdint>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "pcisim_lcm/force_command_t.hpp"
#include "pcisim_lcm/instrument_state_t.hpp"
#include "pcisim_lcm/probe_state_t.hpp"
#include "pcisim_lcm/session_command_t.hpp"
#include "pcisim_lcm/session_metrics_t.hpp"
#include "pcisim_lcm/sim_status_t.hpp"
#include "pcisim_lcm/us_frame_t.hpp"
#include "pcisim_lcm/wire_state_t.hpp"
#include "pcisim_lcm/xray_frame_t.hpp"

namespace pcisim::fuzz {

using Bytes = std::vector<uint8_t>;

struct Mutant {
  std::string what;
  Bytes bytes;
};

template <class M>
Bytes encode(const M& m) {
  Bytes b(static_cast<size_t>(m.getEncodedSize()));
  if (m.encode(b.data(), 0, static_cast<int>(b.size())) != static_cast<int>(b.size()))
    throw std::logic_error("encode failed");
  return b;
}

inline Bytes be32(int32_t v) {
  const auto u = static_cast<uint32_t>(v);
  return {static_cast<uint8_t>(u >> 24), static_cast<uint8_t>(u >> 16), static_cast<uint8_t>(u >> 8),
          static_cast<uint8_t>(u)};
}

inline Bytes cat(Bytes a, const Bytes& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

inline Bytes text(const std::string& s) {
  return Bytes(s.begin(), s.end());
}

// offset of the int32 length/count field that comes just before `after` in `good`
inline size_t length_field(const Bytes& good, const Bytes& after) {
  for (size_t i = 4; i + after.size() <= good.size(); ++i)
    if (std::memcmp(good.data() + i, after.data(), after.size()) == 0) return i - 4;
  throw std::logic_error("length field not found");
}

// truncations, trailing bytes, a wrong fingerprint
inline std::vector<Mutant> framing_mutants(const Bytes& good) {
  std::vector<Mutant> out;
  for (size_t n = 0; n < good.size(); ++n)
    out.push_back({"truncated to " + std::to_string(n), Bytes(good.begin(), good.begin() + n)});
  out.push_back({"one trailing byte", cat(good, {0})});
  Bytes wrong = good;
  wrong[3] ^= 0x5a;
  out.push_back({"wrong fingerprint", wrong});
  return out;
}

// the length/count at `offset` replaced by every hostile value
inline std::vector<Mutant> length_mutants(const Bytes& good, size_t offset, const std::string& field) {
  const auto left = static_cast<int32_t>(good.size() - offset - 4);
  std::vector<Mutant> out;
  for (int32_t v : {0, -1, INT32_MIN, left + 1, INT32_MAX, 100'000'000}) {
    Bytes b = good;
    const Bytes f = be32(v);
    std::memcpy(b.data() + offset, f.data(), 4);
    out.push_back({field + " = " + std::to_string(v), b});
  }
  return out;
}

inline std::vector<Mutant> all_mutants(const Bytes& good, const std::vector<std::pair<size_t, std::string>>& fields) {
  auto out = framing_mutants(good);
  for (const auto& [offset, name] : fields) {
    auto more = length_mutants(good, offset, name);
    out.insert(out.end(), more.begin(), more.end());
  }
  return out;
}

// one valid message of each type and its mutants; `good` decodes, every mutant must not
struct MessageCase {
  std::string type;
  Bytes good;
  std::vector<Mutant> mutants;
};

// a type with no string or array: only the framing can be wrong
template <class M>
MessageCase fixed_size_case(const std::string& type, const M& m) {
  const Bytes good = encode(m);
  return {type, good, framing_mutants(good)};
}

inline MessageCase instrument_case() {
  pcisim_lcm::instrument_state_t m{};
  m.utime = 1;
  m.insertion_mm = 10;
  return fixed_size_case("instrument_state_t", m);
}

inline MessageCase probe_case() {
  pcisim_lcm::probe_state_t m{};
  m.utime = 1;
  m.position_mm[2] = 40;
  m.orientation_wxyz[0] = 1;
  return fixed_size_case("probe_state_t", m);
}

inline MessageCase force_case() {
  pcisim_lcm::force_command_t m{};
  m.utime = 1;
  m.axial_force_n = 0.5;
  return fixed_size_case("force_command_t", m);
}

inline MessageCase session_case() {
  pcisim_lcm::session_command_t m{};
  m.utime = 1;
  m.command = pcisim_lcm::session_command_t::CMD_PAUSE;
  m.scene_path = "SCENE-PATH";
  const Bytes good = encode(m);
  return {"session_command_t", good,
          all_mutants(good, {{length_field(good, text("SCENE-PATH")), "scene_path length"}})};
}

inline MessageCase status_case() {
  pcisim_lcm::sim_status_t m{};
  m.utime = 1;
  m.num_effects = 2;
  m.effect_name = {"EFFA", "EFFB"};
  m.effect_step_ms_p50 = {1.0, 2.0};
  const Bytes good = encode(m);
  const size_t name_len = length_field(good, text("EFFA"));
  return {"sim_status_t", good,
          all_mutants(good, {{length_field(good, cat(be32(5), text("EFFA"))), "num_effects"},
                             {name_len, "effect_name[0] length"}})};
}

inline MessageCase metrics_case() {
  pcisim_lcm::session_metrics_t m{};
  m.utime = 1;
  m.has_target = 1;
  m.target_branch = "TARGET-LAD";
  m.target_reached_s = -1;
  const Bytes good = encode(m);
  return {"session_metrics_t", good,
          all_mutants(good, {{length_field(good, text("TARGET-LAD")), "target_branch length"}})};
}

inline MessageCase wire_case() {
  pcisim_lcm::wire_state_t m{};
  m.utime = 1;
  m.num_nodes = 2;
  m.node_mm = {{1.5f, 0, 0}, {2, 0, 0}};
  m.contact = {0, 1};
  m.contact_force_n = {{0, 0, 0}, {0, -0.25f, 0}};
  m.tip_branch = "TIP-BRANCH";
  const Bytes good = encode(m);
  return {"wire_state_t", good,
          all_mutants(good, {{length_field(good, {0x3f, 0xc0, 0x00, 0x00}), "num_nodes"},
                             {length_field(good, text("TIP-BRANCH")), "tip_branch length"}})};
}

inline MessageCase xray_case() {
  pcisim_lcm::xray_frame_t m{};
  m.utime = 1;
  m.width = 2;
  m.height = 1;
  m.pixel_format = pcisim_lcm::xray_frame_t::FORMAT_GRAY16;
  m.num_wire_points = 1;
  m.wire_mm = {{1.5f, 0, 0}};
  m.wire_px = {{0.5f, 0.5f}};
  m.num_contrast_branches = 1;
  m.contrast_branches = {"BRANCH-LAD"};
  m.num_bytes = 4;
  m.data = {0xde, 0xad, 0xbe, 0xef};
  const Bytes good = encode(m);
  return {"xray_frame_t", good,
          all_mutants(good, {{length_field(good, {0x3f, 0xc0, 0x00, 0x00}), "num_wire_points"},
                             {length_field(good, cat(be32(11), text("BRANCH-LAD"))), "num_contrast_branches"},
                             {length_field(good, text("BRANCH-LAD")), "contrast_branches[0] length"},
                             {length_field(good, {0xde, 0xad, 0xbe, 0xef}), "num_bytes"}})};
}

inline MessageCase us_frame_case() {
  using F = pcisim_lcm::us_frame_t;
  F m{};
  m.utime = 1;
  m.width = 2;
  m.height = 2;
  m.pixel_format = F::FORMAT_GRAY8;
  m.geometry = F::GEOMETRY_LINEAR;
  m.depth_mm = 60;
  m.width_mm = 40;
  m.frequency_mhz = 5;
  m.beam[2] = 1;
  m.lateral[0] = 1;
  m.num_bytes = 4;
  m.data = {0xde, 0xad, 0xbe, 0xef};
  const Bytes good = encode(m);
  return {"us_frame_t", good, all_mutants(good, {{length_field(good, {0xde, 0xad, 0xbe, 0xef}), "num_bytes"}})};
}

}  // namespace pcisim::fuzz
