// Hostile bytes against the one decode path: every malformed shape of every message type is
// refused, nothing escapes as an exception, and no length or count makes the decoder allocate
// what the sender claims (lcm-gen's decoders resized first; cmake/harden_decoders.cmake).
#include <gtest/gtest.h>

#include "protocol/message_checks.h"
#include "realtime/allocation_count.h"
#include "fuzz/lcm_mutants.h"

namespace pcisim::protocol {
namespace {

using fuzz::MessageCase;

template <class M>
void expect_refused(const MessageCase& c) {
  M out;
  ASSERT_TRUE(decode_checked(c.good.data(), static_cast<int64_t>(c.good.size()), out)) << c.type << ": the good one";
  ASSERT_GT(c.mutants.size(), c.good.size()) << c.type;
  for (const auto& m : c.mutants) {
    M fresh;
    pcisim::realtime::AllocationCount alloc;
    bool ok = true;
    EXPECT_NO_THROW(ok = decode_checked(m.bytes.data(), static_cast<int64_t>(m.bytes.size()), fresh))
        << c.type << ": " << m.what;
    EXPECT_FALSE(ok) << c.type << ": " << m.what;
    // a count the buffer cannot hold is refused before anything is sized by it
    EXPECT_LT(alloc.largest(), 64 * 1024) << c.type << ": " << m.what;
  }
}

TEST(HostileDecode, InstrumentState) {
  expect_refused<pcisim_lcm::instrument_state_t>(fuzz::instrument_case());
}
TEST(HostileDecode, ProbeState) {
  expect_refused<pcisim_lcm::probe_state_t>(fuzz::probe_case());
}
TEST(HostileDecode, ForceCommand) {
  expect_refused<pcisim_lcm::force_command_t>(fuzz::force_case());
}
TEST(HostileDecode, SessionCommand) {
  expect_refused<pcisim_lcm::session_command_t>(fuzz::session_case());
}
TEST(HostileDecode, SimStatus) {
  expect_refused<pcisim_lcm::sim_status_t>(fuzz::status_case());
}
TEST(HostileDecode, SessionMetrics) {
  expect_refused<pcisim_lcm::session_metrics_t>(fuzz::metrics_case());
}
TEST(HostileDecode, WireState) {
  expect_refused<pcisim_lcm::wire_state_t>(fuzz::wire_case());
}
TEST(HostileDecode, XrayFrame) {
  expect_refused<pcisim_lcm::xray_frame_t>(fuzz::xray_case());
}
TEST(HostileDecode, UltrasoundFrame) {
  expect_refused<pcisim_lcm::us_frame_t>(fuzz::us_frame_case());
}

// names reach the remote page's JSON (whose writer throws on bad UTF-8, which stopped the gateway's
// tick: found in review, issue #35) and the logs: a name that is not well-formed UTF-8 is refused
TEST(HostileDecode, NamesThatAreNotUtf8AreRefused) {
  const auto round_trip = [](auto m) {
    std::vector<uint8_t> bytes(static_cast<size_t>(m.getEncodedSize()));
    m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    decltype(m) out;
    return decode_checked(bytes.data(), static_cast<int64_t>(bytes.size()), out);
  };
  for (const std::string bad : {std::string("\xff\xfe"), std::string("LAD\xc0\x80"), std::string("\xed\xa0\x80"),
                                std::string("\xf4\x90\x80\x80"), std::string("\xe2\x82"), std::string("a\0b", 3)}) {
    pcisim_lcm::wire_state_t w{};
    w.tip_branch = bad;
    EXPECT_FALSE(round_trip(w)) << "tip_branch";
    pcisim_lcm::session_metrics_t m{};
    m.target_branch = bad;
    EXPECT_FALSE(round_trip(m)) << "target_branch";
    pcisim_lcm::sim_status_t st{};
    st.num_effects = 1;
    st.effect_name = {bad};
    st.effect_step_ms_p50 = {1.0};
    EXPECT_FALSE(round_trip(st)) << "effect_name";
    pcisim_lcm::xray_frame_t x{};
    x.pixel_format = pcisim_lcm::xray_frame_t::FORMAT_PNG;
    x.num_contrast_branches = 1;
    x.contrast_branches = {bad};
    EXPECT_FALSE(round_trip(x)) << "contrast_branches";
  }
  // well-formed names in any script pass (two-, three- and four-byte forms)
  pcisim_lcm::wire_state_t w{};
  w.tip_branch = "D1 \xc3\xa9 \xe2\x86\x92 \xf0\x9f\xab\x80";
  EXPECT_TRUE(round_trip(w));
}

// the finding itself: a 66-byte session command whose scene_path length is 0 (it threw
// std::length_error out of the handler and ended the server)
TEST(HostileDecode, SessionCommandWithZeroLengthPathIsRefused) {
  pcisim_lcm::session_command_t m{};
  m.scene_path = "";
  auto bytes = fuzz::encode(m);
  const size_t len_at = 8 + 8 + 8 + 1;  // fingerprint, utime, seq, command
  ASSERT_EQ(bytes[len_at + 3], 1);      // the encoder wrote 1 (just the NUL)
  bytes[len_at + 3] = 0;
  pcisim_lcm::session_command_t out;
  EXPECT_FALSE(decode_checked(bytes.data(), static_cast<int64_t>(bytes.size()), out));
}

}  // namespace
}  // namespace pcisim::protocol
