#pragma once
// Synthetic coronary CT angiograms with exact truth, to test and benchmark the CTA pipeline
// (segmentation, centerlines, radii). One seed draws the geometry (the coronary phantom posed,
// scaled, made more tortuous, with branches dropped and radii scaled), the contrast timing, a
// stenosis, calcified plaques and a cardiac vein beside an artery; the thorax painter supplies
// the background; the coronary lumens are painted with partial volume; then scanner blur and
// noise. The truth (centerlines and radii, the stenosis included) is in the CT's physical frame.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "anatomy/case/case.h"
#include "anatomy/vessel/lesion.h"
#include "anatomy/vessel/vessel_tree.h"
#include "anatomy/volume/volume.h"

namespace pcisim::anatomy {

// what make_phantom_cta builds, bounded so that no spec allocates without bound (pcisim-model
// refuses the same, naming its options; docs/modeling.md states them):
// voxels: the generator peaks at ~6 bytes a voxel (float HU beside the int16 CT): 2^28 is ~1.7 GB
inline constexpr int64_t kMaxPhantomCtaVoxels = int64_t{1} << 28;
inline constexpr int64_t kMaxPhantomCtaDim = 4096;  // voxels along one axis
// a voxel: a clinical CT's is 0.3..5 mm; down to 0.1 (the blur's kernel is 6 sigma / voxel wide)
// and up to 20 (coarse grids for geometry-only runs)
inline constexpr double kMinPhantomCtaVoxelMm = 0.1, kMaxPhantomCtaVoxelMm = 20.0;
// the field of view along any axis: a scanner's bore is ~700 mm; the painters cover what it holds
inline constexpr double kMaxPhantomCtaExtentMm = 1000.0;
inline constexpr int kMaxPhantomCtaThreads = 256;
// the scanner's point spread: ~0.3..1 mm
inline constexpr double kMaxPhantomCtaBlurMm = 5.0;

struct PhantomCtaSpec {
  uint32_t seed = 1;  // everything below that is drawn, is drawn from this
  std::array<int64_t, 3> dims{512, 512, 250};
  Eigen::Vector3d spacing_mm{0.4, 0.4, 0.6};  // per index axis; clinical 0.3..0.8 mm
  // any signed permutation matrix (diag(1, 1, -1), an axis swap): the voxels are re-ordered
  // exactly, so the same physical point holds the same HU whatever the direction
  Eigen::Matrix3d direction = Eigen::Matrix3d::Identity();
  double noise_sigma_hu = 25;   // Gaussian, added after the blur; 15..40 typical
  double blur_sigma_mm = 0.45;  // scanner point spread (Gaussian); 0: none
  // the heart at a seeded offset in scanner coordinates (as in real scans); false: the heart
  // centre at the origin (patient frame of the coronary phantom, mm)
  bool scanner_frame = true;
  // < 0: drawn (50..80 % diameter reduction); else this diameter reduction (0.95: 95 %)
  double stenosis_fraction = -1;
  // false: a CTA with no coronary arteries (no lumens, fat sleeves or plaques; the aorta, the
  // chambers, the vein and everything else as with them). The truth still holds the tree.
  bool with_coronaries = true;
  int threads = 0;  // 0: std::thread::hardware_concurrency(); the volume does not depend on it
  // a member of the varied family (family_phantom_cta_spec below) rather than one of the classic
  // phantoms (with_coronaries false: no stent and no blooms either): the seed also draws the heart's shape, the right
  // heart enhanced or not, an open or a closed aortic valve, the right ventricle's free wall, the left atrial appendage
  // beside the LCx, veins crossing arteries, calcium with blooming, a stent, small side branches, the LAD-LCx angle and
  // a tortuous trunk (ranges and sources in phantom_cta.cc). false: the classic phantoms, as they were drawn before the
  // family existed
  bool family = false;
  // with family: the plaques' blooming halos (false: the same phantom without them, to see it)
  bool calcium_blooming = true;
  // with family: draws pinned to a value (a failure class's hard end, for a test); NaN or -1: drawn
  // from the seed. Every draw is still made, so what is not pinned is as without the pins.
  struct FamilyPins {
    double contrast_hu_proximal = kUnpinned;  // the aorta and the coronaries' ostia, 300..550
    double fade_hu_per_mm = kUnpinned;        // the coronaries' distal fall-off, 0.5..3
    double myocardium_hu = kUnpinned;         // 40..150
    double rv_hu = kUnpinned;                 // the right ventricle's blood, 40..400
    double rv_wall_mm = kUnpinned;            // the right ventricle's free wall, 2..5
    double vein_hu = kUnpinned;               // every vein, 150..300
    int open_valve = -1;                      // 1 open, 0 closed
    static constexpr double kUnpinned = std::numeric_limits<double>::quiet_NaN();
  } pins;
};

// The family's two splits (issue #30; docs/benchmarks/model.md): seeds 1..999 tune the pipeline,
// seeds from kFamilyHeldOutFirstSeed on are held out (never looked at while developing it).
inline constexpr uint32_t kFamilyHeldOutFirstSeed = 1001;

// a family member's whole spec, drawn from its seed as a scanner protocol varies: in-plane voxel
// 0.3..0.8 mm and slices 0.3..0.8 mm (drawn apart: anisotropic), a 512 x 512 matrix widened where
// its field would be under 175 mm, a z range of 140..160 mm, noise 15..45 HU, the scanner's blur
// 0.3..0.6 mm, slices head- or feet-first
PhantomCtaSpec family_phantom_cta_spec(uint32_t seed);

struct PhantomCtaPlaque {
  std::string branch;
  double arc_length_mm = 0;      // along the branch's truth centerline, from its first point
  Eigen::Vector3d center_mm;     // CT physical frame
  Eigen::Vector3d semi_axes_mm;  // along the vessel 1..2, radial 0.8..1.2, circumferential 1..1.5
  double hu = 0;
};

struct PhantomCtaTortuosity {
  std::string branch;
  double amplitude_mm = 0, wavelength_mm = 0;
};

// what was drawn, for the pipeline's checks and for people (all positions in the CT's frame, mm)
struct PhantomCtaFacts {
  // contrast timing: lumen HU = max(lumen_floor_hu, contrast_hu_proximal - fade_hu_per_mm * d),
  // d the path length from the ostium (0 inside the aorta)
  double contrast_hu_proximal = 0, fade_hu_per_mm = 0, lumen_floor_hu = 0;
  double aorta_hu = 0, lv_hu = 0, la_hu = 0, rv_hu = 0, ra_hu = 0, myocardium_hu = 0;
  double fat_sleeve_mm = 0;  // epicardial fat around every artery: radius + this
  // the stenosis: diameter reduction `fraction` at arc length `arc_length_mm` on `branch`,
  // a raised-cosine profile over `length_mm`
  std::string stenosis_branch;
  double stenosis_arc_length_mm = 0, stenosis_fraction = 0, stenosis_length_mm = 0;
  double stenosis_reference_radius_mm = 0;  // the radius there without the stenosis
  Eigen::Vector3d stenosis_center_mm = Eigen::Vector3d::Zero();
  std::vector<PhantomCtaPlaque> plaques;
  // the cardiac vein: beside `vein_beside` from arc length vein_start_mm over vein_length_mm,
  // touching the artery's outer wall
  std::string vein_beside;
  double vein_start_mm = 0, vein_length_mm = 0, vein_radius_mm = 0, vein_hu = 0;
  std::vector<Eigen::Vector3d> vein_points_mm;  // its centerline
  // pose: the heart rotated (x, then y, then z, degrees; about the heart centre) and scaled
  Eigen::Vector3d heart_rotation_deg = Eigen::Vector3d::Zero();
  Eigen::Matrix3d heart_rotation = Eigen::Matrix3d::Identity();
  double heart_scale = 1;
  Eigen::Vector3d heart_center_mm = Eigen::Vector3d::Zero();  // the scanner offset when scanner_frame
  Eigen::Vector3d lv_center_mm = Eigen::Vector3d::Zero();
  double radius_scale = 1;
  std::vector<std::string> dropped_branches;  // by the seed (D2, OM2)
  // branches the field of view cuts short or leaves out of the truth (the aorta above the
  // field is common; coronaries need a field of at least ~120 mm each way)
  std::vector<std::string> clipped_branches;
  std::vector<PhantomCtaTortuosity> tortuosity;

