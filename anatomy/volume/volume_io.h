#pragma once
// Reading and writing CT volumes: MetaImage (.mha inline, .mhd + raw) and NRRD (.nrrd attached,
// .nhdr + detached; raw, and gzip when built with zlib), and 4-D NRRD sequences (x y z time).
// Errors throw VolumeIoError whose message reads "<file>: <field>: <what>", e.g.
// "ct.mhd: DimSize: expected 3 positive integers, got '5 5'".
#include <stdexcept>
#include <string>
#include <vector>

#include "anatomy/volume/volume.h"

namespace pcisim::anatomy {

struct VolumeIoError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// true when this build can read and write gzip-encoded NRRD (zlib was found)
bool volume_io_has_gzip();

// where a header's detached data file (NRRD "data file", MetaImage ElementDataFile) may be:
// anywhere the header says (a volume the user names), or only inside the folder that holds the
// header (a volume in a case folder, which is not trusted to read outside it: no absolute path,
// no "..", no symbolic link leading out; refused naming the header and the field)
enum class DataFileScope { kAnywhere, kHeaderFolder };

// by extension: .mha/.mhd (MetaImage) or .nrrd/.nhdr (NRRD)
// require_spacing: refuse a file that does not give the voxel spacing (a CT needs it; without it
// the formats default to 1 mm)
Volume read_volume(const std::string& path, bool require_spacing = false,
                   DataFileScope data_files = DataFileScope::kAnywhere);

Volume read_metaimage(const std::string& path, bool require_spacing = false,
                      DataFileScope data_files = DataFileScope::kAnywhere);
// .mha: header and data in one file; .mhd: header, data in <stem>.raw beside it
void write_metaimage(const Volume& volume, const std::string& path);

// a 3-D NRRD; a 4-D one (a sequence) is refused, naming read_nrrd_sequence
Volume read_nrrd(const std::string& path, bool require_spacing = false,
                 DataFileScope data_files = DataFileScope::kAnywhere);
// .nrrd with attached data; gzip needs zlib (throws otherwise)
void write_nrrd(const Volume& volume, const std::string& path, bool gzip = false);

// a 4-D NRRD whose 4th axis is time (cine MRI, 4-D CT): `dimension: 4`, `sizes: X Y Z T` with
// T >= 2, x fastest and time slowest in the data, the 4th `space directions` entry `none` (and
// the 4th `spacings` entry, if given, anything: NaN by the spec), `kinds` (if given) two of
// domain/space then time, list or none (also ???) last. One Volume per time index, all on the
// same grid. Refused (VolumeIoError "<file>: <field>: <what>"): a 3-D file (one volume: read_nrrd),
// a time axis with a space direction, a single frame, kinds that put time before x, y or z.
std::vector<Volume> read_nrrd_sequence(const std::string& path, bool require_spacing = false,
                                       DataFileScope data_files = DataFileScope::kAnywhere);
// frames as one 4-D .nrrd (kinds domain domain domain time, attached data); at least 2 frames, all
// valid and on frame 0's grid (dims, spacing, origin, direction, voxel type), else throws
// VolumeIoError naming the frame
void write_nrrd_sequence(const std::vector<Volume>& frames, const std::string& path, bool gzip = false);

}  // namespace pcisim::anatomy
