#pragma once
// The physics pipeline a scene asks for: it builds only the listed effects and steps them in a
// fixed order. Plain data in (instrument input), plain data out (snapshot, local force model).
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "anatomy/heart/heart_pose.h"
#include "anatomy/organ/organ.h"
#include "anatomy/vessel/vessel_tree.h"
#include "physics/instrument_input.h"
#include "physics/local_force_model.h"
#include "physics/world_snapshot.h"
#include "physics/world_spec.h"

namespace pcisim::anatomy {
struct VesselTree;
}  // namespace pcisim::anatomy

namespace pcisim::physics {

class BeatingHeart;
struct HeartFitReport;
class BloodChainMail;
class ChainMailWire;
class RodWire;
class VesselSkin;
class CoulombFriction;
class LumenQuery;
class WallContact;
namespace soft_tissue {
class TissueScene;
}  // namespace soft_tissue

// one cardiac cycle sampled at `bins` evenly spaced phases (b / bins, b = 0..bins-1), for the
// x-ray background that beats (xray/fluoro/beating_background.h): the heart's particles and the
// coronary centerline points, in the case's frame (metres). Column order: heart particles, then
// the vessel skin's centerline points (tree order)
struct BeatCycle {
  Eigen::Matrix3Xd rest_m;                 // every point at rest
  std::vector<Eigen::Matrix3Xd> at_bin_m;  // bins entries, same columns as rest_m
  int heart_points = 0;                    // the first heart_points columns are heart particles
};

struct EffectCost {
  std::string name;           // the scene's effect name
  double last_step_ms = 0.0;  // wall time of that effect in the last step
};

class World {
 public:
  // the scene's effects around the vessel tree of an anatomy::Case (the server builds the case
  // once per scene). Throws std::invalid_argument naming the bad field when it cannot be built.
  // `contact_geometry`, when given, replaces the SDF the spec would build (benchmarks and tests
  // share one field across worlds); it must describe the same anatomy.
  // `heart_pose` places the template heart under the tree (the case's; identity for the phantom);
  // `heart_rest_m`, when not empty, is the template's rest shape fitted to the patient (the case's
  // heart_vertices_m, template frame): used instead of the template's own vertices.
  // `organ` is the soft-tissue scene's (the case's organ; soft_tissue needs it, the tree is then
  // unused and may be empty).
  World(const WorldSpec& spec, const anatomy::VesselTree& tree,
        std::shared_ptr<const LumenQuery> contact_geometry = nullptr, const anatomy::HeartPose& heart_pose = {},
        const Eigen::Matrix3Xd& heart_rest_m = {}, const anatomy::Organ* organ = nullptr);
  // the same around the procedural phantom of spec.anatomy.seed (tests and benchmarks)
  explicit World(const WorldSpec& spec);
  World(const WorldSpec& spec, std::shared_ptr<const LumenQuery> contact_geometry);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  // one fixed step of spec.step_s; allocates nothing
  void step(const InstrumentInput& input);

  // copies the state out; `out` keeps its capacity so repeated calls do not allocate
  void write_snapshot(WorldSnapshot& out) const;
  LocalForceModel force_model() const;

  // effects in step order, with their cost in the last step
  std::span<const EffectCost> effect_costs() const;
  double time_s() const;

  // one settling cycle, then one sampled cycle, of a private copy of the heart (same params, mesh
  // and pose) and of the skin, at the scene's step; a bin's positions are interpolated linearly
  // between the two steps around its phase (bin 0: the cycle's last step and the first after the
  // wrap). Empty (rest_m.cols() == 0) without heart_beat or vessel_motion. Allocates; called once
  // at scene start. Throws std::invalid_argument when bins < 2.
  BeatCycle sample_beat_cycle(int bins) const;

  // instrument samples refused (NaN, Inf, absurd) since construction; the previous one was kept
  int64_t rejected_inputs() const;
  // insertion the wire is refusing now: commanded minus accepted feed, m (0 without guidewire)
  double refused_feed_m() const;

  // read-only views for tests and benchmarks; null when the effect is not listed. With
  // vessel_motion the chain-mail, its contact and the blood live in the vessels' rest frame and
  // the snapshot carries them into the world; the rod does too with guidewire.beat_coupling
  // "kinematic" or without vessel_contact, and with "contact" its nodes are in the world
  // (RodWire::wall_offset_m() maps them to the rest frame)
  const ChainMailWire* guidewire_state() const;  // guidewire.model chain_mail
  const RodWire* rod_state() const;              // guidewire.model rod (contact and friction inside it)
  const WallContact* contact_state() const;
  const CoulombFriction* friction_state() const;
  const LumenQuery* lumen() const;  // the contact geometry (null without vessel_contact)
  // the same, shared: a world built again around the same case and spec (a reset) takes it
  // instead of building its field again
  std::shared_ptr<const LumenQuery> shared_lumen() const;
  const anatomy::VesselTree& vessel_tree() const;  // at rest; empty without guidewire and vessel_motion
  const BeatingHeart* heart_state() const;
  // how the template heart was fitted under this scene's tree (vessel_motion; all zero otherwise)
  const HeartFitReport& heart_fit() const;
  const VesselSkin* vessel_skin() const;  // the tree now (vessel_motion)
  const BloodChainMail* blood_state() const;
  const soft_tissue::TissueScene* tissue_state() const;  // soft_tissue

 private:
  void write_tissue(WorldSnapshot& out) const;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pcisim::physics
