#include "dataset/run/sample_writer.h"

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <fstream>

#include "dataset/run/dataset_folder.h"
#include "png/png_gray.h"

namespace pcisim::dataset {

void write_text_file(const std::string& path, const std::string& text) {
  errno = 0;
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();
  if (!out) {
    const int saved = errno;
    const std::string what = fmt::format("{}: cannot write: {}", path, std::strerror(saved ? saved : EIO));
    if (disk_full(what, saved)) throw DiskFull(what);
    throw WriteError(what);
  }
}

SampleWriter::SampleWriter(std::string dir) : dir_(std::move(dir)) {}

void SampleWriter::frame(const FrameOutput& out) {
  const std::string stem = fmt::format("{:04d}", out.frame);
  const auto& im = *out.image;
  // the PNG writer names the file and errno's text: a full disk is told apart by that text
  auto png = [&](const std::string& name, auto&& write) {
    try {
      write(dir_ + "/" + name);
    } catch (const std::runtime_error& e) {
      if (disk_full(e.what(), errno)) throw DiskFull(e.what());
      throw WriteError(e.what());
    }
  };
  png("frame_" + stem + ".png",
      [&](const std::string& p) { png::write_png_gray16(p, im.width, im.height, im.pixels.data()); });
  png("mask_" + stem + ".png",
      [&](const std::string& p) { png::write_png_gray8(p, im.width, im.height, out.vessels->mask().data(), true); });
  png("branches_" + stem + ".png", [&](const std::string& p) {
    png::write_png_gray8(p, im.width, im.height, out.vessels->branch_ids().data(), true);
  });
  write_text_file(dir_ + "/frame_" + stem + ".json", out.labels->dump() + "\n");

  images_.push_back({{"id", out.frame + 1},
                     {"file_name", "frame_" + stem + ".png"},
                     {"mask_file", "mask_" + stem + ".png"},
                     {"branches_file", "branches_" + stem + ".png"},
                     {"labels_file", "frame_" + stem + ".json"},
                     {"width", im.width},
                     {"height", im.height},
                     {"frame", out.frame}});
  for (const auto& a : *out.coco) {
    nlohmann::json an = a;
    an["id"] = ++annotation_id_;
    an["image_id"] = out.frame + 1;
    annotations_.push_back(std::move(an));
  }
}

void SampleWriter::finish(const nlohmann::json& sample) {
  write_text_file(dir_ + "/sample.json", sample.dump(1) + "\n");
  write_text_file(dir_ + "/coco.json",
                  nlohmann::json{{"images", images_}, {"annotations", annotations_}}.dump() + "\n");
}

}  // namespace pcisim::dataset
