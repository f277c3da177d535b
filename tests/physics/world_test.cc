// World: builds exactly the listed effects, checks their dependencies, steps without allocating.
#include "physics/world.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "anatomy/phantom/coronary_phantom.h"
#include "anatomy/vessel/vessel_tree.h"
#include "realtime/allocation_count.h"
#include "tests/common/shared_lumen.h"

namespace pcisim::physics {
namespace {

WorldSpec full_spec() {
  WorldSpec s;
  s.guidewire = GuidewireParams{};
  s.vessel_contact = VesselContactParams{};
  s.friction = FrictionParams{};
  s.blood_flow = BloodFlowParams{};
  return s;
}

std::vector<std::string> cost_names(const World& w) {
  std::vector<std::string> names;
  for (const auto& c : w.effect_costs()) names.push_back(c.name);
  return names;
}

std::string error_of(const WorldSpec& s) {
  try {
    World w(s);  // the world's own field: its errors name the spacing
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(World, EmptySceneBuildsNoEffect) {
  World w(WorldSpec{});
  EXPECT_TRUE(w.effect_costs().empty());
  w.step(InstrumentInput{});
  WorldSnapshot snap;
  w.write_snapshot(snap);
  EXPECT_TRUE(snap.wire_nodes_m.empty());
  EXPECT_EQ(w.force_model().valid_for_us, 0);
  EXPECT_NEAR(w.time_s(), WorldSpec{}.step_s, 1e-12);
}

TEST(World, BuildsOnlyListedEffectsInStepOrder) {
  WorldSpec s;
  s.guidewire = GuidewireParams{};
  EXPECT_EQ(cost_names(test::make_world(s)), (std::vector<std::string>{"guidewire"}));
  s.vessel_contact = VesselContactParams{};
  EXPECT_EQ(cost_names(test::make_world(s)), (std::vector<std::string>{"guidewire", "vessel_contact"}));
  s.blood_flow = BloodFlowParams{};
  EXPECT_EQ(cost_names(test::make_world(s)), (std::vector<std::string>{"guidewire", "blood_flow", "vessel_contact"}));
  EXPECT_EQ(cost_names(test::make_world(full_spec())),
            (std::vector<std::string>{"guidewire", "blood_flow", "vessel_contact", "friction"}));
}

TEST(World, UnlistedEffectsAreNeverConstructed) {
  WorldSpec s;
  s.guidewire = GuidewireParams{};
  World wire_only = test::make_world(s);
  EXPECT_NE(wire_only.guidewire_state(), nullptr);
  EXPECT_EQ(wire_only.contact_state(), nullptr);
  EXPECT_EQ(wire_only.lumen(), nullptr);  // no SDF built either
  EXPECT_EQ(wire_only.friction_state(), nullptr);
  World empty(WorldSpec{});
  EXPECT_EQ(empty.guidewire_state(), nullptr);
  EXPECT_TRUE(empty.vessel_tree().branches.empty());  // not even the anatomy
  World full(full_spec());  // builds its own field: the one test here that does (the rest share one)
  EXPECT_NE(full.contact_state(), nullptr);
  EXPECT_NE(full.lumen(), nullptr);
  EXPECT_NE(full.friction_state(), nullptr);
}

TEST(World, DependencyViolationsNameTheEffect) {
  WorldSpec s;
  s.vessel_contact = VesselContactParams{};
  EXPECT_EQ(error_of(s), "vessel_contact: needs guidewire");
  s = WorldSpec{};
  s.guidewire = GuidewireParams{};
  s.friction = FrictionParams{};
  EXPECT_EQ(error_of(s), "friction: needs vessel_contact");
  s = WorldSpec{};
  s.blood_flow = BloodFlowParams{};
  EXPECT_EQ(error_of(s), "blood_flow: needs guidewire");
}

TEST(World, BadFieldsAreNamed) {
  WorldSpec s = full_spec();
  s.guidewire->segment_count = 2;
  EXPECT_NE(error_of(s).find("guidewire.segment_count"), std::string::npos);
  s = full_spec();
  s.friction->body_kinetic = 0.5;  // above static
  EXPECT_NE(error_of(s).find("friction.body_kinetic"), std::string::npos);
  s = full_spec();
  s.step_s = std::nan("");
  EXPECT_NE(error_of(s).find("step_s"), std::string::npos);
  s = full_spec();
  s.vessel_contact->sdf_spacing_m = 1e-6;  // a grid no machine holds
  EXPECT_NE(error_of(s).find("vessel_contact.sdf_spacing_m"), std::string::npos);
}

TEST(World, StepAllocatesNothing) {
  World w = test::make_world(full_spec());
  WorldSnapshot snap;
  InstrumentInput in;
  w.step(in);
  w.write_snapshot(snap);  // sizes the snapshot once
  pcisim::realtime::AllocationCount count;
  for (int k = 0; k < 60; ++k) {
    in.insertion_m = 0.002 * k;
    in.rotation_rad = 0.1 * k;
    w.step(in);
    w.write_snapshot(snap);
    (void)w.force_model();
  }
  EXPECT_EQ(count.allocations(), 0);
}

TEST(World, WireComesOutOfTheCatheterAndIsTimed) {
  World w = test::make_world(full_spec());
  InstrumentInput in;
  for (int k = 0; k <= 30; ++k) {
    in.insertion_m = 0.001 * k;
    w.step(in);
  }
  WorldSnapshot snap;
  w.write_snapshot(snap);
  ASSERT_EQ(snap.wire_nodes_m.size(), static_cast<size_t>(GuidewireParams{}.segment_count + 1));
  const auto path = anatomy::guide_catheter_path(anatomy::make_coronary_phantom({1}));
  // 30 mm out of the exit, give or take the chain-mail's compression slack
  const double out = (snap.tip_m - path.back()).norm();
  EXPECT_GT(out, 0.020);
  EXPECT_LT(out, 0.0305);
  EXPECT_GE(snap.tip_branch, 0);
  const LocalForceModel m = w.force_model();
  EXPECT_GT(m.valid_for_us, 0);
  EXPECT_NEAR(m.x0_m, 0.030, 1e-12);
  // the chain-mail has no load response: no wall force on its nodes is published, and the hub's
  // force is the one the haptic loop's model starts from ([guidewire eq 19])
  ASSERT_EQ(snap.wire_contact_force_n.size(), snap.wire_nodes_m.size());
  for (const auto& f : snap.wire_contact_force_n) EXPECT_EQ(f.norm(), 0.0);
  EXPECT_EQ(snap.tip_force_n, 0.0);
  EXPECT_EQ(snap.hub_force_n, m.f0_n);
  EXPECT_EQ(snap.hub_torque_nm, m.t0_nm);
  for (const auto& c : w.effect_costs()) EXPECT_GE(c.last_step_ms, 0.0) << c.name;
  EXPECT_GT(w.effect_costs()[0].last_step_ms, 0.0);
}

TEST(World, NonFiniteInputIsRejectedAndCounted) {
  World w = test::make_world(full_spec());
  InstrumentInput in;
  in.insertion_m = 0.01;
  w.step(in);
  WorldSnapshot before, after;
  w.write_snapshot(before);
  in.insertion_m = std::nan("");
  w.step(in);
  in.insertion_m = 0.01;
  in.rotation_rad = INFINITY;
  w.step(in);
  EXPECT_EQ(w.rejected_inputs(), 2);
  w.write_snapshot(after);
  EXPECT_DOUBLE_EQ(after.insertion_m, 0.01);
  EXPECT_DOUBLE_EQ(after.rotation_rad, 0.0);
  for (const auto& p : after.wire_nodes_m) EXPECT_TRUE(p.allFinite());
}

}  // namespace
}  // namespace pcisim::physics
