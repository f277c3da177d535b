#include "anatomy/dicom/dicom_series.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <sstream>
#include <vector>

#include "realtime/percentile.h"
#include "anatomy/dicom/dicom_limits.h"
#include "anatomy/dicom/dicom_precheck.h"
#include "anatomy/dicom/itk_dicom_io.h"
#include "anatomy/volume/io_text.h"
#include "json/regular_file.h"

namespace pcisim::anatomy {
namespace {

namespace fs = std::filesystem;

struct Slice {
  std::string file;
  Eigen::Vector3d position_mm;                       // ImagePositionPatient (0020,0032)
  Eigen::Vector3d row_dir, column_dir;               // ImageOrientationPatient (0020,0037)
  double row_spacing_mm = 0, column_spacing_mm = 0;  // PixelSpacing (0028,0030)
  int64_t rows = 0, columns = 0;                     // Rows (0028,0010), Columns (0028,0011)
  int64_t frames = 1;                                // NumberOfFrames (0028,0008), 1 when absent
  std::string temporal_position, trigger_time;       // (0020,0100) and (0018,1060) as written, "" when absent
  double along_normal_mm = 0;
};

// "a\b\c" as n numbers
bool parse_backslashed(const std::string& text, int n, double* out) {
  std::string s = text;
  std::replace(s.begin(), s.end(), '\\', ' ');
  std::istringstream in(s);
  for (int i = 0; i < n; ++i)
    if (!(in >> out[i]) || !std::isfinite(out[i])) return false;
  return true;
}

// the geometry tags of one file, without its pixels
Slice read_slice_header(const std::string& file) {
  std::vector<std::string> tags;
  try {
    tags = itk_io::read_tags(
        file, {"0020|0032", "0020|0037", "0028|0030", "0028|0010", "0028|0011", "0028|0008", "0020|0100", "0018|1060"});
  } catch (const DicomError&) {
    throw;  // the header walk's, naming the file and the tag
  } catch (const std::runtime_error& e) {
    throw DicomError(file + ": " + e.what());
  }
  Slice s;
  s.file = file;
  double p[3], o[6], px[2];
  if (!parse_backslashed(tags[0], 3, p))
    throw DicomError(file + ": ImagePositionPatient (0020,0032) missing or not three numbers");
  if (!parse_backslashed(tags[1], 6, o))
    throw DicomError(file + ": ImageOrientationPatient (0020,0037) missing or not six numbers");
  if (!parse_backslashed(tags[2], 2, px) || !(px[0] > 0 && px[1] > 0))
    throw DicomError(file + ": PixelSpacing (0028,0030) missing or not two positive numbers");
  double size[2], frames = 1;
  if (!parse_backslashed(tags[3], 1, &size[0]) || !parse_backslashed(tags[4], 1, &size[1]) || !(size[0] >= 1) ||
      !(size[1] >= 1) || size[0] > 65535 || size[1] > 65535 || size[0] != std::floor(size[0]) ||
      size[1] != std::floor(size[1]))
    throw DicomError(file + ": Rows (0028,0010) or Columns (0028,0011) missing or not a whole number in 1..65535");
  if (!tags[5].empty() && (!parse_backslashed(tags[5], 1, &frames) || !(frames >= 1) || frames > 1e9))
    throw DicomError(file + ": NumberOfFrames (0028,0008) not a positive number");
  s.rows = static_cast<int64_t>(size[0]);
  s.columns = static_cast<int64_t>(size[1]);
  s.frames = static_cast<int64_t>(frames);
  s.temporal_position = tags[6];
  s.trigger_time = tags[7];
  s.position_mm = {p[0], p[1], p[2]};
  s.row_dir = Eigen::Vector3d(o[0], o[1], o[2]).normalized();
  s.column_dir = Eigen::Vector3d(o[3], o[4], o[5]).normalized();
  s.row_spacing_mm = px[0];     // between rows: along the column direction
  s.column_spacing_mm = px[1];  // between columns: along the row direction
  return s;
}

std::string name_of(const std::string& file) {
  return fs::path(file).filename().string();
}

// the series' voxel count from the headers, refused over the volume readers' cap before ITK
// allocates anything (a header may claim 65535 x 65535 pixels)
void check_size(const std::vector<Slice>& slices, const std::string& where) {
  const Slice& first = slices.front();
  int64_t frames = 0;
  for (const auto& s : slices) {
    if (s.rows != first.rows || s.columns != first.columns)
      throw DicomError(fmt::format("{}: {} rows x {} columns, {} has {} x {}", s.file, s.rows, s.columns,
                                   name_of(first.file), first.rows, first.columns));
    frames += s.frames;  // at most 1e9 each: no overflow
  }
  const int64_t plane = first.rows * first.columns;  // at most 65535^2
  if (frames > io::kMaxVoxels / plane)
    throw DicomError(fmt::format("{}: {} rows x {} columns x {} slices = {} voxels, over the {} voxel limit", where,
                                 first.rows, first.columns, frames, plane * frames, io::kMaxVoxels));
}

// every slice like the first, stacked along its normal at one spacing; sorts them along the normal
// and returns that spacing. `where` names the stack in messages about it as a whole (the folder,
// or the folder and a cine's temporal position); a slice's own problem names its file
double check_stack(std::vector<Slice>& slices, const std::string& where) {
  const Slice& first = slices.front();
  const Eigen::Vector3d normal = first.row_dir.cross(first.column_dir);
  if (std::abs(first.row_dir.dot(first.column_dir)) > 1e-3 || normal.norm() < 0.99)
    throw DicomError(first.file +
                     ": ImageOrientationPatient: row and column directions are not orthogonal unit vectors");
  for (auto& s : slices) {
    if ((s.row_dir - first.row_dir).norm() > 1e-4 || (s.column_dir - first.column_dir).norm() > 1e-4)
      throw DicomError(s.file + ": ImageOrientationPatient differs from " + name_of(first.file) + "'s");
    if (std::abs(s.row_spacing_mm - first.row_spacing_mm) > 1e-4 * first.row_spacing_mm ||
        std::abs(s.column_spacing_mm - first.column_spacing_mm) > 1e-4 * first.column_spacing_mm)
      throw DicomError(s.file + ": PixelSpacing differs from " + name_of(first.file) + "'s");
    s.along_normal_mm = normal.dot(s.position_mm);
  }
  std::sort(slices.begin(), slices.end(),
            [](const Slice& a, const Slice& b) { return a.along_normal_mm < b.along_normal_mm; });
  std::vector<double> gaps;
  for (size_t i = 1; i < slices.size(); ++i) gaps.push_back(slices[i].along_normal_mm - slices[i - 1].along_normal_mm);
  std::vector<double> sorted = gaps;
  const double spacing = realtime::upper_median_in_place(std::span<double>(sorted));
  if (!(spacing > dicom::kMinSpacingMm))
    throw DicomError(where + ": slices share positions (spacing " + fmt::format("{:.3f}", spacing) + " mm)");
  // positions are bounded (dicom_limits.h), so the spacing is finite; a voxel this deep is no CT
  if (spacing > dicom::kMaxSpacingMm)
    throw DicomError(
        fmt::format("{}: slice spacing {:g} mm, over the {:g} mm limit", where, spacing, dicom::kMaxSpacingMm));
  const double tolerance = std::max(0.01 * spacing, 0.01);
  for (size_t i = 0; i < gaps.size(); ++i) {
    if (std::abs(gaps[i] - spacing) > tolerance)
      throw DicomError(
          fmt::format("{}: gap of {:.2f} mm after the previous slice ({}), the series' spacing is {:.2f} mm "
                      "(a missing slice or uneven spacing)",
                      slices[i + 1].file, gaps[i], name_of(slices[i].file), spacing));
    // stacked straight along the normal (no gantry tilt: a sheared grid is not a Volume)
    const Eigen::Vector3d offset = slices[i + 1].position_mm - first.position_mm;
    if ((offset - normal * normal.dot(offset)).norm() > tolerance)
      throw DicomError(slices[i + 1].file + ": not stacked along the slice normal (gantry tilt or a shifted slice)");
  }
  return spacing;
}

// the grid of a sorted, checked stack (check_stack), without voxels
Volume grid_of(const std::vector<Slice>& sorted, double slice_spacing_mm) {
  const Slice& first = sorted.front();
  Volume v;
  v.dims = {first.columns, first.rows, int64_t(sorted.size())};
  v.spacing_mm = {first.column_spacing_mm, first.row_spacing_mm, slice_spacing_mm};
  v.origin_mm = first.position_mm;
  v.direction.col(0) = first.row_dir;
  v.direction.col(1) = first.column_dir;
  v.direction.col(2) = first.row_dir.cross(first.column_dir);
  return v;
}

// the voxels of a sorted, checked stack into `v` (from grid_of), rescale slope and intercept
// applied by the IO; int16 when every value fits, else float32
void read_stack_voxels(const std::vector<Slice>& sorted, const std::string& where, Volume& v) {
  std::vector<std::string> ordered;
  for (const auto& s : sorted) ordered.push_back(s.file);
  const Slice& first = sorted.front();
  // converted straight from ITK's image: at most ITK's floats and the volume's voxels at once
  itk_io::read_voxels(ordered, [&](const std::array<int64_t, 3>& dims, const float* px) {
    if (dims[2] != int64_t(sorted.size()))
      throw DicomError(fmt::format("{}: {} slices read from {} files (multi-frame files are not supported)", where,
                                   dims[2], sorted.size()));
    if (dims[0] != first.columns || dims[1] != first.rows)
      throw DicomError(fmt::format("{}: {} x {} pixels read, the headers say {} columns x {} rows", where, dims[0],
                                   dims[1], first.columns, first.rows));
    v.dims = dims;
    const int64_t n = v.voxel_count();
    bool fits_int16 = true;
    for (int64_t i = 0; i < n && fits_int16; ++i)
      fits_int16 = px[i] == std::round(px[i]) && px[i] >= -32768.f && px[i] <= 32767.f;
    v.type = fits_int16 ? VoxelType::kInt16 : VoxelType::kFloat32;
    if (fits_int16) {
      v.hu_i16.resize(n);
      for (int64_t i = 0; i < n; ++i) v.hu_i16[i] = static_cast<int16_t>(px[i]);
    } else {
      v.hu_f32.assign(px, px + n);
    }
  });
  if (const std::string why = validate(v); !why.empty()) throw DicomError(where + ": " + why);
}

// runs `f`, ITK's errors (runtime_error) becoming DicomError "<folder>: <what>"
template <class F>
auto naming_folder(const std::string& folder, F&& f) {
  try {
    return f();
  } catch (const DicomError&) {
    throw;
  } catch (const std::runtime_error& e) {
    throw DicomError(folder + ": " + e.what());
  }
}

// the image files of each series in `folder`, by SeriesInstanceUID, every one through the header
// walk (dicom_precheck.h) before GDCM may see it: a file without the preamble and "DICM" is a
// stray file (a README, a thumbnail) and skipped, as is a DICOMDIR and anything not a regular file
// (a subfolder, a FIFO: never opened); a file that fails the walk refuses the series, naming it.
// A symbolic link is followed only to a file inside the folder.
std::map<std::string, std::vector<std::string>> series_in(const std::string& folder) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) throw DicomError(folder + ": not a folder");
  std::vector<fs::path> paths;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    if (int64_t(paths.size()) == dicom::kMaxFolderFiles)
      throw DicomError(fmt::format("{}: more than {} files in the folder", folder, dicom::kMaxFolderFiles));
    paths.push_back(it->path());
  }
  if (ec) throw DicomError(folder + ": cannot list the folder: " + ec.message());
  std::sort(paths.begin(), paths.end());
  const fs::path inside = fs::weakly_canonical(folder, ec);
  std::map<std::string, std::vector<std::string>> series;
  for (const fs::path& p : paths) {
    const std::string file = p.string();
    if (!fs::is_regular_file(p, ec)) continue;
    if (fs::is_symlink(p, ec)) {
      const fs::path target = fs::weakly_canonical(p, ec);
      if (ec || target.parent_path() != inside)
        throw DicomError(file + ": a symbolic link to a file outside the folder (" + target.string() + ")");
    }
    // a stray file (a README, a thumbnail, a 4 GB video) is skipped on its first 132 bytes
    std::string bytes;
    try {
      if (!dicom::has_dicom_magic(json::read_regular_file_head(file, "the DICOM file", 132))) continue;
      bytes = json::read_regular_file(file, "the DICOM file", dicom::kMaxFileBytes);
    } catch (const json::FileError& e) {
      throw DicomError(e.what());
    }
    if (!dicom::has_dicom_magic(bytes)) continue;
    const dicom::CheckedFile checked = dicom::precheck_dicom(file, bytes);
    if (checked.dicomdir) continue;
    if (checked.series_uid.empty()) throw DicomError(file + ": SeriesInstanceUID (0020,000E): missing");
    series[checked.series_uid].push_back(file);
  }
  return series;
}

