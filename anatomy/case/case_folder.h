#pragma once
// A case on disk (docs/anatomy.md): a folder with case.json naming what is present,
//   vessels.json   centerlines and radii (the pcisim-vessel-tree format, metres); optional in an
//                  organ case
//   lumen.stl      the lumen surface, binary STL, millimetres, LPS
//   ct.nrrd|.mha   optional CT in HU (required in an organ case: the ultrasound images it)
//   organ.ply      the soft-tissue scene's organ surface (optional), millimetres, LPS: written as
//                  binary PLY of doubles; read from any mesh file read_mesh reads (STL, PLY, OBJ)
//   fiducials.json the organ's bead centres (millimetres, LPS)
//   tissue.nrrd    the organ's tissue map (optional): int16 labels on the CT's grid, their names
//                  in case.json organ.tissue.names (the ultrasound's acoustic properties per
//                  tissue); slicer/tissue.ctbl its 3D Slicer colour table (written, not read)
//   lesions.json   the vessels' stenoses (optional; anatomy/vessel/lesion.h): branch, position along
//                  it, length, minimal lumen and reference diameters, % stenosis
//   slicer/<branch>.mrk.json   each centerline as a 3D Slicer markups curve (written, not read;
//                              the name made safe: markups_file_stem)
//   slicer/fiducials.mrk.json  the organ's beads as a 3D Slicer point list (written, not read)
//   overview.png   a picture for people (written when built with libpng, not read)
// Built only with nlohmann-json. Readers throw CaseError "<file>: <field>: <what>".
#include <functional>
#include <stdexcept>
#include <string>

#include "anatomy/case/case.h"

namespace pcisim::anatomy {

struct CaseError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

inline constexpr const char* kCaseFormat = "pcisim-case";
inline constexpr int kCaseVersion = 1;
inline constexpr const char* kFiducialsFormat = "pcisim-fiducials";  // fiducials.json
inline constexpr const char* kLesionsFormat = "pcisim-lesions";      // lesions.json

// lesions.json alone (a phantom's truth beside its CT; a case writes it with write_case): throws
// CaseError naming the file, and on reading the lesion and field that do not fit `tree`
void write_lesions_json(const std::vector<Lesion>& lesions, const std::string& path);
std::vector<Lesion> read_lesions_json(const std::string& path, const VesselTree& tree);

// writes the case into `dir` (created; files of the same names are replaced)
void write_case(const Case& c, const std::string& dir);

// whether write_case writes overview.png: only when built with libpng (without it case.json names
// no overview; callers say so in their logs)
constexpr bool case_overview_written() {
#ifdef PCISIM_ANATOMY_HAVE_PNG
  return true;
#else
  return false;
#endif
}

// how a CT given as a DICOM series folder ("ct": {"dicom": "ct/"}) is read: the DICOM reader
// lives in its own library (anatomy/dicom, ITK), so the caller hands it in; without one such a
// case is refused saying so
using DicomFolderReader = std::function<Volume(const std::string& folder)>;

// reads and checks a case folder: every named file present and readable, units "mm", frame "LPS",
// the lumen closed and manifold, the CT with its spacing, every centerline point inside the CT;
// an organ closed, manifold and wound outward, inside the CT, its beads inside it, its support's
// normal non-zero (normalised) with the organ on its free side, and a CT beside it
Case read_case(const std::string& dir, const DicomFolderReader& read_dicom = nullptr);

}  // namespace pcisim::anatomy
