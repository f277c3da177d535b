#include "dataset/run/dataset_folder.h"

#include <fcntl.h>
#include <sys/file.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "dataset/sample/coco.h"

namespace pcisim::dataset {
namespace {

namespace fs = std::filesystem;

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// written whole under a temporary name, synced, then renamed over the target
void write_file_atomic(const fs::path& p, const std::string& text) {
  const fs::path tmp = p.string() + fmt::format(".tmp{}", getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  int saved = errno;
  bool ok = fd >= 0;
  if (ok) {
    size_t done = 0;
    while (ok && done < text.size()) {
      const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
      ok = n > 0;
      if (ok) done += static_cast<size_t>(n);
      saved = errno;
    }
    if (ok && ::fsync(fd) != 0) ok = false, saved = errno;
    if (::close(fd) != 0 && ok) ok = false, saved = errno;
  }
  std::error_code ec;
  if (ok) fs::rename(tmp, p, ec);
  if (!ok || ec) {
    fs::remove(tmp, ec);
    const std::string what =
        fmt::format("{}: cannot write: {}", p.string(), std::strerror(!ok ? (saved ? saved : EIO) : ec.value()));
    if (disk_full(what, saved)) throw DiskFull(what);
    throw WriteError(what);
  }
}

// the lines of a JSON-lines file; a torn last line (no newline: a kill mid-append) is ignored, and
// cut off the file when `cut_torn` (the shard's own process only: a merge reading beside a running
// shard must not cut a line being appended). A whole line that is not JSON is an error naming it
std::vector<nlohmann::json> read_lines(const fs::path& p, bool cut_torn) {
  std::vector<nlohmann::json> out;
  std::error_code ec;
  if (!fs::exists(p, ec)) return out;
  const std::string text = read_file(p);
  const size_t end = text.rfind('\n');
  const size_t whole = end == std::string::npos ? 0 : end + 1;
  if (cut_torn && whole < text.size()) fs::resize_file(p, whole);
  size_t from = 0;
  int line = 0;
  while (from < whole) {
    const size_t nl = text.find('\n', from);
    ++line;
    try {
      out.push_back(nlohmann::json::parse(text.substr(from, nl - from)));
    } catch (const nlohmann::json::exception&) {
      throw std::runtime_error(fmt::format("{}:{}: not a JSON line (the file is damaged)", p.string(), line));
    }
    from = nl + 1;
  }
  return out;
}

// N of a shard file "shard-I-of-N.jsonl", "failed-I-of-N.jsonl" or "shard-I-of-N.lock"; 0 otherwise
int shard_count_of(const std::string& name) {
  if (!name.starts_with("shard-") && !name.starts_with("failed-")) return 0;
  const size_t of = name.find("-of-"), dot = name.rfind('.');
  if (of == std::string::npos || dot == std::string::npos || dot < of + 5) return 0;
  const std::string ext = name.substr(dot);
  if (ext != ".jsonl" && ext != ".lock") return 0;
  int n = 0;
  for (size_t i = of + 4; i < dot; ++i) {
    if (name[i] < '0' || name[i] > '9' || n > 1'000'000) return 0;
    n = n * 10 + (name[i] - '0');
  }
  return n;
}

int64_t parse_sample_dir(const std::string& name, const std::string& prefix) {
  if (!name.starts_with(prefix) || name.size() != prefix.size() + 7) return -1;
  int64_t v = 0;
  for (size_t i = prefix.size(); i < name.size(); ++i) {
    if (name[i] < '0' || name[i] > '9') return -1;
    v = v * 10 + (name[i] - '0');
  }
  return v;
}

}  // namespace

bool disk_full(const std::string& what, int saved_errno) {
  return saved_errno == ENOSPC || saved_errno == EDQUOT || what.find(std::strerror(ENOSPC)) != std::string::npos ||
         what.find(std::strerror(EDQUOT)) != std::string::npos;
}

std::string Shard::name() const {
  return fmt::format("shard-{}-of-{}", index, count);
}

std::string sample_dir_name(int64_t sample) {
  return fmt::format("{:07d}", sample);
}

DatasetFolder::DatasetFolder(const std::string& out_dir, const std::string& spec_text, const Shard& shard)
    : root_(out_dir), shard_(shard) {
  std::error_code ec;
  fs::create_directories(fs::path(root_) / "samples", ec);
  if (!ec) fs::create_directories(fs::path(root_) / "shards", ec);
  if (ec) throw std::runtime_error(fmt::format("{}: cannot create the dataset folder: {}", root_, ec.message()));
  if (access(root_.c_str(), W_OK) != 0)
    throw std::runtime_error(fmt::format("{}: cannot write into the dataset folder: {}", root_, std::strerror(errno)));

  // one process per shard: a second one would remove the first's partial samples
  const fs::path lock = fs::path(root_) / "shards" / (shard.name() + ".lock");
  lock_fd_ = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock_fd_ < 0)
    throw WriteError(fmt::format("{}: cannot create the shard's lock: {}", lock.string(), std::strerror(errno)));
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    ::close(lock_fd_);
    lock_fd_ = -1;
    throw std::runtime_error(
        fmt::format("{}: {} is being made by another process (its lock is held)", root_, shard.name()));
  }