  // the family's draws (spec.family; zero, empty or as the classic phantoms otherwise)
  bool family = false;
  // the heart's semi-axes along its frame (anterior, left, base) times heart_scale
  Eigen::Vector3d heart_axes_scale = Eigen::Vector3d::Ones();
  bool open_valve = true;   // the LV outflow tract joins the LV cavity to the aortic root
  double rv_wall_mm = 4.0;  // the right ventricle's blood this far inside the myocardium's outline
  // the right ventricle's cavity semi-axes (heart frame, mm before the scales)
  Eigen::Vector3d rv_semi_mm = Eigen::Vector3d(11, 24, 28);
  double lad_lcx_angle_deg = 0;            // between the two daughters' first 5 mm (chords from the fork)
  std::string tortuous_branch;             // a trunk with >= 3 bends of >= 45 deg (empty: none)
  std::vector<std::string> side_branches;  // small branches added to the tree (in the truth)
  // the left atrial appendage: a rounded cone of left-atrial blood from the LA to beside the LCx,
  // its surface laa_gap_mm from the LCx's lumen (laa_gap_mm < 0: none)
  Eigen::Vector3d laa_base_mm = Eigen::Vector3d::Zero(), laa_tip_mm = Eigen::Vector3d::Zero();
  double laa_base_radius_mm = 0, laa_tip_radius_mm = 0, laa_gap_mm = -1;
  // veins crossing over arteries, touching them where they cross
  struct CrossingVein {
    std::string crosses;
    double radius_mm = 0, hu = 0, angle_deg = 0;
    std::vector<Eigen::Vector3d> points_mm;
  };
  std::vector<CrossingVein> crossing_veins;
  // blooming: each plaque's halo, bloom_mm wider, at bloom_fraction of its HU (over what it covers)
  double bloom_mm = 0, bloom_fraction = 0;
  // a stent's struts (metal) over stent_length_mm of stent_branch from stent_start_mm (empty: none)
  std::string stent_branch;
  double stent_start_mm = 0, stent_length_mm = 0, stent_strut_hu = 0;
  Eigen::Vector3d stent_center_mm = Eigen::Vector3d::Zero();
};

struct PhantomCta {
  PhantomCtaSpec spec;
  Volume ct;  // int16 HU, spec's dims, spacing and direction
  // true centerlines and radii (metres, the CT's physical frame, LPS), the stenosis in the
  // radii; the ascending aorta is the root branch. Only points inside the grid (voxel centres'
  // box): a branch leaving it ends there (facts.clipped_branches)
  VesselTree truth;
  // on the ascending aorta's centerline 25 mm above its root (~15 mm above the LM's origin)
  Eigen::Vector3d aortic_seed_mm = Eigen::Vector3d::Zero();
  // "aortic seed", "aortic root", "LM ostium", "RCA ostium", "stenosis", "plaque 1".., "vein
  // start", "vein end", "LV centre", "heart centre" (metres, CT frame)
  std::vector<Landmark> landmarks;
  PhantomCtaFacts facts;
};

// the painted stenosis as a lesion of the truth tree (anatomy/vessel/lesion.h), measured as
// detect_lesions measures one: at the narrowest point (the raised cosine's centre), MLD
// 2 r (1 - f) against the reference 2 r, over the extent narrowed by at least edge_stenosis_pct
// (the raised cosine of length L: L / pi * acos(2 e / f - 1)); none when f does not reach the edge
std::vector<Lesion> phantom_cta_lesions(const PhantomCta& phantom, double edge_stenosis_pct = 10.0);

// how far p_mm (CT frame) lies from the painted heart's outer surface, the myocardium's sphere
// (thorax_phantom.h kPhantomHeartRadiusMm x heart_scale about heart_center_mm), unsigned: the truth
// the heart fit is measured against
double distance_to_painted_heart_mm(const PhantomCtaFacts& facts, const Eigen::Vector3d& p_mm);

// throws std::invalid_argument "PhantomCtaSpec.<field>: <expected>, got <value>" for a spec it
// cannot build, before allocating anything: dims, voxel size, extent or threads outside the bounds
// above, a direction that is not a signed permutation, negative or non-finite noise or blur, a
// stenosis fraction >= 1)
PhantomCta make_phantom_cta(const PhantomCtaSpec& spec);

#ifdef PCISIM_HAVE_JSON
// writes dir/ct.nrrd (raw NRRD), dir/truth.json (the vessel tree format) and dir/phantom.json
// (format "pcisim-phantom-cta": the spec, the facts, the aortic seed and the landmarks);
// creates dir. Throws std::runtime_error naming the file on failure.
void write_phantom_cta(const PhantomCta& cta, const std::string& dir);
#endif

}  // namespace pcisim::anatomy
