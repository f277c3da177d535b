#pragma once
// Reading and writing CT volumes: MetaImage (.mha inline, .mhd + raw) and NRRD (.nrrd attached,
// .nhdr + detached; raw, and gzip when built with zlib). Errors throw VolumeIoError whose message
// reads "<file>: <field>: <what>", e.g. "ct.mhd: DimSize: expected 3 positive integers, got '5 5'".
#include <stdexcept>
#include <string>

#include "anatomy/volume/volume.h"

namespace pcisim::anatomy {

struct VolumeIoError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// true when this build can read and write gzip-encoded NRRD (zlib was found)
bool volume_io_has_gzip();

// by extension: .mha/.mhd (MetaImage) or .nrrd/.nhdr (NRRD)
// require_spacing: refuse a file that does not give the voxel spacing (a CT needs it; without it
// the formats default to 1 mm)
Volume read_volume(const std::string& path, bool require_spacing = false);

Volume read_metaimage(const std::string& path, bool require_spacing = false);
// .mha: header and data in one file; .mhd: header, data in <stem>.raw beside it
void write_metaimage(const Volume& volume, const std::string& path);

Volume read_nrrd(const std::string& path, bool require_spacing = false);
// .nrrd with attached data; gzip needs zlib (throws otherwise)
void write_nrrd(const Volume& volume, const std::string& path, bool gzip = false);

}  // namespace pcisim::anatomy
