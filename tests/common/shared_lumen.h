#pragma once
// The contact field of a vessel tree built once and shared, because building it is the suite's
// most repeated cost (0.7-1.6 s at 0.2 mm in Release, ~25x that under ASan). Shared twice:
//  - in memory, by every World of one test process;
//  - on disk, by the test processes of one test executable (CTest runs each test alone): a
//    fixture file (tests/common/fixture_file.h) keyed by the tree's every number and the spacing;
//    a file that does not read back whole is not trusted (the field is built again).
// The field is exactly what physics::SdfLumen(tree, spacing_m) builds: the same bytes.
#include <memory>

#include "anatomy/vessel/vessel_tree.h"
#include "physics/guidewire/lumen_query.h"
#include "physics/sdf/signed_distance_field.h"
#include "physics/world.h"
#include "physics/world_spec.h"

namespace pcisim::physics::test {

std::shared_ptr<const LumenQuery> shared_lumen(const anatomy::VesselTree& tree, double spacing_m);

// the field a World(spec) would build: the procedural phantom of spec.anatomy.seed at
// spec.vessel_contact's spacing (null without vessel_contact)
std::shared_ptr<const LumenQuery> shared_lumen(const WorldSpec& spec);

// World(spec) with its contact field from shared_lumen(spec): the same world, built without
// rebuilding the field (the caller names it as a prvalue: World w = make_world(spec))
inline World make_world(const WorldSpec& spec) {
  return World(spec, shared_lumen(spec));
}

// the field of (tree, spacing_m) as stored in this build's fixture file, read back from disk (its
// test compares it with the field the world builds); false when no process has stored it
bool read_stored_field(const anatomy::VesselTree& tree, double spacing_m, SignedDistanceField* out);

// how many fields this process built, read from disk, or took from memory (tests of the cache)
struct SharedLumenCounts {
  int built = 0, read = 0, reused = 0;
};
SharedLumenCounts shared_lumen_counts();

}  // namespace pcisim::physics::test
