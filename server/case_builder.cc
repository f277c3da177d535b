#include "server/case_builder.h"

#include "anatomy/case/case_folder.h"
#include "anatomy/organ/kidney_phantom.h"
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

// the soft-tissue scene's procedural organ: its CT (what the ultrasound images) and the organ
// physics builds; no vessels
anatomy::Case kidney_case(const Scene& scene) {
  anatomy::KidneySpec spec;
  spec.seed = scene.world.anatomy.seed;
  anatomy::KidneyPhantom k = anatomy::make_kidney_phantom(spec);
  anatomy::Case c;
  c.name = "kidney phantom " + std::to_string(spec.seed);
  c.organ = anatomy::kidney_organ(k);
  c.ct = std::move(k.ct);
  return c;
}

std::shared_ptr<const anatomy::Case> build_case(const Scene& scene) {
  if (scene.organ == "kidney") {
    if (!scene.case_dir.empty())
      throw std::invalid_argument("anatomy: a case folder (" + scene.case_dir +
                                  ") cannot replace the procedural organ of a soft-tissue scene");
    return std::make_shared<const anatomy::Case>(kidney_case(scene));
  }
  if (!scene.case_dir.empty()) return std::make_shared<const anatomy::Case>(read_case_folder(scene.case_dir));
  anatomy::PhantomCaseSpec p = phantom_case_spec(scene);
  p.with_ct = scene.xray.has_value();  // only the X-ray thread needs the CT
  return std::make_shared<const anatomy::Case>(anatomy::make_phantom_case(p));
}

}  // namespace pcisim::server
