#pragma once
// Small text and byte helpers shared by the MetaImage and NRRD readers (internal).
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "anatomy/volume/volume.h"
#include "anatomy/volume/volume_io.h"

namespace pcisim::anatomy::io {

// the bytes of a regular file of at most max_bytes (json::read_regular_file, the one reader);
// throws VolumeIoError naming the path (a FIFO
// or device is refused unread: a FIFO would block for ever, /dev/zero never ends), and a file
// over the limit before reading it, naming its size and the limit
inline constexpr int64_t kMaxFileBytes = int64_t{8} << 30;
std::string read_file(const std::string& path, int64_t max_bytes = kMaxFileBytes);

// the bytes of the detached data file `name` a header at `header_path` names in `field` (relative
// to the header's folder, or absolute); *data_name gets the path for messages. kHeaderFolder
// refuses a name leading out of the header's folder (resolve_inside_folder) before opening it,
// and reads the resolved path. Throws VolumeIoError "<header>: <field>: <what>".
std::string read_data_file(const std::string& header_path, const std::string& name, DataFileScope scope,
                           const char* field, std::string* data_name);

// how a header says its voxels are stored, for load_voxels
struct VoxelData {
  const char* bytes = nullptr;  // the data part (after the header, or the data file's bytes)
  int64_t available = 0;
  int64_t skip = 0;  // bytes before the voxels; -1: the voxels are the last bytes
  bool compressed = false, big_endian = false;
  std::string data_name;        // the file the bytes came from, for messages
  const char* size_field = "";  // the header field naming the dimensions, for messages
  const char* skip_field = "";
  const char* compression_field = "";
};

// sizes, checks and fills vol's voxels from data: the voxel count is checked for overflow and
// against kMaxVoxels, the data's size against the count before anything is allocated, and float
// voxels must be finite. Every refusal throws VolumeIoError "<file>: <field>: <what>".
inline constexpr int64_t kMaxVoxels = int64_t{1} << 30;
void load_voxels(const std::string& path, const VoxelData& data, Volume& vol);
void write_file(const std::string& path, const std::string& header, const void* data, int64_t bytes);

std::string_view trim(std::string_view s);
std::string lower(std::string_view s);
// the file name without folders, for messages
std::string base_name(const std::string& path);
std::string folder_of(const std::string& path);

// exactly n numbers separated by spaces (or commas/parentheses when loose), else false
bool parse_doubles(std::string_view text, int n, double* out, bool loose = false);
bool parse_int64s(std::string_view text, int n, int64_t* out);

// zlib inflate of gzip or zlib data into exactly expected bytes; false on failure or no zlib
bool inflate_bytes(const char* in, int64_t in_bytes, void* out, int64_t expected_bytes, std::string* error);
bool deflate_gzip(const void* in, int64_t in_bytes, std::string* out);

}  // namespace pcisim::anatomy::io
