#pragma once
// Centerline JSON for a vessel tree (format in docs/anatomy.md). Built only with nlohmann-json.
#include <cstdint>
#include <string>

#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::anatomy {

// the largest vessels.json read: a tree of 10^5 centerline points is about 10 MB
inline constexpr int64_t kMaxVesselTreeFileBytes = int64_t{64} << 20;

// read throws std::runtime_error naming the file and the JSON path of the bad field; only a
// regular file of at most kMaxVesselTreeFileBytes is read (a FIFO or folder is refused unopened)
void write_vessel_tree_json(const VesselTree& tree, const std::string& path);
VesselTree read_vessel_tree_json(const std::string& path);

}  // namespace pcisim::anatomy
