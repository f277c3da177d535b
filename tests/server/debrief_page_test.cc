// debrief.html (server/debrief/debrief_page.h) from a scripted session: the figures it states,
// the frame it embeds (a PNG of the frame's size), the tip's path drawn where the frame's own
// projection puts it (worked out here from the geometry, ray by ray), a reference run beside it.
// The page is left in the build folder for the browser test (tests/remote/debrief_page_browser.py).
#include "server/debrief/debrief_page.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <unistd.h>

#include <filesystem>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <regex>

#include "anatomy/vessel/vessel_tree.h"
#include "xray/geometry/c_arm.h"

namespace pcisim::server {
namespace {

constexpr int64_t kSecond = 1'000'000'000;
constexpr int kPixels = 64;

anatomy::VesselTree two_branches() {
  anatomy::VesselTree t;
  t.branches.resize(3);
  t.branches[0].name = "LM";
  t.branches[1].name = "LAD";
  t.branches[1].parent = 0;
  t.branches[2].name = "LCx";
  t.branches[2].parent = 0;
  return t;
}

xray::DetectorGeometry small_detector() {
  xray::CArmSpec arm;
  arm.width = arm.height = kPixels;
  arm.pixel_mm = 3.2;
  return xray::c_arm_geometry(arm, xray::CArmPose{});
}

// the tip's pixel by the ray from the source through it to the detector plane
Eigen::Vector2d pixel_of(const xray::DetectorGeometry& g, const Eigen::Vector3d& p_mm) {
  const Eigen::Vector3d n = g.u.cross(g.v).normalized();
  const double t = (g.center_mm - g.source_mm).dot(n) / (p_mm - g.source_mm).dot(n);
  const Eigen::Vector3d hit = g.source_mm + t * (p_mm - g.source_mm);
  return {(hit - g.center_mm).dot(g.u) / g.pixel_mm + 0.5 * (g.width - 1),
          (hit - g.center_mm).dot(g.v) / g.pixel_mm + 0.5 * (g.height - 1)};
}

// a 12 s session: fluoroscopy 1-11 s, a cine run, an injection, a C-arm move; the tip along x in
// the LM and LAD, then into the LCx; two force episodes
// `wrong`: the tip's state from which it is in the LCx (the reference goes there later);
// `heart_phase`: the frame's (NaN: a still background, every state joined)
DebriefFigures scripted_session(SessionMetrics& m, const std::string& target, int wrong = 200,
                                double heart_phase = std::nan("")) {
  DebriefParams p;
  p.target_branch = target;
  const anatomy::VesselTree tree = two_branches();
  m.begin_pipeline(p, tree, true, beam_geometry(750, 1100, kPixels * 3.2, kPixels * 3.2), kSecond, kPixels, kPixels);
  m.record_pedals(false, false, kSecond);
  m.record_pedals(true, false, 2 * kSecond);
  m.record_pedals(true, true, 5 * kSecond);
  m.record_pedals(true, false, 6 * kSecond);
  m.record_injection(8.0, 4 * kSecond);
  m.record_carm(40, 25, 7 * kSecond);
  m.record_pedals(false, false, 12 * kSecond);
  m.record_beam_time(9.0, false, 0, 0);
  m.record_beam_time(1.0, true, 0, 0);
  std::vector<uint16_t> frame(kPixels * kPixels);
  for (int i = 0; i < kPixels * kPixels; ++i) frame[i] = static_cast<uint16_t>(1000 + 30 * (i % kPixels));
  m.record_frame(frame.data(), kPixels, kPixels, small_detector(), heart_phase, 3, 4 * kSecond);
  for (int k = 0; k <= 300; ++k) {
    physics::WorldSnapshot s;
    s.step = k;
    s.time_s = k / 30.0;
    s.wire_nodes_m.assign(2, Eigen::Vector3d::Zero());
    s.tip_m = Eigen::Vector3d(-40e-3 + 0.25e-3 * k, 0.0, 10e-3 * std::sin(k / 40.0));
    s.tip_rest_m = s.tip_m;
    s.tip_branch = k < 120 ? 0 : k < wrong ? 1 : 2;
    s.heart_phase = std::fmod(k / 25.0, 1.0);  // 72 beats a minute at 30 states a second
    s.tip_force_n = (k > 50 && k < 60) || (k > 220 && k < 240) ? 0.3 : 0.02;
    m.record_wire(s, 0, 0, kSecond + static_cast<int64_t>(k * kSecond / 30));
  }
  return m.figures(13 * kSecond);
}

TEST(DebriefPage, ASessionsPageHoldsItsFiguresItsFrameAndThePathWhereTheFrameShowsIt) {
  SessionMetrics expert_metrics, metrics;
  const nlohmann::json reference = to_json(scripted_session(expert_metrics, "LAD", 280));
  const DebriefFigures f = scripted_session(metrics, "LAD");
  const std::string page = debrief_html(f, &reference, "debrief <test> & check");
  {
    // whole or not at all: the browser test may read it while another run of this test writes
    const std::string path = PCISIM_BINARY_DIR "/tests/debrief-page-sample.html";
    const std::string part = path + ".part" + std::to_string(::getpid());
    std::ofstream(part) << page;
    std::filesystem::rename(part, path);
  }

  EXPECT_NE(page.find("<title>debrief &lt;test&gt; &amp; check</title>"), std::string::npos) << "escaped";
  EXPECT_NE(page.find("<th>reference</th>"), std::string::npos);
  // the figures as the table states them (this session, then the reference: the same script)
  const auto row = [&](const std::string& label, const std::string& value, const std::string& reference_value) {
    return page.find("<td>" + label + "</td><td class=n>" + value + "</td><td class=n>" + reference_value + "</td>");
  };
  EXPECT_NE(row("Procedure time (s)", "12.0", "12.0"), std::string::npos);
  EXPECT_NE(row("Cine runs", "1", "1"), std::string::npos);
  EXPECT_NE(row("Contrast (ml)", "8.0", "8.0"), std::string::npos);
  EXPECT_NE(row("Force events above the risk force", "2", "2"), std::string::npos);
  // this session in the LCx from state 200, the reference from 280: 100 and 20 states
  EXPECT_NE(row("Time off the route to the target (s)", "3.3", "0.7"), std::string::npos);
  // the embedded frame: a PNG of the frame's size
  const std::smatch png = [&] {
    std::smatch m;
    std::regex_search(page, m, std::regex("data:image/png;base64,([A-Za-z0-9+/=]+)"));
    return m;
  }();
  ASSERT_EQ(png.size(), 2u);
  const std::string b64 = png[1].str();
  std::string bytes;
  int bits = 0;
  uint32_t acc = 0;
  for (char c : b64) {
    if (c == '=') break;
    const std::string table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    acc = acc << 6 | static_cast<uint32_t>(table.find(c));
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      bytes += static_cast<char>(acc >> bits & 0xff);
    }
  }
  ASSERT_GT(bytes.size(), 24u);
  EXPECT_EQ(bytes.substr(1, 3), "PNG");
  const auto be32 = [&](size_t at) {
    return static_cast<uint32_t>(static_cast<uint8_t>(bytes[at])) << 24 |
           static_cast<uint32_t>(static_cast<uint8_t>(bytes[at + 1])) << 16 |
           static_cast<uint32_t>(static_cast<uint8_t>(bytes[at + 2])) << 8 |
           static_cast<uint32_t>(static_cast<uint8_t>(bytes[at + 3]));
  };
  EXPECT_EQ(be32(16), static_cast<uint32_t>(kPixels)) << "width";
  EXPECT_EQ(be32(20), static_cast<uint32_t>(kPixels)) << "height";
  // the path on the route, green: its first point where the frame's projection puts the first tip
  std::smatch on;
  ASSERT_TRUE(std::regex_search(page, on, std::regex(R"re(class="pathon" points="([-0-9.]+),([-0-9.]+) )re")));
  const Eigen::Vector2d first = pixel_of(small_detector(), Eigen::Vector3d(-40.0, 0.0, 0.0));
  EXPECT_NEAR(std::stod(on[1].str()), first.x(), 0.06);
  EXPECT_NEAR(std::stod(on[2].str()), first.y(), 0.06);
  EXPECT_NE(page.find(R"(class="pathoff")"), std::string::npos) << "the LCx drawn red";
  EXPECT_NE(page.find(R"(class="pathref")"), std::string::npos) << "the reference's path";
  // the timeline's bars and marks, the force plot
  EXPECT_NE(page.find(R"(class="fluoro")"), std::string::npos);
  EXPECT_NE(page.find(R"(class="cine")"), std::string::npos);
  EXPECT_NE(page.find(R"(class="contrast")"), std::string::npos);
  EXPECT_NE(page.find("LAO 40 / CRA 25"), std::string::npos);
  EXPECT_NE(page.find(R"(class="forceline")"), std::string::npos);
  // nothing the page fetches: no script, no link, no source but the inline image
  for (const char* fetch : {"<script", "<link", "src=\"http", "href=\"http", "url("})
    EXPECT_EQ(page.find(fetch), std::string::npos) << fetch;
}

// with a beating heart the states at the frame's phase are joined (about one a beat), the rest faint
TEST(DebriefPage, OnABeatingHeartThePathJoinsTheStatesAtTheFramesPhase) {
  SessionMetrics m;
  const DebriefFigures f = scripted_session(m, "LAD", 200, 0.4);
  const std::string page = debrief_html(f, nullptr, "beating");
  // states k with frac(k / 25) within 0.05 of 0.4: k = 9, 10, 11 of each 25 (phase 0.36-0.44)
  int joined = 0;
  for (int k = 0; k <= 300; ++k) {
    const double d = std::abs(std::fmod(k / 25.0, 1.0) - 0.4);
    joined += std::min(d, 1.0 - d) <= 0.05;
  }
  int drawn = 0;
  for (const char* cls : {R"(class="pathon" points=")", R"(class="pathoff" points=")"}) {
    for (size_t at = page.find(cls); at != std::string::npos; at = page.find(cls, at + 1)) {
      const size_t end = page.find('"', at + std::string(cls).size());
      const std::string points = page.substr(at + std::string(cls).size(), end - at - std::string(cls).size());
      drawn += static_cast<int>(std::count(points.begin(), points.end(), ','));
    }
  }
  // each run after the first starts at the last run's end point: one more point a change of colour
  EXPECT_EQ(drawn, joined + 1);
  EXPECT_NE(page.find(R"(class="pathall")"), std::string::npos);
  EXPECT_NE(page.find("(0.40, within 0.05 of a beat)"), std::string::npos);
}

TEST(DebriefPage, WithoutAFrameOrForcesThePageSaysSo) {
  SessionMetrics m;
  m.begin_pipeline(DebriefParams{}, two_branches(), false, BeamGeometry{}, kSecond);
  const std::string page = debrief_html(m.figures(2 * kSecond), nullptr, "quiet");
  EXPECT_NE(page.find("No frame showed contrast"), std::string::npos);
  EXPECT_NE(page.find("Not computed: the chain-mail wire"), std::string::npos);
  EXPECT_EQ(page.find("<th>reference</th>"), std::string::npos);
}

}  // namespace
}  // namespace pcisim::server
