#include "clients/bridge/serial_device.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <pty.h>
#include <unistd.h>

#include <cstring>
#include <string>

namespace pcisim::clients {
namespace {

TEST(EncoderLine, ParsesTheDocumentedFormatAndRejectsEverythingElse) {
  EncoderLine e;
  ASSERT_TRUE(parse_encoder_line("E 1200 -300 5", e));
  EXPECT_EQ(e.insertion_counts, 1200);
  EXPECT_EQ(e.rotation_counts, -300);
  EXPECT_EQ(e.buttons, 5);
  EXPECT_TRUE(parse_encoder_line("E 1 2 0\r", e)) << "CRLF line ends are fine";
  for (const char* bad :
       {"", "E", "E 1 2", "E 1 2 3 4", "X 1 2 3", "E1 2 3", "E 1.5 2 3", "E a b c", "E 1 2 -1",
        "E 99999999999999999999 2 3", "E -9223372036854775808 0 0", "E 0 2000000000000 0", "garbage \x01\x02"})
    EXPECT_FALSE(parse_encoder_line(bad, e)) << "'" << bad << "'";
}

// a pseudo-terminal stands in for the encoder box: we write the box's side
class SerialOverPty : public ::testing::Test {
 protected:
  int master = -1, slave = -1;
  char name[256] = {};
  void SetUp() override { ASSERT_EQ(openpty(&master, &slave, name, nullptr, nullptr), 0); }
  void TearDown() override {
    if (master >= 0) close(master);
    if (slave >= 0) close(slave);
  }
  void box_says(const std::string& text) {
    ASSERT_EQ(write(master, text.data(), text.size()), static_cast<ssize_t>(text.size()));
  }
  static void settle() { usleep(20000); }
};

TEST_F(SerialOverPty, CalibratesCountsSkipsGarbageAndDerivesRates) {
  SerialCalibration cal;
  cal.mm_per_count = 0.01;
  cal.rad_per_count = 0.002;
  cal.insertion_zero_counts = 100;
  SerialDevice dev(name, 115200, cal);
  InstrumentReading r;
  EXPECT_FALSE(dev.read(0.0, r)) << "no sample yet: fault";
  box_says("# encoder box v1\nE 1100 500 1\nthis is not a sample\nE 1 2\n");
  settle();
  ASSERT_TRUE(dev.read(0.010, r));
  EXPECT_DOUBLE_EQ(r.insertion_mm, 10.0);  // (1100 - 100) * 0.01
  EXPECT_DOUBLE_EQ(r.rotation_rad, 1.0);
  EXPECT_EQ(r.buttons, 1);
  EXPECT_EQ(dev.lines(), 1);
  EXPECT_EQ(dev.malformed(), 2);
  box_says("E 1200 500 0\n");
  settle();
  ASSERT_TRUE(dev.read(0.020, r));
  EXPECT_DOUBLE_EQ(r.insertion_mm, 11.0);
  EXPECT_NEAR(r.insertion_rate_mm_s, 100.0, 1e-9) << "1 mm in 10 ms";
  box_says("E 99999999 0 0\n");  // beyond the insertion limit
  settle();
  ASSERT_TRUE(dev.read(0.030, r));
  EXPECT_DOUBLE_EQ(r.insertion_mm, cal.max_insertion_mm);
  // a line longer than any sample, whose first bytes would parse, is malformed as a whole
  box_says("E 1300 500 0" + std::string(5000, ' ') + "junk\n");
  settle();
  ASSERT_TRUE(dev.read(0.035, r));
  EXPECT_EQ(dev.malformed(), 3);
  EXPECT_DOUBLE_EQ(r.insertion_mm, cal.max_insertion_mm) << "the cut line was not taken";
}

TEST(SerialDevice, BadCalibrationIsRefusedByName) {
  const std::pair<const char*, void (*)(SerialCalibration&)> cases[] = {
      {"mm_per_count", [](SerialCalibration& c) { c.mm_per_count = 0.0; }},
      {"rad_per_count", [](SerialCalibration& c) { c.rad_per_count = std::nan(""); }},
      {"insertion range", [](SerialCalibration& c) { c.max_insertion_mm = -5.0; }},
      {"silent_timeout_s", [](SerialCalibration& c) { c.silent_timeout_s = 0.0; }},
  };
  for (const auto& [what, spoil] : cases) {
    SerialCalibration c;
    spoil(c);
    try {
      SerialDevice dev("/dev/null", 115200, c);
      ADD_FAILURE() << what << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  }
}

TEST_F(SerialOverPty, SilenceAndUnpluggingAreFaults) {
  SerialDevice dev(name, 115200, SerialCalibration{});
  InstrumentReading r;
  box_says("E 0 0 0\n");
  settle();
  EXPECT_TRUE(dev.read(1.000, r));
  EXPECT_TRUE(dev.read(1.025, r)) << "25 ms of silence is within the timeout";
  EXPECT_FALSE(dev.read(1.035, r)) << "35 ms of silence is a fault";
  box_says("E 5 0 0\n");
  settle();
  EXPECT_TRUE(dev.read(1.040, r)) << "a new line clears the fault";
  close(master);  // the box is unplugged
  master = -1;
  settle();
  EXPECT_FALSE(dev.read(1.041, r));
  EXPECT_TRUE(dev.unplugged());
}

TEST(SerialDevice, MissingPortIsAClearError) {
  try {
    SerialDevice dev("/dev/pcisim-no-such-port", 115200, SerialCalibration{});
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/pcisim-no-such-port: cannot open the serial port"), std::string::npos);
  }
}

}  // namespace
}  // namespace pcisim::clients
