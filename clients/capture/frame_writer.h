#pragma once
// Writes each fluoroscopy frame as a 16-bit PNG and each ultrasound frame as an 8-bit PNG, each
// with a JSON sidecar (geometry, time, frame number; for X-ray the ground-truth labels).
// Fluoroscopy goes to DIR/fluoro/, each cine run to DIR/cine_NNN/, ultrasound to DIR/ultrasound/;
// after a server restarts its pipeline (a scene reload: frame numbers start again at 0), under
// DIR/restart_NN/. Every file is written under a temporary name and renamed into place, so a full
// disk or a crash never leaves a half frame, and frames already written stay intact.
#include <cstdint>
#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "pcisim_lcm/us_frame_t.hpp"
#include "pcisim_lcm/xray_frame_t.hpp"

namespace pcisim::clients {

class FrameWriter {
 public:
  // creates DIR; throws std::runtime_error naming DIR when it cannot be created or written
  explicit FrameWriter(const std::string& out_dir);

  // throws std::runtime_error naming the file and the reason; returns the PNG's path
  std::string write(const pcisim_lcm::xray_frame_t& frame);
  std::string write(const pcisim_lcm::us_frame_t& frame);

  int64_t written() const { return written_xray_ + written_ultrasound_; }  // frames of both kinds
  int64_t written_xray() const { return written_xray_; }
  int64_t written_ultrasound() const { return written_ultrasound_; }
  static nlohmann::json sidecar(const pcisim_lcm::xray_frame_t& frame);
  static nlohmann::json sidecar(const pcisim_lcm::us_frame_t& frame);

 private:
  // writes LEAF/frame_SEQ.json and .png (write_png makes the PNG at the path it is given)
  std::string write_files(const std::string& leaf, int64_t seq, const nlohmann::json& sidecar,
                          const std::function<void(const std::string&)>& write_png);

  std::string out_dir_;
  int64_t written_xray_ = 0, written_ultrasound_ = 0;
  int restart_ = 0;  // server pipelines seen restarting their frame numbers
};

}  // namespace pcisim::clients
