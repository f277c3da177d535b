#pragma once
// What a scene sets for effect `vessel_motion`: how the coronary tree is tied to the beating
// heart's epicardium.
namespace pcisim::physics {

struct VesselMotionParams {
  // tree points within this distance of the epicardium ride it fully (the coronaries lie on it
  // with their radius, ~1-2 mm, plus fat)
  double attach_distance_m = 0.006;
  // beyond it the ride fades linearly to nothing over this distance: the aortic root, where the
  // guide catheter sits, stays put
  double fade_distance_m = 0.010;
  // radius of the blend that carries points between centerline samples (the wire inside the
  // lumen): samples within it weigh in by inverse squared distance
  double blend_radius_m = 0.004;
};

}  // namespace pcisim::physics
