#pragma once
// Writes one sample's files into its (partial) folder as the runner hands over each frame:
// frame_FFFF.png (16-bit, the display frame), mask_FFFF.png (8-bit, 255 = contrast-filled vessel),
// branches_FFFF.png (8-bit, 1 + the branch's tree index), frame_FFFF.json (the labels), and at
// the end sample.json (what the sample was) and coco.json (its images and annotations, numbered
// within the sample). Throws DiskFull when the disk is full, WriteError otherwise.
#include <string>

#include <nlohmann/json.hpp>

#include "dataset/sample/sample_runner.h"

namespace pcisim::dataset {

class SampleWriter final : public FrameSink {
 public:
  explicit SampleWriter(std::string dir);
  void frame(const FrameOutput& out) override;
  void finish(const nlohmann::json& sample);

 private:
  std::string dir_;
  nlohmann::json images_ = nlohmann::json::array(), annotations_ = nlohmann::json::array();
  int64_t annotation_id_ = 0;
};

// text to a file, or DiskFull / WriteError naming it
void write_text_file(const std::string& path, const std::string& text);

}  // namespace pcisim::dataset
