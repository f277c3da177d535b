#pragma once
// ITK only (see itk_bridge.h): included by the itk_*bridge.cc files alone, which see ITK's
// headers; the rest of pcisim never includes it.
#include <itkImage.h>

#include <cstring>

#include "modeling/image/itk_bridge.h"

namespace pcisim::modeling::itk_bridge {

// an ITK image over a copy of the data, with the grid's geometry
template <typename T>
inline typename itk::Image<T, 3>::Pointer to_itk(const Grid& g, const T* data) {
  auto img = itk::Image<T, 3>::New();
  typename itk::Image<T, 3>::RegionType region;
  typename itk::Image<T, 3>::SizeType size;
  typename itk::Image<T, 3>::SpacingType sp;
  typename itk::Image<T, 3>::PointType origin;
  typename itk::Image<T, 3>::DirectionType dir;
  size_t n = 1;
  for (int a = 0; a < 3; ++a) {
    size[a] = static_cast<itk::SizeValueType>(g.dims[a]);
    n *= static_cast<size_t>(g.dims[a]);
    sp[a] = g.spacing_mm[a];
    origin[a] = g.origin_mm[a];
    for (int b = 0; b < 3; ++b) dir[a][b] = g.direction[3 * a + b];
  }
  region.SetSize(size);
  img->SetRegions(region);
  img->SetSpacing(sp);
  img->SetOrigin(origin);
  img->SetDirection(dir);
  img->Allocate();
  std::memcpy(img->GetBufferPointer(), data, n * sizeof(T));
  return img;
}

inline size_t voxels(const Grid& g) {
  return static_cast<size_t>(g.dims[0] * g.dims[1] * g.dims[2]);
}

}  // namespace pcisim::modeling::itk_bridge
