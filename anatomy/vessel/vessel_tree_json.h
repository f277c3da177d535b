#pragma once
// Centerline JSON for a vessel tree (format in docs/anatomy.md). Built only with nlohmann-json.
#include <string>

#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::anatomy {

// read throws std::runtime_error naming the file and the JSON path of the bad field
void write_vessel_tree_json(const VesselTree& tree, const std::string& path);
VesselTree read_vessel_tree_json(const std::string& path);

}  // namespace pcisim::anatomy
