// pcisim-lcm-flood: a hostile peer on the LCM buses, for scripts/soak. Publishes, at a given
// rate, messages of every pcisim type on every pcisim channel: each malformed shape of
// fuzz/lcm_mutants.h (truncations, trailing bytes, wrong fingerprints, bad lengths and counts),
// random bytes, and well-formed messages carrying NaN, infinity or extreme values. Its
// well-formed messages carry utime <= 0, so a watcher can tell them from the server's.
#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <csignal>
#include <fstream>
#include <iostream>
#include <limits>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <thread>

#include "fuzz/lcm_mutants.h"
#include "protocol/channels.h"

namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) {
  g_stop = true;
}

using pcisim::fuzz::Bytes;

// well-formed encodings with values no sender should send
std::vector<Bytes> poisoned_messages() {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  std::vector<Bytes> out;
  for (double v : {nan, inf, -inf, 1e308, -1e308}) {
    pcisim_lcm::instrument_state_t i{};
    i.utime = -1;
    i.insertion_mm = v;
    i.rotation_rate_rad_s = v;
    i.buttons = -1;
    out.push_back(pcisim::fuzz::encode(i));
    pcisim_lcm::force_command_t f{};
    f.utime = -1;
    f.axial_force_n = v;
    out.push_back(pcisim::fuzz::encode(f));
    pcisim_lcm::session_command_t s{};
    s.utime = -1;
    s.command = pcisim_lcm::session_command_t::CMD_CARM;
    s.primary_angle_deg = v;
    s.contrast_ml = v;
    out.push_back(pcisim::fuzz::encode(s));
    pcisim_lcm::wire_state_t w{};
    w.utime = -1;
    w.num_nodes = 1;
    w.node_mm = {{static_cast<float>(v), 0, 0}};
    w.contact = {1};
    w.contact_force_n = {{0, 0, 0}};
    out.push_back(pcisim::fuzz::encode(w));
    pcisim_lcm::us_frame_t u{};
    u.utime = -1;
    u.width = u.height = 1;
    u.pixel_format = pcisim_lcm::us_frame_t::FORMAT_GRAY8;
    u.depth_mm = v;
    u.width_mm = 40;
    u.frequency_mhz = 5;
    u.beam[2] = 1;
    u.lateral[0] = v;
    u.num_bytes = 1;
    u.data = {0};
    out.push_back(pcisim::fuzz::encode(u));
  }
  // an unknown command and a scene path that is no file
  pcisim_lcm::session_command_t s{};
  s.utime = -1;
  s.command = 99;
  out.push_back(pcisim::fuzz::encode(s));
  s.command = pcisim_lcm::session_command_t::CMD_LOAD_SCENE;
  s.scene_path = "/dev/zero";
  out.push_back(pcisim::fuzz::encode(s));
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "pcisim-lcm-flood: publishes malformed and poisoned pcisim LCM messages of every type on every "
      "channel, for soak and fault runs (scripts/soak). Never point it at a session a trainee is using."};
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0", image_url = "udpm://239.255.76.67:7668?ttl=0";
  std::string json_path;
  double seconds = 10, rate_hz = 200;
  uint32_t seed = 1;
  app.add_option("--lcm-url", lcm_url, "control LCM URL")->capture_default_str();
  app.add_option("--image-lcm-url", image_url, "image LCM URL (the X-ray and ultrasound frames' channels)")
      ->capture_default_str();
  app.add_option("--seconds", seconds, "how long to flood")->check(CLI::Range(0.1, 1e6))->capture_default_str();
  app.add_option("--rate-hz", rate_hz, "messages per second, over all channels")
      ->check(CLI::Range(1.0, 1e5))
      ->capture_default_str();
  app.add_option("--seed", seed, "random seed")->capture_default_str();
  app.add_option("--json", json_path, "write what was sent (per channel and kind) to this file");
  CLI11_PARSE(app, argc, argv);

  lcm::LCM control(lcm_url), images(image_url);
  if (!control.good() || !images.good()) {
    std::cerr << "pcisim-lcm-flood: cannot open LCM (" << lcm_url << ", " << image_url << ")\n";
    return 3;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);

  // every type's malformed shapes, to go on every channel
  using namespace pcisim::fuzz;
  const std::vector<MessageCase> cases = {instrument_case(), force_case(), session_case(),
                                          status_case(),     wire_case(),  xray_case(),
                                          us_frame_case(),   probe_case(), metrics_case()};
  const std::vector<Bytes> poisoned = poisoned_messages();
  const std::vector<const char*> channels = {
      pcisim::protocol::kInstrumentChannel, pcisim::protocol::kForceChannel,      pcisim::protocol::kWireChannel,
      pcisim::protocol::kStatusChannel,     pcisim::protocol::kSessionChannel,    pcisim::protocol::kXrayChannel,
      pcisim::protocol::kProbeChannel,      pcisim::protocol::kUltrasoundChannel, pcisim::protocol::kMetricsChannel};
  std::mt19937 rng(seed);
  std::map<std::string, std::map<std::string, int64_t>> sent;  // channel -> kind -> count
  const auto period = std::chrono::duration<double>(1.0 / rate_hz);
  const auto start = std::chrono::steady_clock::now();
  auto next = start;
  Bytes random_bytes;
  while (!g_stop && std::chrono::steady_clock::now() - start < std::chrono::duration<double>(seconds)) {
    const char* channel = channels[rng() % channels.size()];
    const Bytes* msg = nullptr;
    std::string kind;
    switch (rng() % 3) {
      case 0: {  // a malformed shape of some type
        const MessageCase& c = cases[rng() % cases.size()];
        const Mutant& m = c.mutants[rng() % c.mutants.size()];
        msg = &m.bytes;
        kind = c.type + " malformed";
        break;
      }
      case 1:  // poisoned values in a well-formed message
        msg = &poisoned[rng() % poisoned.size()];
        kind = "poisoned";
        break;
      default:  // bytes from nowhere, up to 4 KB
        random_bytes.resize(rng() % 4096);
        for (auto& b : random_bytes) b = static_cast<uint8_t>(rng());
        msg = &random_bytes;
        kind = "random bytes";
    }
    // the frames' channels are on the image instance, as the server sends them
    const bool image_channel =
        channel == pcisim::protocol::kXrayChannel || channel == pcisim::protocol::kUltrasoundChannel;
    lcm::LCM& bus = image_channel ? images : control;
    bus.publish(channel, msg->data(), static_cast<unsigned>(msg->size()));
    ++sent[channel][kind];
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    std::this_thread::sleep_until(next);
  }

  nlohmann::json j = nlohmann::json::object();
  int64_t total = 0;
  for (const auto& [channel, kinds] : sent)
    for (const auto& [kind, n] : kinds) {
      j["channels"][channel][kind] = n;
      total += n;
    }
  j["total"] = total;
  j["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!json_path.empty()) {
    std::ofstream out(json_path);
    out << j.dump(2) << "\n";
  }
  std::cout << "pcisim-lcm-flood: " << total << " messages sent\n";
  return 0;
}
