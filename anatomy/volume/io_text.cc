#include "anatomy/volume/io_text.h"

#include <cctype>
#include <charconv>
#include <cstring>
#include <fstream>
#include <sstream>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include "anatomy/volume/inside_folder.h"
#include "anatomy/volume/volume_io.h"
#include "json/regular_file.h"

#ifdef PCISIM_ANATOMY_HAVE_ZLIB
#include <zlib.h>
#endif

namespace pcisim::anatomy::io {

std::string read_file(const std::string& path, int64_t max_bytes) {
  try {
    return json::read_regular_file(path, "the file", max_bytes);
  } catch (const json::FileError& e) {
    throw VolumeIoError(e.what());
  }
}

std::string read_data_file(const std::string& header_path, const std::string& name, DataFileScope scope,
                           const char* field, std::string* data_name) {
  *data_name = !name.empty() && name.front() == '/' ? name : folder_of(header_path) + name;
  std::string open_path = *data_name;
  if (scope == DataFileScope::kHeaderFolder) {
    const InsideFolder inside = resolve_inside_folder(folder_of(header_path), name);
    if (inside.escape != FolderEscape::kNone)
      throw VolumeIoError(
          fmt::format("{}: {}: '{}' {} (a volume in a case folder reads its data only from the "
                      "folder that holds its header)",
                      base_name(header_path), field, escaped_name(name), inside.why));
    open_path = inside.resolved;  // what was checked is what is opened
  }
  try {
    return read_file(open_path);
  } catch (const VolumeIoError& e) {
    throw VolumeIoError(fmt::format("{}: {}: cannot open '{}' ({})", base_name(header_path), field,
                                    escaped_name(*data_name), e.what()));
  }
}

void load_voxels(const std::string& path, const VoxelData& d, Volume& vol) {
  auto fail = [&](const char* field, const std::string& what) {
    throw VolumeIoError(fmt::format("{}: {}: {}", base_name(path), field, what));
  };
  // the count, checked before any product can overflow
  int64_t count = 1;
  for (const int64_t n : vol.dims) {
    if (n <= 0 || n > kMaxVoxels || count > kMaxVoxels / n)
      fail(d.size_field, fmt::format("{} x {} x {} voxels: over the {} voxel limit", vol.dims[0], vol.dims[1],
                                     vol.dims[2], kMaxVoxels));
    count *= n;
  }
  const int64_t expected = count * voxel_type_bytes(vol.type);
  const char* bytes = d.bytes;
  int64_t available = d.available;
  if (d.skip == -1) {
    if (available < expected)
      fail(d.skip_field, fmt::format("-1 but the data holds {} bytes, fewer than {}", available, expected));
    bytes += available - expected;
    available = expected;
  } else if (d.skip > 0) {
    if (d.skip > available) fail(d.skip_field, fmt::format("{} exceeds the data's {} bytes", d.skip, available));
    bytes += d.skip;
    available -= d.skip;
  }
  // sizes agree before anything is allocated: raw data exactly, compressed data within deflate's
  // best ratio (about 1032:1, RFC 1951's longest match per bit pattern)
  if (!d.compressed && available != expected)
    fail(d.size_field,
         fmt::format("{}x{}x{} {} voxels need {} bytes but the data ({}) holds {}", vol.dims[0], vol.dims[1],
                     vol.dims[2], voxel_type_name(vol.type), expected, base_name(d.data_name), available));
  if (d.compressed && available * 1032 < expected)
    fail(d.size_field, fmt::format("{} voxel bytes cannot come from {} compressed bytes", expected, available));
  if (vol.type == VoxelType::kInt16) {
    vol.hu_i16.assign(static_cast<size_t>(count), 0);
  } else {
    vol.hu_f32.assign(static_cast<size_t>(count), 0.0f);
  }
  if (d.compressed) {
    std::string error;
    if (!inflate_bytes(bytes, available, vol.data(), expected, &error)) fail(d.compression_field, "gzip: " + error);
  } else {
    std::memcpy(vol.data(), bytes, static_cast<size_t>(expected));
  }
  if (d.big_endian) {
    auto* p = static_cast<char*>(vol.data());
    const int b = voxel_type_bytes(vol.type);
    for (int64_t n = 0; n < count; ++n, p += b) std::reverse(p, p + b);
  }
  // a NaN or infinite voxel would make every ray through it NaN
  if (vol.type == VoxelType::kFloat32) {
    for (int64_t n = 0; n < count; ++n) {
      if (!std::isfinite(vol.hu_f32[static_cast<size_t>(n)])) {
        const int64_t i = n % vol.dims[0], j = n / vol.dims[0] % vol.dims[1], k = n / (vol.dims[0] * vol.dims[1]);
        fail("voxels", fmt::format("voxel ({}, {}, {}) is {}: every voxel must be a finite HU value", i, j, k,
                                   vol.hu_f32[static_cast<size_t>(n)]));
      }
    }
  }
}

void write_file(const std::string& path, const std::string& header, const void* data, int64_t bytes) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw VolumeIoError(path + ": cannot open the file for writing");
  out.write(header.data(), static_cast<std::streamsize>(header.size()));
  out.write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
  if (!out) throw VolumeIoError(path + ": write failed");
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string base_name(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

std::string folder_of(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

namespace {
std::vector<std::string_view> tokens(std::string_view text, bool loose) {
  std::vector<std::string_view> out;
  size_t i = 0;
  auto sep = [loose](char c) {
    return std::isspace(static_cast<unsigned char>(c)) || (loose && (c == ',' || c == '(' || c == ')'));
  };
  while (i < text.size()) {
    while (i < text.size() && sep(text[i])) ++i;
    const size_t start = i;
    while (i < text.size() && !sep(text[i])) ++i;
    if (i > start) out.push_back(text.substr(start, i - start));
  }
  return out;
}
}  // namespace

bool parse_doubles(std::string_view text, int n, double* out, bool loose) {
  const auto t = tokens(text, loose);
  if (static_cast<int>(t.size()) != n) return false;
  for (int a = 0; a < n; ++a) {
    // strtod accepts what from_chars does plus a leading '+'; the token is copied to end it
    const std::string s(t[a]);
    char* end = nullptr;
    out[a] = std::strtod(s.c_str(), &end);
    if (end != s.c_str() + s.size()) return false;
  }
  return true;
}

bool parse_int64s(std::string_view text, int n, int64_t* out) {
  const auto t = tokens(text, false);
  if (static_cast<int>(t.size()) != n) return false;
  for (int a = 0; a < n; ++a) {
    const auto r = std::from_chars(t[a].data(), t[a].data() + t[a].size(), out[a]);
    if (r.ec != std::errc() || r.ptr != t[a].data() + t[a].size()) return false;
  }
  return true;
}

bool inflate_bytes(const char* in, int64_t in_bytes, void* out, int64_t expected_bytes, std::string* error) {
#ifdef PCISIM_ANATOMY_HAVE_ZLIB
  z_stream zs{};
  // 15 + 32: accept a zlib or a gzip header
  if (inflateInit2(&zs, 15 + 32) != Z_OK) {
    *error = "zlib inflateInit2 failed";
    return false;
  }
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in));
  zs.avail_in = static_cast<uInt>(in_bytes);
  zs.next_out = static_cast<Bytef*>(out);
  zs.avail_out = static_cast<uInt>(expected_bytes);
  const int rc = inflate(&zs, Z_FINISH);
  const int64_t produced = expected_bytes - zs.avail_out;
  inflateEnd(&zs);
  if (rc != Z_STREAM_END) {
    *error = rc == Z_BUF_ERROR && zs.avail_out == 0
                 ? "compressed data holds more than the header's sizes"
                 : "corrupt or truncated compressed data (" + std::to_string(produced) + " of " +
                       std::to_string(expected_bytes) + " bytes inflated)";
    return false;
  }
  if (produced != expected_bytes) {
    *error = "compressed data inflates to " + std::to_string(produced) + " bytes, expected " +
             std::to_string(expected_bytes);
    return false;
  }
  return true;
#else
  (void)in, (void)in_bytes, (void)out, (void)expected_bytes;
  *error = "this build has no zlib, so compressed data cannot be read";
  return false;
#endif
}

bool deflate_gzip(const void* in, int64_t in_bytes, std::string* out) {
#ifdef PCISIM_ANATOMY_HAVE_ZLIB
  z_stream zs{};
  if (deflateInit2(&zs, Z_DEFAULT_COMPRESSION, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) {
    return false;
  }
  out->resize(deflateBound(&zs, static_cast<uLong>(in_bytes)) + 64);
  zs.next_in = static_cast<Bytef*>(const_cast<void*>(in));
  zs.avail_in = static_cast<uInt>(in_bytes);
  zs.next_out = reinterpret_cast<Bytef*>(out->data());
  zs.avail_out = static_cast<uInt>(out->size());
  const int rc = deflate(&zs, Z_FINISH);
  out->resize(zs.total_out);
  deflateEnd(&zs);
  return rc == Z_STREAM_END;
#else
  (void)in, (void)in_bytes, (void)out;
  return false;
#endif
}

}  // namespace pcisim::anatomy::io