// the files of the one series in `folder` (or of series_uid), in name order; `uid_out` gets its UID
std::vector<std::string> series_files_of(const std::string& folder, const std::string& series_uid,
                                         std::string& uid_out) {
  std::map<std::string, std::vector<std::string>> series = series_in(folder);
  std::vector<std::string> uids;
  for (const auto& [uid, files] : series) uids.push_back(uid);
  if (uids.empty()) throw DicomError(folder + ": no DICOM series found");
  std::string uid = series_uid;
  if (uid.empty()) {
    if (uids.size() > 1)
      throw DicomError(fmt::format("{}: {} series found ({}): name one", folder, uids.size(), fmt::join(uids, ", ")));
    uid = uids.front();
  } else if (series.count(uid) == 0) {
    throw DicomError(fmt::format("{}: no series {} (found: {})", folder, uid, fmt::join(uids, ", ")));
  }
  uid_out = uid;
  return series[uid];
}

// geometry first, from every file's own tags
std::vector<Slice> headers_of(const std::vector<std::string>& files) {
  std::vector<Slice> slices;
  for (const auto& f : files) slices.push_back(read_slice_header(f));
  return slices;
}

std::string point_text(const Eigen::Vector3d& p) {
  return fmt::format("({:.3f}, {:.3f}, {:.3f})", p.x(), p.y(), p.z());
}

}  // namespace

