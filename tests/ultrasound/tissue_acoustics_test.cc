// Acoustic properties per named tissue (issue #32 item 1): the table's numbers and ranks, and the
// renderer through a tissue map: each tissue's speckle as bright as its backscatter, fluid's
// posterior enhancement as the attenuation it spares, the kidney phantom's tissues in a
// sonographer's order of brightness, and a map it cannot use refused naming what is wrong.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "anatomy/organ/kidney_phantom.h"
#include "ultrasound/echo/acoustic_model.h"
#include "ultrasound/echo/tissue_acoustics.h"
#include "ultrasound/render/bmode_renderer.h"

namespace pcisim::ultrasound {
namespace {

using anatomy::TissueMap;
using anatomy::Volume;
using Eigen::Vector3d;

double db(double ratio) {
  return 10.0 * std::log10(ratio);
}

const TissueAcoustics& row(const std::string& name) {
  const TissueAcoustics* t = find_tissue_acoustics(name);
  if (!t) throw std::runtime_error("no row " + name);
  return *t;
}

TEST(TissueAcoustics, RowsGiveTheirImpedanceAndKeepTheKidneysRanks) {
  for (const std::string& name : anatomy::kidney_tissue_names())
    EXPECT_NE(find_tissue_acoustics(name), nullptr) << name;
  EXPECT_EQ(find_tissue_acoustics("spleen"), nullptr);
  EXPECT_NE(known_tissue_names().find("renal cortex"), std::string::npos);
  // Z = rho c: fat 0.911 x 1.440, kidney 1.066 x 1.560 (MRayl); the capsule's echo between them
  const Acoustics fat = acoustics_of(row("perirenal fat")), cortex = acoustics_of(row("renal cortex"));
  EXPECT_NEAR(fat.impedance_mrayl, 1.31184, 1e-5);
  EXPECT_NEAR(cortex.impedance_mrayl, 1.66296, 1e-5);
  EXPECT_NEAR(db(reflection(fat.impedance_mrayl, cortex.impedance_mrayl)), -18.56, 0.01);
  EXPECT_NEAR(fat.path_ratio, 1440.0 / 1540.0, 1e-6);
  // brightness as a sonographer ranks it: sinus fat > perirenal fat > cortex > medulla (6 dB or
  // more under the cortex) > blood, urine (anechoic: 20 dB or more under the cortex)
  const double sinus = row("renal sinus fat").backscatter, peri = row("perirenal fat").backscatter,
               cx = row("renal cortex").backscatter, med = row("renal medulla").backscatter;
  EXPECT_GT(sinus, peri);
  EXPECT_GT(peri, cx);
  EXPECT_GT(db(cx / med), 6.0);
  EXPECT_GT(db(cx / row("blood").backscatter), 20.0);
  EXPECT_GT(db(cx / row("urine").backscatter), 20.0);
  // fluid spares the beam: a tenth of the soft tissue's attenuation or less
  EXPECT_LT(row("urine").attenuation_db_cm_mhz, 0.1 * kSoftTissueAttenuationDbCmMhz);
  // a case without a map: the HU rules, the same four numbers
  const Acoustics soft = acoustics_of_hu(40.0);
  EXPECT_FLOAT_EQ(soft.impedance_mrayl, static_cast<float>(impedance_mrayl(40.0)));
  EXPECT_FLOAT_EQ(soft.attenuation_factor, static_cast<float>(attenuation_factor(40.0)));
  EXPECT_FLOAT_EQ(soft.scatter_amplitude, static_cast<float>(std::sqrt(backscatter(40.0))));
}

// a 0.5 mm grid over x in [-30, 30], y (depth) in [-5, 95], z in [-20, 20] mm, labelled by
// `label_at` (names' indices); its CT all zero (the map, not the HU, is imaged)
struct Layers {
  Volume ct;
  TissueMap map;
};

template <class F>
Layers make_layers(const std::vector<std::string>& names, F label_at) {
  constexpr double h = 0.5;
  const Vector3d lo(-30, -5, -20);
  const std::array<int64_t, 3> dims{121, 201, 81};
  Layers l;
  l.ct = Volume::make(dims, Vector3d::Constant(h), lo, anatomy::VoxelType::kInt16);
  l.map.labels = Volume::make(dims, Vector3d::Constant(h), lo, anatomy::VoxelType::kInt16);
  l.map.names = names;
  for (int64_t k = 0; k < dims[2]; ++k)
    for (int64_t j = 0; j < dims[1]; ++j)
      for (int64_t i = 0; i < dims[0]; ++i)
        l.map.labels.hu_i16[l.map.labels.linear_index(i, j, k)] =
            static_cast<int16_t>(label_at(lo + h * Vector3d(i, j, k)));
  return l;
}

ProbePose probe_at_top() {
  ProbePose p;
  p.origin_mm = Vector3d::Zero();
  p.beam = Vector3d::UnitY();
  p.lateral = Vector3d::UnitX();
  return p;
}

UsSettings layer_settings() {
  UsSettings s;
  s.width_mm = 50.0;
  s.width_px = 128;
  s.height_px = 512;
  s.depth_mm = 90.0;
  return s;
}

// the mean echo intensity over depths [a, b] mm and lateral positions [x0, x1] mm
double mean_echo(const BModeRenderer& r, double a, double b, double x0, double x1) {
  const UsSettings& s = r.settings();
  double sum = 0.0;
  int n = 0;
  for (int row = 0; row < s.height_px; ++row) {
    const double d = (row + 0.5) * s.depth_mm / s.height_px;
    if (d < a || d > b) continue;
    for (int c = 0; c < s.width_px; ++c) {
      const double x = ((c + 0.5) / s.width_px - 0.5) * s.width_mm;
      if (x < x0 || x > x1) continue;
      sum += r.echo_intensity()[static_cast<size_t>(row) * s.width_px + c];
      ++n;
    }
  }
  return sum / n;
}

// without attenuation each layer's speckle is as bright on average as its tissue's backscatter
// (the scatterers' scale: 1e-4 x the table's number), whatever the PSF
TEST(TissueAcoustics, EachLayersSpeckleIsItsTissuesBackscatter) {
  const std::vector<std::string> names = {"renal cortex", "renal medulla", "renal sinus fat", "perirenal fat"};
  // depth bands of 18 mm: cortex, medulla, sinus fat, perirenal fat
  const Layers l =
      make_layers(names, [](const Vector3d& p) { return std::clamp(static_cast<int>(p.y() / 18.0), 0, 3); });
  UsSettings s = layer_settings();
  s.attenuation_db_per_cm_mhz = 0.0;
  BModeRenderer r(l.ct, s, &l.map);
  r.render(probe_at_top(), 3);
  for (int band = 0; band < 4; ++band) {
    // the band's middle (3 mm clear of its boundaries' echoes), the speckle's mean over ~1000 grains
    const double mean = mean_echo(r, 18.0 * band + 3.0, 18.0 * band + 15.0, -20.0, 20.0);
    const double expected = 1e-4 * row(names[band]).backscatter;
    std::printf("%s: mean intensity %.3g, backscatter %.3g (%+.2f dB)\n", names[band].c_str(), mean, expected,
                db(mean / expected));
    EXPECT_NEAR(db(mean / expected), 0.0, 1.0) << names[band];
  }
}

// posterior enhancement: 10 mm of urine in place of cortex spares the beam 2 (alpha_cortex -
// alpha_urine) f 1 cm of round-trip loss, so the cortex behind it is that much brighter
// (transmission through urine's two faces costs < 0.01 dB: Z 1.588 against 1.663 MRayl)
TEST(TissueAcoustics, FluidBrightensWhatLiesBehindItByTheAttenuationItSpares) {
  // names: 0 cortex, 1 urine; the cyst: a 10 mm slab at depths 30-40 mm on the left half
  const Layers l = make_layers({"renal cortex", "urine"},
                               [](const Vector3d& p) { return p.x() < 0.0 && p.y() >= 30.0 && p.y() < 40.0 ? 1 : 0; });
  UsSettings s = layer_settings();
  BModeRenderer r(l.ct, s, &l.map);
  r.render(probe_at_top(), 5);
  // behind the cyst (left) against the same depth through cortex (right); 8 mm clear of x = 0,
  // where the lateral PSF mixes the two
  const double left = mean_echo(r, 45.0, 60.0, -24.0, -8.0), right = mean_echo(r, 45.0, 60.0, 8.0, 24.0);
  const double spared_db = 2.0 * (row("renal cortex").attenuation_db_cm_mhz - row("urine").attenuation_db_cm_mhz) /
                           kSoftTissueAttenuationDbCmMhz * s.attenuation_db_per_cm_mhz * s.frequency_mhz * 1.0;
  std::printf("behind the cyst %+.2f dB (spared attenuation %.2f dB)\n", db(left / right), spared_db);
  EXPECT_NEAR(db(left / right), spared_db, 1.0);
  // and the cyst itself is dark: 20 dB or more under the cortex beside it
  EXPECT_GT(db(mean_echo(r, 32.0, 38.0, 8.0, 24.0) / mean_echo(r, 32.0, 38.0, -24.0, -8.0)), 20.0);
}

TEST(TissueAcoustics, AMapTheRendererCannotUseIsRefusedNamingWhatIsWrong) {
  Layers l = make_layers({"renal cortex", "unobtainium"}, [](const Vector3d& p) { return p.y() > 40.0 ? 1 : 0; });
  try {
    BModeRenderer r(l.ct, layer_settings(), &l.map);
    ADD_FAILURE() << "an unknown tissue was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("tissue \"unobtainium\" (label 1) has no acoustic properties"),
              std::string::npos)
        << e.what();
  }
  l.map.names = {"renal cortex"};  // label 1 named by nothing
  try {
    BModeRenderer r(l.ct, layer_settings(), &l.map);
    ADD_FAILURE() << "a label without a name was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("not a label of the 1 names"), std::string::npos) << e.what();
  }
}