  // one spec per folder: a resume or another shard must be the same dataset
  const fs::path spec_path = fs::path(root_) / "spec.json";
  if (fs::exists(spec_path, ec)) {
    if (read_file(spec_path) != spec_text)
      throw std::runtime_error(fmt::format(
          "{}: this folder holds a dataset made from another spec; give a new --out (or the same spec to resume)",
          spec_path.string()));
  } else {
    write_file_atomic(spec_path, spec_text);
  }
  // one shard count per folder: sample i belongs to shard i % N
  for (const auto& e : fs::directory_iterator(fs::path(root_) / "shards")) {
    const std::string name = e.path().filename().string();
    const int count = shard_count_of(name);
    if (count > 0 && count != shard.count)
      throw std::runtime_error(fmt::format("{}: this folder is being made in {} shards, not {} (found {})", root_,
                                           count, shard.count, name));
  }

  // what this shard has done: listed and present. A listed folder that is gone is made again
  const fs::path manifest = fs::path(root_) / "shards" / (shard.name() + ".jsonl");
  bool dropped = false;
  std::string kept;
  for (const auto& line : read_lines(manifest, true)) {
    const int64_t s = line.value("sample", int64_t{-1});
    if (s >= 0 && shard.owns(s) && !done_.contains(s) &&
        fs::is_directory(fs::path(root_) / "samples" / sample_dir_name(s), ec)) {
      done_.insert(s);
      kept += line.dump() + "\n";
    } else {
      dropped = true;
    }
  }
  if (dropped) write_file_atomic(manifest, kept);
  for (const auto& line :
       read_lines(fs::path(root_) / "shards" / fmt::format("failed-{}-of-{}.jsonl", shard.index, shard.count), true))
    if (line.contains("sample")) failed_[line["sample"].get<int64_t>()] = line;

  // partial folders (a kill mid-sample) and whole ones never listed (a kill before the listing)
  for (const auto& e : fs::directory_iterator(fs::path(root_) / "samples")) {
    const std::string name = e.path().filename().string();
    int64_t s = parse_sample_dir(name, ".partial-");
    if (s < 0) {
      s = parse_sample_dir(name, "");
      if (s < 0 || done_.contains(s)) continue;
    }
    if (shard.owns(s)) fs::remove_all(e.path(), ec);
  }
}

DatasetFolder::~DatasetFolder() {
  if (lock_fd_ >= 0) ::close(lock_fd_);  // releases the flock
}

std::string DatasetFolder::begin_sample(int64_t sample) {
  const fs::path dir = fs::path(root_) / "samples" / (".partial-" + sample_dir_name(sample));
  std::error_code ec;
  fs::remove_all(dir, ec);
  fs::create_directory(dir, ec);
  if (ec) {
    const std::string what = fmt::format("{}: cannot create: {}", dir.string(), ec.message());
    if (disk_full(what, ec.value())) throw DiskFull(what);
    throw WriteError(what);
  }
  return dir.string();
}

void DatasetFolder::commit_sample(int64_t sample, const nlohmann::json& entry) {
  const fs::path partial = fs::path(root_) / "samples" / (".partial-" + sample_dir_name(sample));
  const fs::path whole = fs::path(root_) / "samples" / sample_dir_name(sample);
  nlohmann::json line = entry;
  line["sample"] = sample;
  line["dir"] = "samples/" + sample_dir_name(sample);
  line["digest"] = folder_digest(partial.string());
  std::error_code ec;
  fs::remove_all(whole, ec);
  fs::rename(partial, whole, ec);
  if (ec) throw WriteError(fmt::format("{}: cannot rename into place: {}", whole.string(), ec.message()));
  append_line((fs::path(root_) / "shards" / (shard_.name() + ".jsonl")).string(), line);
  done_.insert(sample);
}

void DatasetFolder::abandon_sample(int64_t sample) {
  std::error_code ec;
  fs::remove_all(fs::path(root_) / "samples" / (".partial-" + sample_dir_name(sample)), ec);
}

void DatasetFolder::record_failure(int64_t sample, uint64_t seed, const std::string& error) {
  nlohmann::json line = {{"sample", sample}, {"seed", seed}, {"error", error}};
  append_line((fs::path(root_) / "shards" / fmt::format("failed-{}-of-{}.jsonl", shard_.index, shard_.count)).string(),
              line);
  failed_[sample] = line;
}

