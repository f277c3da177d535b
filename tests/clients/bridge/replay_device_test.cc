#include "clients/bridge/replay_device.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <string>
#include <lcm/lcm-cpp.hpp>

#include <filesystem>
#include <vector>

#include "pcisim_lcm/instrument_state_t.hpp"
#include "protocol/channels.h"

namespace pcisim::clients {
namespace {

// writes a log as lcm-logger would: 1 kHz instrument samples, plus noise on other channels
std::string write_log(int samples, bool with_bad = false) {
  // a name of this process's own, removed when it ends: CTest runs the tests of this file in
  // parallel processes, and one shared name let a test read a log another was rewriting
  // ("Invalid header after log data")
  static const struct OwnLog {
    std::string path =
        (std::filesystem::temp_directory_path() / ("pcisim_replay_test_" + std::to_string(::getpid()) + ".lcmlog"))
            .string();
    ~OwnLog() { std::filesystem::remove(path); }
  } own;
  const std::string& path = own.path;
  std::filesystem::remove(path);
  lcm::LogFile log(path, "w");
  EXPECT_TRUE(log.good());
  std::vector<uint8_t> buf;
  int64_t event = 0;
  auto write = [&](const std::string& channel, int64_t utime, const std::vector<uint8_t>& data) {
    lcm::LogEvent e;
    e.eventnum = event++;
    e.timestamp = utime;
    e.channel = channel;
    e.datalen = static_cast<int32_t>(data.size());
    e.data = const_cast<uint8_t*>(data.data());
    log.writeEvent(&e);
  };
  for (int i = 0; i < samples; ++i) {
    pcisim_lcm::instrument_state_t m{};
    m.seq = i;
    m.insertion_mm = 0.01 * i;
    m.status = (i >= 500 && i < 510) ? pcisim_lcm::instrument_state_t::STATUS_FAULT : 0;
    buf.resize(m.getEncodedSize());
    m.encode(buf.data(), 0, static_cast<int>(buf.size()));
    write(protocol::kInstrumentChannel, 5'000'000 + i * 1000, buf);
    write("PCISIM_OTHER", 5'000'000 + i * 1000 + 1, {1, 2, 3});
    if (with_bad && i == 10) write(protocol::kInstrumentChannel, 5'000'000 + i * 1000 + 2, {9, 9, 9});
  }
  return path;
}

TEST(ReplayDevice, PlaysTheRecordingAtItsOwnPace) {
  ReplayDevice dev(write_log(1000, true), 1.0, protocol::kInstrumentChannel);
  EXPECT_EQ(dev.samples(), 1000u);
  EXPECT_EQ(dev.skipped_bad(), 1);
  InstrumentReading r;
  ASSERT_TRUE(dev.read(0.0, r));
  EXPECT_DOUBLE_EQ(r.insertion_mm, 0.0);
  ASSERT_TRUE(dev.read(0.2505, r));
  EXPECT_DOUBLE_EQ(r.insertion_mm, 2.50) << "the sample recorded 250 ms after the first";
  EXPECT_FALSE(dev.read(0.5055, r)) << "recorded faults replay as faults";
  EXPECT_FALSE(dev.finished(0.9));
  EXPECT_TRUE(dev.finished(1.1));
}

TEST(ReplayDevice, FasterAndSteppedPlayback) {
  const std::string path = write_log(1000);
  ReplayDevice fast(path, 2.0, protocol::kInstrumentChannel);
  InstrumentReading r;
  ASSERT_TRUE(fast.read(0.2, r));
  EXPECT_DOUBLE_EQ(r.insertion_mm, 4.0) << "0.2 s at 2x is 400 ms of the recording";
  ReplayDevice stepped(path, 0.0, protocol::kInstrumentChannel);
  for (int i = 0; i < 3; ++i) stepped.read(123.0, r);  // the clock is ignored
  EXPECT_DOUBLE_EQ(r.insertion_mm, 0.02);
}

TEST(ReplayDevice, ALogWithoutInstrumentSamplesIsAClearError) {
  const std::string path = write_log(10);
  try {
    ReplayDevice dev(path, 1.0, "NOT_RECORDED");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), path + ": no instrument_state_t samples on channel NOT_RECORDED");
  }
  EXPECT_THROW(ReplayDevice("/nonexistent.lcmlog", 1.0, protocol::kInstrumentChannel), std::runtime_error);
}

}  // namespace
}  // namespace pcisim::clients
