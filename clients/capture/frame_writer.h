#pragma once
// Writes each fluoroscopy frame as a 16-bit PNG with a JSON sidecar (geometry, time, frame
// number and ground-truth labels). Fluoroscopy goes to DIR/fluoro/, each cine run to
// DIR/cine_NNN/; after a server restarts its pipeline (a scene reload: frame numbers start again
// at 0), under DIR/restart_NN/. Every file is written under a temporary name and renamed into place, so a full
// disk or a crash never leaves a half frame, and frames already written stay intact.
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "pcisim_lcm/xray_frame_t.hpp"

namespace pcisim::clients {

class FrameWriter {
 public:
  // creates DIR; throws std::runtime_error naming DIR when it cannot be created or written
  explicit FrameWriter(const std::string& out_dir);

  // throws std::runtime_error naming the file and the reason; returns the PNG's path
  std::string write(const pcisim_lcm::xray_frame_t& frame);

  int64_t written() const { return written_; }
  static nlohmann::json sidecar(const pcisim_lcm::xray_frame_t& frame);

 private:
  std::string out_dir_;
  int64_t written_ = 0;
  int restart_ = 0;  // server pipelines seen restarting their frame numbers
};

}  // namespace pcisim::clients
