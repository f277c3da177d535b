// pcisim-server: the real-time PCI training server (see docs/ and DESIGN.md).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <spdlog/spdlog.h>

#include "json/json_reader.h"
#include "anatomy/case/case_folder.h"
#include "server/case_builder.h"
#include "server/debrief/debrief_page.h"
#include "server/scene/scene.h"
#include "server/session_runner.h"
#include "realtime/clock.h"
#include "realtime/stop_signal.h"

namespace {}  // namespace

int main(int argc, char** argv) {
  using namespace pcisim::server;
  CLI::App app{
      "pcisim-server: simulates a coronary guidewire for a PCI trainee. It reads the instrument "
      "over LCM, returns force at 1 kHz and publishes the wire's state. With no options it runs the "
      "built-in scene (a procedural coronary phantom) until Ctrl-C."};
  std::string scene_path, lcm_url = "udpm://239.255.76.67:7667?ttl=0", stats_path, write_scene_path;
  std::string log_level = "info";
  double duration_s = 0;
  app.add_option("--scene", scene_path, "scene file (JSON with comments); default: the built-in scene");
  app.add_option("--duration", duration_s, "seconds to run; 0 = until SIGINT/SIGTERM")->check(CLI::Range(0.0, 1e7));
  app.add_option("--lcm-url", lcm_url, "LCM URL of the control traffic (instrument, force, wire, status)")
      ->capture_default_str();
  std::string image_url = "udpm://239.255.76.67:7668?ttl=0";
  app.add_option("--lcm-image-url", image_url,
                 "LCM URL of the fluoroscopy frames (its own instance, so frames never delay the 1 kHz traffic)")
      ->capture_default_str();
  app.add_option("--stats-json", stats_path, "write loop statistics to this file at exit");
  std::string debrief_path, debrief_html_path, debrief_reference_path;
  app.add_option("--debrief-json", debrief_path,
                 "write the session's debrief at exit: fluoro and cine time, dose, contrast, C-arm poses, the tip's "
                 "path, time in a wrong branch, tip forces and a timeline (docs/debrief.md)");
  app.add_option("--debrief-html", debrief_html_path,
                 "write the session's debrief as one self-contained page at exit: the figures, a timeline, the tip's "
                 "path on an angiogram frame, the tip's force against time");
  app.add_option("--debrief-reference", debrief_reference_path,
                 "another session's debrief.json (an expert's) shown beside this one in --debrief-html")
      ->check(CLI::ExistingFile);
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error or off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}))
      ->capture_default_str();
  int cpu_latency_us = 0;
  app.add_option("--cpu-latency-us", cpu_latency_us,
                 "while running, ask the kernel (PM QoS) to keep CPU wake-ups within this many us, so idle cores "
                 "poll instead of halting and the 1 kHz loop wakes on time; -1 = leave the CPUs alone (saves power)")
      ->check(CLI::Range(-1, 100000))
      ->capture_default_str();
  app.add_option("--write-scene", write_scene_path, "write the built-in scene to this file and exit");
  std::string write_case_dir, case_dir;
  app.add_option("--write-case", write_case_dir,
                 "write the scene's anatomy (the built-in phantom, or --scene's) as a case folder and exit: "
                 "case.json, vessels.json, lumen.stl (LPS mm), ct.nrrd and slicer/*.mrk.json; for the soft-tissue "
                 "scene (scenes/kidney.json) its organ: organ.ply, fiducials.json and the CT (docs/anatomy.md)");
  app.add_option("--case", case_dir,
                 "run on this case folder instead of the scene's anatomy (the scene's effects are kept), for "
                 "every scene of the session: the first and each one loaded over LCM. It replaces a soft-tissue "
                 "scene's procedural organ too (the case must then have an organ; a coronary scene needs its "
                 "vessels)");
  CLI11_PARSE(app, argc, argv);
  // until the session runs, SIGINT/SIGTERM end the process at once (reading a case takes seconds)
  pcisim::realtime::install_stop_signals("pcisim-server");
  // an in-process control bus gets an in-process image bus unless told otherwise
  if (app.count("--lcm-image-url") == 0 && lcm_url.rfind("memq://", 0) == 0) image_url = "memq://";
  spdlog::set_level(spdlog::level::from_str(log_level));

  if (!write_scene_path.empty()) {
    std::ofstream out(write_scene_path);
    out << default_scene_text();
    if (!out.flush()) {
      std::cerr << "pcisim-server: cannot write " << write_scene_path << "\n";
      return 1;
    }
    std::cout << "wrote the built-in scene to " << write_scene_path << "\n";
    return 0;
  }

  Scene scene;
  try {
    scene = scene_path.empty() ? default_scene() : load_scene_file(scene_path);
  } catch (const std::exception& e) {
    std::cerr << "pcisim-server: bad scene: " << e.what() << "\n";
    return 2;
  }
  if (!case_dir.empty()) use_case_folder(scene, case_dir);

  if (!write_case_dir.empty()) {
    try {
      // the phantom with its CT at the resolution the scene's fluoroscopy projects, so running on
      // the written case gives the frames the seed gives; the soft-tissue scene's organ and its CT
      const pcisim::anatomy::Case c = !scene.case_dir.empty() ? read_case_folder(scene.case_dir)
                                      : scene.organ == "kidney"
                                          ? kidney_case(scene)
                                          : pcisim::anatomy::make_phantom_case(phantom_case_spec(scene));
      pcisim::anatomy::write_case(c, write_case_dir);
      std::cout << "wrote case '" << c.name << "' to " << write_case_dir << " (" << c.vessels.branches.size()
                << " branches, " << c.lumen.triangles.size() << " lumen triangles"
                << (c.organ ? ", organ '" + c.organ->name + "' with " + std::to_string(c.organ->fiducials_m.size()) +
                                  " fiducials"
                            : std::string())
                << (c.ct ? ", CT" : "") << ")\n";
      if (!pcisim::anatomy::case_overview_written())
        std::cout << "no overview.png: this pcisim-server was built without libpng\n";
    } catch (const std::exception& e) {
      std::cerr << "pcisim-server: cannot write the case: " << e.what() << "\n";
      return 1;
    }
    return 0;
  }

  lcm::LCM lcm(lcm_url);
  if (!lcm.good()) {
    std::cerr << "pcisim-server: cannot open LCM at " << lcm_url
              << " (for udpm, is there a multicast route? see docs/protocol.md)\n";
    return 3;
  }

  // the reference run is read before the session: a bad file is said now, not after it
  std::optional<nlohmann::json> reference;
  if (!debrief_reference_path.empty()) {
    std::ifstream in(debrief_reference_path);
    reference = nlohmann::json::parse(in, nullptr, false);
    if (reference->is_discarded() || !reference->is_object()) {
      std::cerr << "pcisim-server: --debrief-reference " << debrief_reference_path
                << ": not a debrief.json (a JSON object, as --debrief-json writes)\n";
      return 2;
    }
  }
  const std::string scene_name = scene.name;  // (the session may load others; the page names the first)
  SessionLimits limits;
  SessionMetrics metrics;
  // the debrief so far into its files (at the end, and when a session command asks: CMD_DEBRIEF);
  // false when one could not be written
  // whole or not at all: written beside, then renamed over the last (a gateway serving the page may
  // read it at any moment)
  const auto write_whole = [](const std::string& path, const std::string& text) {
    const std::string part = path + ".part";
    {
      std::ofstream out(part);
      out << text;
      if (!out.flush()) {
        spdlog::error("cannot write {}", part);
        return false;
      }
    }
    std::error_code ec;
    std::filesystem::rename(part, path, ec);
    if (ec) spdlog::error("cannot put {} in place: {}", path, ec.message());
    return !ec;
  };
  const auto write_debrief = [&](const DebriefFigures& figures) {
    bool ok = true;
    if (!debrief_path.empty()) ok = write_whole(debrief_path, to_json(figures).dump(2) + "\n") && ok;
    if (!debrief_html_path.empty())
      ok = write_whole(debrief_html_path,
                       debrief_html(figures, reference ? &*reference : nullptr, "pcisim debrief: " + scene_name)) &&
           ok;
    return ok;
  };
  // a scene loaded over LCM is built while the running one goes on, then takes over; --duration
  // counts the running time of the whole session (the first scene's build aside)
  SessionOptions options;
  options.duration_s = duration_s;
  options.cpu_latency_us = cpu_latency_us;
  options.image_url = image_url;
  options.case_dir = case_dir;  // for every scene of the session, not only the first
  if (!debrief_path.empty() || !debrief_html_path.empty())
    options.write_debrief = [&] {
      const DebriefFigures figures = metrics.figures(pcisim::realtime::monotonic_ns());
      if (write_debrief(figures))
        spdlog::info("session: the debrief so far written ({:.0f} s of the session)", figures.procedure_time_s);
    };
  try {
    const StatsReport stats =
        run_session(std::move(scene), lcm, options, pcisim::realtime::stop_flag(), limits, &metrics);
    std::cout << human_summary(stats) << "\n";
    if (!debrief_path.empty() || !debrief_html_path.empty()) {
      const DebriefFigures figures = metrics.figures(pcisim::realtime::monotonic_ns());
      std::cout << human_debrief(figures) << "\n";
      if (!write_debrief(figures)) {
        std::cerr << "pcisim-server: cannot write the debrief (" << debrief_path << " " << debrief_html_path << ")\n";
        return 1;
      }
      if (!debrief_path.empty()) std::cout << "  debrief " << debrief_path << "\n";
      if (!debrief_html_path.empty()) std::cout << "  page    " << debrief_html_path << "\n";
    }
    if (!stats_path.empty()) {
      std::ofstream out(stats_path);
      out << to_json(stats).dump(2) << "\n";
      if (!out.flush()) {
        std::cerr << "pcisim-server: cannot write stats to " << stats_path << "\n";
        return 1;
      }
      std::cout << "  stats   " << stats_path << "\n";
    }
  } catch (const std::exception& e) {
    std::cerr << "pcisim-server: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
