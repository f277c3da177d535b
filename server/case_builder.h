#pragma once
// The one place a scene's anatomy is built: its case folder read (and checked), or the procedural
// phantom of its seed generated, once per scene. Physics, the X-ray thread and the status
// messages all get this same value.
#include <memory>

#include "anatomy/case/case.h"
#include "anatomy/phantom/phantom_case.h"
#include "server/scene/scene.h"

namespace pcisim::server {

// what the phantom of this scene is: its seed; with a CT exactly where and as fine as the scene's
// X-ray background wants it (blood in the lumens: the iodine comes per frame)
anatomy::PhantomCaseSpec phantom_case_spec(const Scene& scene);

// the soft-tissue scene's procedural organ (anatomy.organ "kidney", its seed): the organ and its
// CT (at ct_spacing_mm voxels: the scene's 1 mm; finer shows sloping boundaries without the
// voxels' steps, at 4-5x the build time for 0.5 mm) and tissue map, no vessels (what
// --write-case writes for such a scene)
anatomy::Case kidney_case(const Scene& scene, double ct_spacing_mm = 1.0);

// throws anatomy::CaseError (a case folder that is missing or wrong, or one that does not fit the
// scene: no organ for a soft-tissue scene, no vessels for the others) naming the file and field
std::shared_ptr<const anatomy::Case> build_case(const Scene& scene);

// --case: the folder replaces the scene's anatomy, its phantom seed or its procedural organ (a
// soft-tissue scene then runs on the case's organ)
void use_case_folder(Scene& scene, const std::string& dir);

// a case folder, its CT possibly a DICOM series (when this build has the DICOM reader)
anatomy::Case read_case_folder(const std::string& dir);

}  // namespace pcisim::server
