#pragma once
// Small text and byte helpers shared by the MetaImage and NRRD readers (internal).
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace pcisim::xray::io {

// the file's bytes; throws VolumeIoError("<path>: cannot open ...")
std::string read_file(const std::string& path);
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
bool inflate_bytes(const char* in, int64_t in_bytes, void* out, int64_t expected_bytes,
                   std::string* error);
bool deflate_gzip(const void* in, int64_t in_bytes, std::string* out);

}  // namespace pcisim::xray::io