Volume read_dicom_series(const std::string& folder, const std::string& series_uid) {
  return naming_folder(folder, [&] {
    std::string uid;
    const std::vector<std::string> files = series_files_of(folder, series_uid, uid);
    if (files.size() < 2)
      throw DicomError(fmt::format("{}: series {} has {} slice(s), a CT needs at least 2", folder, uid, files.size()));
    std::vector<Slice> slices = headers_of(files);
    check_size(slices, folder);
    const double slice_spacing_mm = check_stack(slices, folder);
    // then the voxels, in that order
    Volume v = grid_of(slices, slice_spacing_mm);
    read_stack_voxels(slices, folder, v);
    return v;
  });
}

std::vector<Volume> read_dicom_cine(const std::string& folder, const std::string& series_uid) {
  return naming_folder(folder, [&] {
    std::string uid;
    const std::vector<std::string> files = series_files_of(folder, series_uid, uid);
    if (files.empty()) throw DicomError(fmt::format("{}: series {} has no images", folder, uid));
    std::vector<Slice> slices = headers_of(files);
    // every image the same size, the whole sequence under the volume readers' cap
    check_size(slices, folder);

    // the time key: Temporal Position Identifier when the files give it, else Trigger Time; a
    // key some files give and others lack is refused naming a file without it
    const bool by_position =
        std::any_of(slices.begin(), slices.end(), [](const Slice& s) { return !s.temporal_position.empty(); });
    const bool by_trigger = !by_position && std::any_of(slices.begin(), slices.end(),
                                                        [](const Slice& s) { return !s.trigger_time.empty(); });
    if (!by_position && !by_trigger)
      throw DicomError(folder +
                       ": one time point: a 3-D series, not a cine (no file gives a Temporal Position Identifier "
                       "(0020,0100) or Trigger Time (0018,1060))");
    const char* tag_name = by_position ? "Temporal Position Identifier (0020,0100)" : "Trigger Time (0018,1060)";
    std::map<double, std::vector<Slice>> groups;
    for (auto& s : slices) {
      const std::string& text = by_position ? s.temporal_position : s.trigger_time;
      double key = 0;
      if (text.empty())
        throw DicomError(fmt::format("{}: no {}, which other files of the series give", s.file, tag_name));
      if (!parse_backslashed(text, 1, &key))
        throw DicomError(fmt::format("{}: {} '{}' is not a number", s.file, tag_name, text));
      groups[key].push_back(std::move(s));
    }
    auto label = [&](double key) {
      return by_position ? fmt::format("temporal position {:g}", key) : fmt::format("trigger time {:g} ms", key);
    };
    if (groups.size() < 2)
      throw DicomError(fmt::format("{}: one time point: a 3-D series, not a cine (every file has {} {})", folder,
                                   tag_name, groups.begin()->first));

    // each time point's stack, checked, and its grid against the first's before any voxel is read
    const double key0 = groups.begin()->first;
    std::vector<Slice>& first_stack = groups.begin()->second;
    if (first_stack.size() < 2)
      throw DicomError(fmt::format("{}: {}: {} slice: a 2-D cine, a frame of 3-D + time needs at least 2", folder,
                                   label(key0), first_stack.size()));
    std::vector<Volume> frames;
    for (auto& [key, stack] : groups) {
      const std::string where = folder + ": " + label(key);
      if (stack.size() != first_stack.size())
        throw DicomError(fmt::format("{}: {} slices, {} has {} (a missing or extra slice)", where, stack.size(),
                                     label(key0), first_stack.size()));
      const double slice_spacing_mm = check_stack(stack, where);
      Volume grid = grid_of(stack, slice_spacing_mm);
      if (!frames.empty()) {
        const Volume& g0 = frames.front();
        const Slice &s0 = first_stack.front(), &s = stack.front();
        if ((grid.direction - g0.direction).norm() > 1e-4)
          throw DicomError(fmt::format("{}: ImageOrientationPatient ({}) differs from {}'s ({})", where,
                                       name_of(s.file), label(key0), name_of(s0.file)));
        if ((grid.spacing_mm.head<2>() - g0.spacing_mm.head<2>()).norm() > 1e-4 * g0.spacing_mm.head<2>().norm())
          throw DicomError(fmt::format("{}: PixelSpacing {:g} x {:g} mm ({}) differs from {}'s {:g} x {:g} mm", where,
                                       s.row_spacing_mm, s.column_spacing_mm, name_of(s.file), label(key0),
                                       s0.row_spacing_mm, s0.column_spacing_mm));
        if (std::abs(grid.spacing_mm.z() - g0.spacing_mm.z()) > 1e-4 * g0.spacing_mm.z())
          throw DicomError(fmt::format("{}: slice spacing {:.3f} mm differs from {}'s {:.3f} mm", where,
                                       grid.spacing_mm.z(), label(key0), g0.spacing_mm.z()));
        if ((grid.origin_mm - g0.origin_mm).norm() > std::max(0.01 * g0.spacing_mm.z(), 0.01))
          throw DicomError(fmt::format(
              "{}: ImagePositionPatient of its first slice ({}) is {} mm, {}'s ({}) is {} mm (the slices moved)", where,
              name_of(s.file), point_text(grid.origin_mm), label(key0), name_of(s0.file), point_text(g0.origin_mm)));
      }
      frames.push_back(std::move(grid));
    }

    // then the voxels, frame by frame in time order
    size_t f = 0;
    for (auto& [key, stack] : groups) read_stack_voxels(stack, folder + ": " + label(key), frames[f++]);
    // one voxel type for the whole sequence: float32 if any frame needs it
    if (std::any_of(frames.begin(), frames.end(), [](const Volume& v) { return v.type == VoxelType::kFloat32; }))
      for (auto& v : frames)
        if (v.type == VoxelType::kInt16) {
          v.hu_f32.assign(v.hu_i16.begin(), v.hu_i16.end());
          v.hu_i16 = {};
          v.type = VoxelType::kFloat32;
        }
    return frames;
  });
}

}  // namespace pcisim::anatomy
