// pcisim-capture: headless image capture. Writes every X-ray frame the server streams as a 16-bit
// PNG and every ultrasound frame as an 8-bit PNG, each with a JSON sidecar (geometry, time; for
// X-ray the ground-truth labels); see docs/capture.md.
#include <CLI/CLI.hpp>
#include <csignal>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>
#include <thread>

#include "clients/capture/capture_sink.h"
#include "clients/capture/frame_writer.h"
#include "protocol/channels.h"
#include "realtime/clock.h"

namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) {
  g_stop = true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "pcisim-capture: records the images pcisim-server streams on its image LCM instance. X-ray "
      "(PCISIM_XRAY): one 16-bit PNG and one JSON sidecar per frame (geometry, time, the wire's 3D nodes and "
      "2D polyline, branches holding contrast); fluoroscopy goes to OUT/fluoro/, each cine run to OUT/cine_NNN/. "
      "Ultrasound (PCISIM_ULTRASOUND, the soft-tissue scene): one 8-bit PNG and one JSON sidecar per frame "
      "(probe geometry, pixel -> world, gain, frequency, the probe's force) in OUT/ultrasound/. After a scene "
      "reload (frame numbers from 0 again) frames go under OUT/restart_NN/."};
  std::string out_dir, image_url = "udpm://239.255.76.67:7668?ttl=0&recv_buf_size=4194304",
                       lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  int64_t max_frames = 0;
  double duration_s = 0;
  bool only_while_pedal = false;
  app.add_option("--out", out_dir, "output folder (created)")->required();
  app.add_option("--lcm-image-url", image_url, "LCM URL of the frames (X-ray and ultrasound)")->capture_default_str();
  app.add_option("--lcm-url", lcm_url, "LCM URL of the control traffic (for --only-while-pedal)")
      ->capture_default_str();
  app.add_option("--frames", max_frames, "stop after this many frames (X-ray and ultrasound together); 0 = no limit")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--duration", duration_s, "seconds to run; 0 = until SIGINT/SIGTERM")->check(CLI::Range(0.0, 1e7));
  app.add_flag("--only-while-pedal", only_while_pedal,
               "keep X-ray frames only while the instrument's fluoroscopy or cine pedal is down (not console-triggered "
               "ones); ultrasound frames, which no pedal starts, are always kept");
  CLI11_PARSE(app, argc, argv);

  std::unique_ptr<pcisim::clients::FrameWriter> writer;
  try {
    writer = std::make_unique<pcisim::clients::FrameWriter>(out_dir);
  } catch (const std::exception& e) {
    std::cerr << "pcisim-capture: " << e.what() << "\n";
    return 2;
  }
  lcm::LCM images(image_url);
  if (!images.good()) {
    std::cerr << "pcisim-capture: cannot open LCM at " << image_url << "\n";
    return 3;
  }
  pcisim::clients::CaptureSink capture(*writer, max_frames, only_while_pedal);
  images.subscribe(pcisim::protocol::kXrayChannel, &pcisim::clients::CaptureSink::on_frame, &capture);
  images.subscribe(pcisim::protocol::kUltrasoundChannel, &pcisim::clients::CaptureSink::on_ultrasound, &capture);
  std::unique_ptr<lcm::LCM> control;
  std::thread control_rx;
  if (only_while_pedal) {
    control = std::make_unique<lcm::LCM>(lcm_url);
    control->subscribe(pcisim::protocol::kInstrumentChannel, &pcisim::clients::CaptureSink::on_instrument, &capture);
    control_rx = std::thread([&] {
      while (!g_stop) control->handleTimeout(20);
    });
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  spdlog::info("capture: frames from {} into {}", image_url, out_dir);
  const int64_t end_ns =
      duration_s > 0 ? pcisim::realtime::monotonic_ns() + static_cast<int64_t>(duration_s * 1e9) : INT64_MAX;
  while (!g_stop && pcisim::realtime::monotonic_ns() < end_ns && !capture.done()) images.handleTimeout(50);
  g_stop = true;
  if (control_rx.joinable()) control_rx.join();
  // scripts/soak_report.py reads "N frames written ... M undecodable" from this line
  spdlog::info(
      "capture: {} frames written to {} ({} X-ray, {} ultrasound), {} undecodable ({} of them ultrasound), {} X-ray "
      "skipped (pedal up), {} bad instrument samples",
      writer->written(), out_dir, writer->written_xray(), writer->written_ultrasound(),
      capture.bad() + capture.bad_ultrasound(), capture.bad_ultrasound(), capture.skipped(), capture.bad_instrument());
  if (!capture.error().empty()) {
    std::cerr << "pcisim-capture: stopped: " << capture.error() << " (the " << writer->written()
              << " frames written before are intact)\n";
    return 1;
  }
  return 0;
}