// the kidney phantom through its tissue map, as a sonographer would rank it: the sinus's fat
// brightest, then the cortex, the medullary pyramids darker, the pelvis's urine darkest. Each
// beam sample is classed by the phantom's own tissue at its place (2 mm clear of any other
// tissue, beyond the boundaries' echoes); attenuation off, so depth does not rank them
TEST(TissueAcoustics, TheKidneysTissuesShowInASonographersOrder) {
  const anatomy::KidneyPhantom kidney = anatomy::make_kidney_phantom();
  const TissueMap map{kidney.tissue, anatomy::kidney_tissue_names()};
  UsSettings s;
  s.width_px = 192;
  s.height_px = 512;
  s.depth_mm = 80.0;
  s.width_mm = 100.0;
  s.attenuation_db_per_cm_mhz = 0.0;
  BModeRenderer r(kidney.ct, s, &map);
  ProbePose p;
  p.origin_mm = Vector3d(0, kidney.ct.origin_mm.y(), 0);
  p.beam = Vector3d::UnitY();
  p.lateral = Vector3d::UnitZ();
  r.render(p, 1);
  using anatomy::KidneyTissue;
  const KidneyTissue kinds[] = {KidneyTissue::kSinusFat, KidneyTissue::kCortex, KidneyTissue::kMedulla,
                                KidneyTissue::kPelvis};
  std::vector<std::vector<float>> found(4);
  for (int row = 0; row < s.height_px; ++row)
    for (int c = 0; c < s.width_px; ++c) {
      const Vector3d x = pixel_to_world(s, p, c, row);
      const KidneyTissue t = anatomy::kidney_tissue_at(kidney.spec, kidney.facts, x);
      bool clear = true;
      for (int a = 0; a < 3 && clear; ++a)
        for (double d : {-2.0, 2.0})
          clear = clear && anatomy::kidney_tissue_at(kidney.spec, kidney.facts, x + d * Vector3d::Unit(a)) == t;
      if (!clear) continue;
      for (int k = 0; k < 4; ++k)
        if (t == kinds[k]) found[k].push_back(r.echo_intensity()[static_cast<size_t>(row) * s.width_px + c]);
    }
  // medians (a speckle's intensity is exponential: median = ln 2 x mean for each alike)
  double median[4];
  for (int k = 0; k < 4; ++k) {
    ASSERT_GT(found[k].size(), 100u) << "tissue " << static_cast<int>(kinds[k]);
    std::nth_element(found[k].begin(), found[k].begin() + found[k].size() / 2, found[k].end());
    median[k] = found[k][found[k].size() / 2];
  }
  std::printf("median intensity: sinus fat %.3g, cortex %.3g, medulla %.3g, urine %.3g (samples %zu %zu %zu %zu)\n",
              median[0], median[1], median[2], median[3], found[0].size(), found[1].size(), found[2].size(),
              found[3].size());
  EXPECT_GT(db(median[0] / median[1]), 6.0);   // sinus fat over cortex (the table: 9 dB)
  EXPECT_GT(db(median[1] / median[2]), 6.0);   // cortex over the pyramids (the table: 9.2 dB)
  EXPECT_GT(db(median[2] / median[3]), 10.0);  // pyramids over urine (the table: 20.8 dB)
}

}  // namespace
}  // namespace pcisim::ultrasound
