#include "server/case_builder.h"

#include <filesystem>

#include "anatomy/case/case_folder.h"
#include "anatomy/organ/kidney_phantom.h"
#include "ultrasound/echo/tissue_acoustics.h"
#ifdef PCISIM_HAVE_DICOM
#include "anatomy/dicom/dicom_series.h"
#endif

namespace pcisim::server {

anatomy::Case read_case_folder(const std::string& dir) {
#ifdef PCISIM_HAVE_DICOM
  return anatomy::read_case(dir, [](const std::string& folder) { return anatomy::read_dicom_series(folder); });
#else
  return anatomy::read_case(dir);
#endif
}

anatomy::PhantomCaseSpec phantom_case_spec(const Scene& scene) {
  anatomy::PhantomCaseSpec p;
  p.seed = scene.world.anatomy.seed;
  const xray::FluoroSpec fluoro = scene.xray ? scene.xray->fluoro : xray::FluoroSpec{};
  p.ct_seed = fluoro.seed;
  p.ct_dims = fluoro.volume_dims;
  p.ct_spacing_mm = fluoro.volume_spacing_mm;
  p.ct_contrast = false;
  return p;
}

anatomy::Case kidney_case(const Scene& scene, double ct_spacing_mm) {
  anatomy::KidneySpec spec;
  spec.seed = scene.world.anatomy.seed;
  spec.ct_spacing_mm = ct_spacing_mm;
  anatomy::KidneyPhantom k = anatomy::make_kidney_phantom(spec);
  anatomy::Case c;
  c.name = "kidney phantom " + std::to_string(spec.seed);
  c.organ = anatomy::kidney_organ(k);
  c.ct = std::move(k.ct);
  return c;
}

// a case read for a scene must hold what the scene simulates: the soft-tissue scene an organ,
// the others (wire, heart, fluoroscopy) a vessel tree
void check_case_fits(const anatomy::Case& c, const Scene& scene) {
  const std::string case_json = (std::filesystem::path(scene.case_dir) / "case.json").string();
  if (scene.world.soft_tissue && !c.organ)
    throw anatomy::CaseError(case_json +
                             ": organ: missing (the soft-tissue scene needs a case with an organ; docs/anatomy.md)");
  if (!scene.world.soft_tissue && c.vessels.branches.empty())
    throw anatomy::CaseError(case_json + ": vessels: missing (an organ case without vessels: scene '" + scene.name +
                             "' needs a coronary case)");
  // the ultrasound takes each tissue's acoustic properties by its name: refused here, naming the
  // file, rather than when the ultrasound thread starts (a Slicer labelmap names label 0
  // "Background": it must be a tissue the table knows, say "air" or "water")
  if (scene.ultrasound && c.organ && c.organ->tissue)
    for (size_t i = 0; i < c.organ->tissue->names.size(); ++i)
      if (!ultrasound::find_tissue_acoustics(c.organ->tissue->names[i]))
        throw anatomy::CaseError(case_json + ": organ.tissue.names[" + std::to_string(i) + "]: \"" +
                                 c.organ->tissue->names[i] +
                                 "\" has no acoustic properties (known: " + ultrasound::known_tissue_names() + ")");
}

std::shared_ptr<const anatomy::Case> build_case(const Scene& scene) {
  if (!scene.case_dir.empty()) {
    // the scene loader refuses both; a Scene put together in code gets the same answer
    if (!scene.organ.empty())
      throw std::invalid_argument("anatomy: a case folder (" + scene.case_dir + ") and the procedural organ \"" +
                                  scene.organ + "\" both given: the case brings its own organ");
    anatomy::Case c = read_case_folder(scene.case_dir);
    check_case_fits(c, scene);
    return std::make_shared<const anatomy::Case>(std::move(c));
  }
  if (scene.organ == "kidney") return std::make_shared<const anatomy::Case>(kidney_case(scene));
  anatomy::PhantomCaseSpec p = phantom_case_spec(scene);
  p.with_ct = scene.xray.has_value();  // only the X-ray thread needs the CT
  return std::make_shared<const anatomy::Case>(anatomy::make_phantom_case(p));
}

void use_case_folder(Scene& scene, const std::string& dir) {
  scene.case_dir = dir;
  scene.organ.clear();
}

}  // namespace pcisim::server
