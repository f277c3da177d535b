#pragma once
// A dataset's folder on disk (docs/dataset.md, "Layout"): what is done, what failed, and how a
// sample lands. A sample is written into samples/.partial-NNNNNNN/ and renamed into
// samples/NNNNNNN/ when whole; only then is its line appended (and synced) to its shard's
// manifest. A kill at any point leaves at most a partial folder or an unlisted whole one, which
// the next run of the shard removes and makes again: nothing is duplicated, nothing half-listed.
#include <cstdint>
#include <map>
#include <set>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "dataset/spec/dataset_spec.h"

namespace pcisim::dataset {

// the dataset folder cannot be written (read-only, gone, I/O error): not the sample's fault, so
// the run stops, saying so, rather than recording every later sample as failed
class WriteError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// the disk (or quota) is full: the run stops, saying so, and a later run resumes
class DiskFull : public WriteError {
 public:
  using WriteError::WriteError;
};

// true when `what` failed because the disk or quota is full (errno ENOSPC / EDQUOT, or their text)
bool disk_full(const std::string& what, int saved_errno);

struct Shard {
  int index = 0, count = 1;  // this process makes samples i with i % count == index
  bool owns(int64_t sample) const { return sample % count == index; }
  std::string name() const;  // "shard-I-of-N"
};

std::string sample_dir_name(int64_t sample);  // "0000123"

class DatasetFolder {
 public:
  // opens (creating) OUT for `shard`: takes the shard's lock (another process making the same
  // shard is refused), writes spec.json the first time, refuses a folder made
  // from another spec or with another shard count (naming it), reads the shard's manifest and
  // failure list (a torn last line from a kill is cut off), and removes this shard's partial and
  // unlisted sample folders. Throws std::runtime_error naming the path
  DatasetFolder(const std::string& out_dir, const std::string& spec_text, const Shard& shard);
  ~DatasetFolder();
  DatasetFolder(const DatasetFolder&) = delete;
  DatasetFolder& operator=(const DatasetFolder&) = delete;

  const std::set<int64_t>& done() const { return done_; }
  const std::map<int64_t, nlohmann::json>& failed() const { return failed_; }
  const std::string& root() const { return root_; }

  // the folder a sample is written into, created empty
  std::string begin_sample(int64_t sample);
  // the sample is whole: rename it into place, then list it (digest of its files) in the manifest
  void commit_sample(int64_t sample, const nlohmann::json& entry);
  // the partial folder removed (after a failure)
  void abandon_sample(int64_t sample);
  // recorded with its seed and error; the run goes on
  void record_failure(int64_t sample, uint64_t seed, const std::string& error);

  // FNV-1a 64 over the names and bytes of a folder's files in name order, as hex
  static std::string folder_digest(const std::string& dir);

 private:
  void append_line(const std::string& file, const nlohmann::json& line);
  std::string root_;
  Shard shard_;
  int lock_fd_ = -1;  // flock on shards/shard-I-of-N.lock while this folder is open
  std::set<int64_t> done_;
  std::map<int64_t, nlohmann::json> failed_;
};

// every shard's manifest and failure list merged into OUT/manifest.json and OUT/coco.json, in
// sample order (so any sharding gives the same files). Throws std::runtime_error when a sample
// is missing or listed twice, naming it; returns the merged manifest
nlohmann::json merge_dataset(const std::string& out_dir, const DatasetSpec& spec);

}  // namespace pcisim::dataset