// one write() of the whole line with O_APPEND, then fsync: the line is on disk before the next
// sample starts, and a kill leaves at most a torn last line (cut off on the next start)
void DatasetFolder::append_line(const std::string& file, const nlohmann::json& line) {
  const std::string text = line.dump() + "\n";
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  int saved = errno;
  bool ok = fd >= 0;
  if (ok) {
    const ssize_t n = ::write(fd, text.data(), text.size());
    saved = errno;
    ok = n == static_cast<ssize_t>(text.size());
    if (ok && ::fsync(fd) != 0) ok = false, saved = errno;
    ::close(fd);
  }
  if (!ok) {
    if (fd >= 0) {
      // a short write leaves a torn line: cut it off now so the list stays whole lines
      const std::string have = read_file(file);
      const size_t nl = have.rfind('\n');
      std::error_code ec;
      fs::resize_file(file, nl == std::string::npos ? 0 : nl + 1, ec);
    }
    const std::string what = fmt::format("{}: cannot append: {}", file, std::strerror(saved ? saved : EIO));
    if (disk_full(what, saved)) throw DiskFull(what);
    throw WriteError(what);
  }
}

std::string DatasetFolder::folder_digest(const std::string& dir) {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  uint64_t h = 0xcbf29ce484222325ull;
  auto mix = [&h](const std::string& bytes) {
    for (unsigned char ch : bytes) h = (h ^ ch) * 0x100000001b3ull;
  };
  for (const auto& f : files) {
    mix(f.filename().string());
    mix(std::string(1, '\0'));
    mix(read_file(f));
  }
  return fmt::format("{:016x}", h);
}

nlohmann::json merge_dataset(const std::string& out_dir, const DatasetSpec& spec) {
  const fs::path root(out_dir);
  std::map<int64_t, nlohmann::json> done, failed;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(root / "shards", ec)) {
    const std::string name = e.path().filename().string();
    if (!name.ends_with(".jsonl")) continue;
    const bool fail_list = name.starts_with("failed-");
    for (auto& line : read_lines(e.path(), false)) {
      const int64_t s = line.value("sample", int64_t{-1});
      auto& into = fail_list ? failed : done;
      if (into.contains(s))
        throw std::runtime_error(fmt::format("{}: sample {} is listed twice", (root / "shards").string(), s));
      into[s] = std::move(line);
    }
  }
  if (ec) throw std::runtime_error(fmt::format("{}: no shard lists: {}", (root / "shards").string(), ec.message()));
  std::vector<int64_t> missing;
  for (int64_t s = 0; s < spec.samples; ++s)
    if (!done.contains(s) && !failed.contains(s)) missing.push_back(s);
  if (!missing.empty()) {
    std::string first;
    for (size_t i = 0; i < missing.size() && i < 8; ++i) first += (i ? ", " : "") + std::to_string(missing[i]);
    throw std::runtime_error(
        fmt::format("{}: {} of {} samples are not made yet (sample {}{}): a shard has not finished", out_dir,
                    missing.size(), spec.samples, first, missing.size() > 8 ? ", ..." : ""));
  }

  // the manifest: every sample in order, the failures apart; a sample both made and failed
  // (failed once, made by a retry) counts as made
  nlohmann::json samples = nlohmann::json::array(), failures = nlohmann::json::array();
  int64_t frames = 0;
  for (auto& [s, line] : done) {
    frames += line.value("frames", 0);
    samples.push_back(line);
  }
  for (auto& [s, line] : failed)
    if (!done.contains(s)) failures.push_back(line);
  const nlohmann::json manifest = {{"name", spec.name},
                                   {"format", "pcisim-dataset"},
                                   {"version", 1},
                                   {"samples_asked", spec.samples},
                                   {"samples_made", samples.size()},
                                   {"frames", frames},
                                   {"samples", samples},
                                   {"failed", failures}};
  write_file_atomic(root / "manifest.json", manifest.dump(1) + "\n");

  // COCO: images and annotations numbered in sample order, frame order
  nlohmann::json images = nlohmann::json::array(), annotations = nlohmann::json::array();
  int64_t image_id = 0, annotation_id = 0;
  for (const auto& [s, line] : done) {
    const std::string dir = line.at("dir").get<std::string>();
    const nlohmann::json local = nlohmann::json::parse(read_file(root / dir / "coco.json"));
    std::map<int64_t, int64_t> ids;
    for (const auto& im : local.at("images")) {
      nlohmann::json g = im;
      g["id"] = ++image_id;
      ids[im.at("id").get<int64_t>()] = image_id;
      for (const char* key : {"file_name", "mask_file", "branches_file", "labels_file"})
        if (g.contains(key)) g[key] = dir + "/" + g[key].get<std::string>();
      g["sample"] = s;
      images.push_back(std::move(g));
    }
    for (const auto& an : local.at("annotations")) {
      nlohmann::json g = an;
      g["id"] = ++annotation_id;
      g["image_id"] = ids.at(an.at("image_id").get<int64_t>());
      annotations.push_back(std::move(g));
    }
  }
  const nlohmann::json coco = {
      {"info", {{"description", spec.name + " (pcisim synthetic fluoroscopy)"}, {"version", "1"}}},
      {"licenses", nlohmann::json::array()},
      {"categories", coco_categories(spec.labels.wire_keypoints)},
      {"images", images},
      {"annotations", annotations}};
  write_file_atomic(root / "coco.json", coco.dump() + "\n");
  return manifest;
}

}  // namespace pcisim::dataset
