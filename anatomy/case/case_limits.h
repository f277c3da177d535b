#pragma once
// The bounds on a case folder's numbers (docs/anatomy.md, "Limits"), defined once: the case
// reader, the vessel tree reader and the mesh reader check every count, length and position a
// case brings against these before anything is allocated or looped over for it, so a case can
// make a tool neither allocate without bound nor work for minutes. Each bound says why.
#include <cstdint>

namespace pcisim::anatomy::case_limits {

// ---- vessels.json ----
// the widest lumen: an aneurysmal aortic root at the surgical threshold is 55 mm across (a
// coronary lumen is under 5 mm in radius); a metre lofts tubes of millions of triangles
inline constexpr double kMaxVesselRadiusM = 0.03;
// the narrowest: a 99% stenosis of the finest branch the modeller traces is still ~5 um
inline constexpr double kMinVesselRadiusM = 1e-6;
// consecutive centerline points closer than this give the tube no direction (a repeated point);
// the modeller's finest section spacing is 0.1 mm
inline constexpr double kMinPointSpacingM = 1e-6;
// no patient coordinate is this far from the scanner's origin (table positions reach ~2 m):
// every square and product of coordinates stays finite
inline constexpr double kMaxCoordinateM = 10.0;
// a CTA's tree resolves a few dozen named branches; room for every side branch a model traces
inline constexpr int kMaxBranches = 512;
// the aorta across a chest CT (<= 400 mm) at the modeller's finest section spacing (0.1 mm)
inline constexpr int kMaxBranchPoints = 4000;
// five such branches; the phantom has 1 234
inline constexpr int kMaxTreePoints = 20000;
// the centerlines' total length: a coronary tree with its ascending aorta is under 1 m (the
// phantom's 0.61 m); the lofted tubes and the wall-contact field grow with it
inline constexpr double kMaxTreeLengthM = 2.0;

// ---- meshes ----
// lumen.stl: the modeller's stitched lumen of a phantom CTA is 1.8 M triangles at its default
// 0.2 mm (6 s to read and check), 7.2 M at 0.1 mm; 8 M is 400 MB of binary STL
inline constexpr int64_t kMaxLumenTriangles = 8'000'000;
// the organ's surface: the kidney phantom has 11 328; marching cubes over a kidney segmented at
// 0.5 mm gives about 160 000 (2 x 10^4 mm^2 of surface). Each bead is tested against every
// triangle (kMaxFiducials x this is 1.3 x 10^8 triangle visits, about a second)
inline constexpr int64_t kMaxOrganTriangles = 500'000;

// tissue.nrrd's names: a labelmap of an abdomen names tens of tissues (the kidney phantom 11);
// each name is a word or three
inline constexpr int kMaxTissueNames = 256;
inline constexpr int kMaxTissueNameChars = 64;

// ---- case.json, fiducials.json, heart.node ----
// a registration phantom carries tens of beads (the kidney phantom 45)
inline constexpr int kMaxFiducials = 256;
// named points for people and the C-arm's isocentre (the phantom writes 20)
inline constexpr int kMaxLandmarks = 1000;
// lesions.json: a tree has a few; a file that lists more is not a patient's
inline constexpr int kMaxLesions = 256;
inline constexpr int64_t kMaxLesionsFileBytes = int64_t{1} << 20;
// case.json holds names and a few numbers (the phantom's is 4 KB). fiducials.json holds at most
// kMaxFiducials lines of ~80 bytes; the file may be far larger (read, then refused by its count)
inline constexpr int64_t kMaxCaseJsonBytes = int64_t{4} << 20;
inline constexpr int64_t kMaxFiducialsFileBytes = int64_t{16} << 20;
// heart.node has one line per template vertex (1 484 lines of under 100 bytes: 150 KB)
inline constexpr int64_t kMaxHeartNodeFileBytes = int64_t{4} << 20;

// ---- where things may be ----
// landmarks, the heart's placement and the organ's support plane lie inside the CT or at most
// this far outside its box (a CT cropped to the coronaries may leave the heart's centre just
// outside it); without a CT, the same distance from the centerlines' box
inline constexpr double kNearCtMm = 50.0;
// a direction given by its components (the support's normal, any length): each within this
// magnitude and the length at least kMinDirectionLength, so normalising it neither overflows
// (|x|^2 of 1e308 is inf) nor divides by an underflowed length
inline constexpr double kMaxDirectionComponent = 1e6;
inline constexpr double kMinDirectionLength = 1e-6;

}  // namespace pcisim::anatomy::case_limits
