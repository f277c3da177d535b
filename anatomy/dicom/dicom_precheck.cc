#include "anatomy/dicom/dicom_precheck.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "anatomy/dicom/dicom_limits.h"
#include "json/regular_file.h"

namespace pcisim::anatomy::dicom {
namespace {

constexpr uint32_t kGroupLength = 0x00020000, kMediaStorage = 0x00020002, kTransferSyntax = 0x00020010;
constexpr uint32_t kItem = 0xFFFEE000, kItemEnd = 0xFFFEE00D, kSequenceEnd = 0xFFFEE0DD;
constexpr uint32_t kPixelData = 0x7FE00010, kSeriesUid = 0x0020000E;
constexpr uint32_t kUndefined = 0xFFFFFFFF;
constexpr const char* kImplicitLe = "1.2.840.10008.1.2";
constexpr const char* kExplicitLe = "1.2.840.10008.1.2.1";
constexpr const char* kDicomdir = "1.2.840.10008.1.3.10";

// the names in messages: the tags this walk looks at, and those users see most
struct Named {
  uint32_t tag;
  const char* keyword;
};
constexpr Named kNames[] = {
    {0x00020000, "FileMetaInformationGroupLength"},
    {0x00020001, "FileMetaInformationVersion"},
    {0x00020002, "MediaStorageSOPClassUID"},
    {0x00020003, "MediaStorageSOPInstanceUID"},
    {0x00020010, "TransferSyntaxUID"},
    {0x00020012, "ImplementationClassUID"},
    {0x00020013, "ImplementationVersionName"},
    {0x00080010, "RecognitionCode"},
    {0x00080016, "SOPClassUID"},
    {0x00080018, "SOPInstanceUID"},
    {0x00080060, "Modality"},
    {0x00100010, "PatientName"},
    {0x00180050, "SliceThickness"},
    {0x00180088, "SpacingBetweenSlices"},
    {0x00181060, "TriggerTime"},
    {0x0020000D, "StudyInstanceUID"},
    {0x0020000E, "SeriesInstanceUID"},
    {0x00200013, "InstanceNumber"},
    {0x00200032, "ImagePositionPatient"},
    {0x00200037, "ImageOrientationPatient"},
    {0x00200100, "TemporalPositionIdentifier"},
    {0x00280002, "SamplesPerPixel"},
    {0x00280004, "PhotometricInterpretation"},
    {0x00280005, "ImageDimensions"},
    {0x00280006, "PlanarConfiguration"},
    {0x00280008, "NumberOfFrames"},
    {0x00280010, "Rows"},
    {0x00280011, "Columns"},
    {0x00280012, "Planes"},
    {0x00280030, "PixelSpacing"},
    {0x00280100, "BitsAllocated"},
    {0x00280101, "BitsStored"},
    {0x00280102, "HighBit"},
    {0x00280103, "PixelRepresentation"},
    {0x00281052, "RescaleIntercept"},
    {0x00281053, "RescaleSlope"},
    {0x00283000, "ModalityLUTSequence"},
    {0x00283006, "LUTData"},
    {0x00880200, "IconImageSequence"},
    {0x7FE00010, "PixelData"},
    {0xFFFEE000, "Item"},
    {0xFFFEE00D, "ItemDelimitationItem"},
    {0xFFFEE0DD, "SequenceDelimitationItem"},
};

std::string tag_text(uint32_t tag) {
  const std::string code = fmt::format("({:04X},{:04X})", tag >> 16, tag & 0xFFFF);
  for (const Named& n : kNames)
    if (n.tag == tag) return std::string(n.keyword) + " " + code;
  return code;
}

// the transfer syntaxes a user may meet, named when refused
struct Syntax {
  const char* uid;
  const char* name;
};
constexpr Syntax kSyntaxes[] = {
    {"1.2.840.10008.1.2.2", "Explicit VR Big Endian"},
    {"1.2.840.10008.1.2.1.99", "Deflated Explicit VR Little Endian"},
    {"1.2.840.10008.1.2.4.50", "JPEG Baseline (Process 1)"},
    {"1.2.840.10008.1.2.4.51", "JPEG Extended (Process 2 & 4)"},
    {"1.2.840.10008.1.2.4.57", "JPEG Lossless, Non-Hierarchical (Process 14)"},
    {"1.2.840.10008.1.2.4.70", "JPEG Lossless, First-Order Prediction (Process 14, SV1)"},
    {"1.2.840.10008.1.2.4.80", "JPEG-LS Lossless Image Compression"},
    {"1.2.840.10008.1.2.4.81", "JPEG-LS Lossy (Near-Lossless) Image Compression"},
    {"1.2.840.10008.1.2.4.90", "JPEG 2000 Image Compression (Lossless Only)"},
    {"1.2.840.10008.1.2.4.91", "JPEG 2000 Image Compression"},
    {"1.2.840.10008.1.2.4.100", "MPEG2 Main Profile / Main Level"},
    {"1.2.840.10008.1.2.4.102", "MPEG-4 AVC/H.264 High Profile / Level 4.1"},
    {"1.2.840.10008.1.2.4.201", "High-Throughput JPEG 2000 Image Compression (Lossless Only)"},
    {"1.2.840.10008.1.2.5", "RLE Lossless"},
};

// the images read: CT, MR, secondary capture (the enhanced multi-frame classes are not: GDCM takes
// their geometry from nested functional groups, and the series reader reads one frame a file)
constexpr const char* kImageClasses[] = {"1.2.840.10008.5.1.4.1.1.2", "1.2.840.10008.5.1.4.1.1.4",
                                         "1.2.840.10008.5.1.4.1.1.7"};

// the elements GDCM reads through gdcm::Attribute (which asserts that an explicit VR matches its
// dictionary's, and reads a binary value as the dictionary's type): their VR and, for binary
// values of one value, their length (0: any)
struct Typed {
  uint32_t tag;
  const char* vr;
  uint32_t length;
};
constexpr Typed kTyped[] = {
    {0x00080016, "UI", 0}, {0x00080100, "SH", 0}, {0x00080104, "LO", 0}, {0x00180050, "DS", 0}, {0x00180088, "DS", 0},
    {0x00181063, "DS", 0}, {0x0018602C, "FD", 8}, {0x0018602E, "FD", 8}, {0x0020000E, "UI", 0}, {0x00200030, "DS", 0},
    {0x00200032, "DS", 0}, {0x00200035, "DS", 0}, {0x00200037, "DS", 0}, {0x00280002, "US", 2}, {0x00280004, "CS", 0},
    {0x00280006, "US", 2}, {0x00280008, "IS", 0}, {0x00280009, "AT", 0}, {0x00280010, "US", 2}, {0x00280011, "US", 2},
    {0x00280030, "DS", 0}, {0x00280100, "US", 2}, {0x00280101, "US", 2}, {0x00280102, "US", 2}, {0x00280103, "US", 2},
    {0x00281052, "DS", 0}, {0x00281053, "DS", 0}, {0x00281054, "LO", 0}, {0x00282110, "CS", 0}, {0x00409224, "FD", 8},
    {0x00409225, "FD", 8}, {0x00480006, "UL", 4}, {0x00480007, "UL", 4}, {0x3004000C, "DS", 0}, {0x3004000E, "DS", 0},
};

// explicit VRs; those with a 4-byte length after two reserved bytes are long
constexpr const char* kShortVrs[] = {"AE", "AS", "AT", "CS", "DA", "DS", "DT", "FL", "FD", "IS", "LO",
                                     "LT", "PN", "SH", "SL", "SS", "ST", "TM", "UI", "UL", "US"};
// (OV, SV and UV, added to DICOM in 2019, are left out: unknown to older readers)
constexpr const char* kLongVrs[] = {"OB", "OD", "OF", "OL", "OW", "SQ", "UC", "UN", "UR", "UT"};

bool in(std::string_view s, std::initializer_list<const char*> list) {
  return std::any_of(list.begin(), list.end(), [&](const char* x) { return s == x; });
}
template <size_t N>
bool in(std::string_view s, const char* const (&list)[N]) {
  return std::any_of(std::begin(list), std::end(list), [&](const char* x) { return s == x; });
}

// the size of one value of a binary VR, 0 for the others
int value_size(std::string_view vr) {
  if (in(vr, {"SS", "US", "OW"})) return 2;
  if (in(vr, {"AT", "FL", "SL", "UL", "OF", "OL"})) return 4;
  if (in(vr, {"FD", "OD"})) return 8;
  return 0;
}

// a text value without its padding (trailing spaces and NULs, leading spaces)
std::string_view trimmed(std::string_view s) {
  while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.remove_suffix(1);
  while (!s.empty() && s.front() == ' ') s.remove_prefix(1);
  return s;
}

// "a\b\c" as exactly n finite numbers (DS or IS text), else false
bool parse_numbers(std::string_view text, size_t n, double* out) {
  size_t count = 0;
  while (true) {
    const size_t cut = text.find('\\');
    std::string_view part = trimmed(text.substr(0, cut));
    if (!part.empty() && part.front() == '+') part.remove_prefix(1);
    if (count == n || part.empty()) return false;
    const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), out[count]);
    if (ec != std::errc() || end != part.data() + part.size() || !std::isfinite(out[count])) return false;
    ++count;
    if (cut == std::string_view::npos) break;
    text.remove_prefix(cut + 1);
  }
  return count == n;
}

std::string printable(std::string_view s) {
  std::string out;
  for (const char c : s.substr(0, 64))
    out += (c >= 32 && c < 127) ? std::string(1, c) : fmt::format("\\x{:02x}", uint8_t(c));
  return s.size() > 64 ? out + "..." : out;
}

class Walker {
 public:
  Walker(const std::string& file, std::string_view bytes) : file_(file), b_(bytes) {}

  CheckedFile run() {
    if (!has_dicom_magic(b_)) throw DicomError(file_ + ": not a DICOM file (no \"DICM\" after a 128-byte preamble)");
    const size_t meta_at = meta_group();
    const bool explicit_vr = out_.transfer_syntax_uid == kExplicitLe;
    data_set(meta_at, b_.size(), explicit_vr, 0, false, true);
    if (!out_.dicomdir && !seen_sop_class_) fail(0x00080016, "missing");
    if (!out_.dicomdir && !has_pixels_) fail(kPixelData, "missing (the file holds no image)");
    return out_;
  }

 private:
  [[noreturn]] void fail(uint32_t tag, const std::string& what) const {
    throw DicomError(fmt::format("{}: {}: {}", file_, tag_text(tag), what));
  }
  uint16_t u16(size_t at) const { return uint16_t(uint8_t(b_[at]) | uint8_t(b_[at + 1]) << 8); }
  uint32_t u32(size_t at) const { return uint32_t(u16(at)) | uint32_t(u16(at + 2)) << 16; }
  uint32_t tag_at(size_t at) const { return uint32_t(u16(at)) << 16 | u16(at + 2); }
  std::string past_end(uint64_t length, size_t left, size_t end) const {
    return fmt::format("length {} runs past the end of {} ({} bytes left)", length,
                       end == b_.size() ? "the file" : "its item or sequence", left);
  }

  // the File Meta group: explicit VR little endian, (0002,0000) first and counting the rest
  // exactly; returns where the data set starts
  size_t meta_group() {
    const size_t at = 132;
    if (b_.size() == at) fail(kGroupLength, "missing (the file ends after the preamble)");
    if (b_.size() - at < 12 || tag_at(at) != kGroupLength || b_.substr(at + 4, 2) != "UL" || u16(at + 6) != 4)
      fail(kGroupLength, "missing or not UL of 4 bytes (the File Meta group must start with it)");
    const uint32_t length = u32(at + 8);
    const size_t start = at + 12;
    if (length > b_.size() - start)
      fail(kGroupLength, fmt::format("{}, but the file has {} bytes after it", length, b_.size() - start));
    meta_ = true;
    data_set(start, start + length, true, 0, false, true);
    meta_ = false;
    if (start + length < b_.size() - 3 && u16(start + length) == 0x0002)
      fail(kGroupLength, fmt::format("{}, but the File Meta group goes on after that many bytes", length));
    if (out_.transfer_syntax_uid.empty()) fail(kTransferSyntax, "missing");
    if (!seen_media_storage_) fail(kMediaStorage, "missing");
    return start + length;
  }

  // a data set from `at` to `end` (the file, an item, a defined-length sequence); with
  // `undefined_item`, it ends at an item delimitation, returning after it
  size_t data_set(size_t at, size_t end, bool explicit_vr, int depth, bool undefined_item, bool top) {
    uint32_t previous = 0;
    bool first = true;
    while (at < end) {
      if (end - at < 8) fail(previous, fmt::format("{} stray bytes after it, too few for an element", end - at));
      const uint32_t tag = tag_at(at);
      if (tag == kItemEnd) {
        if (!undefined_item) fail(tag, "outside an item of undefined length");
        if (u32(at + 4) != 0) fail(tag, fmt::format("length {}, must be 0", u32(at + 4)));
        return at + 8;
      }
      if (tag >> 16 == 0xFFFE) fail(tag, "where a data element belongs");
      if (!first && tag <= previous) fail(tag, fmt::format("after {}: tags must ascend", tag_text(previous)));
      first = false;
      previous = tag;
      check_tag(tag, top);
      // the VR (explicit) and the length
      std::string_view vr;
      uint32_t length = 0;
      size_t value_at = at + 8;
      if (explicit_vr) {
        vr = b_.substr(at + 4, 2);
        if (in(vr, kLongVrs)) {
          if (end - at < 12) fail(tag, past_end(12, end - at, end));
          length = u32(at + 8);
          value_at = at + 12;
        } else if (in(vr, kShortVrs)) {
          length = u16(at + 6);
        } else {
          fail(tag, fmt::format("unknown value representation '{}'", printable(vr)));
        }
      } else {
        length = u32(at + 4);
      }
      if (meta_ && (tag >> 16 != 0x0002 || !explicit_vr || vr == "SQ" || length == kUndefined))
        fail(tag, "in the File Meta group, which holds only (0002,xxxx) elements of defined length");
      if (!meta_ && top && tag >> 16 == 0x0002) fail(tag, "a File Meta element in the data set");
      if (length == kUndefined) {
        // a sequence of undefined length: SQ, UN (its items implicit VR, as in CP-246), or any
        // element in implicit VR; pixel data would be encapsulated, which native syntaxes are not
        if (tag == kPixelData) fail(tag, "undefined length (encapsulated pixel data) in a native transfer syntax");
        if (explicit_vr && vr != "SQ" && vr != "UN") fail(tag, fmt::format("undefined length for VR {}", vr));
        at = undefined_sequence(value_at, end, explicit_vr && vr == "SQ", depth + 1, tag);
        continue;
      }
      if (length > end - value_at) fail(tag, past_end(length, end - value_at, end));
      if (length % 2) fail(tag, fmt::format("odd length {} (DICOM values have even lengths)", length));
      if (const int size = value_size(vr); size && length % size)
        fail(tag, fmt::format("length {} is not a whole number of {}-byte {} values", length, size, vr));
      check_type(tag, vr, length);
      const std::string_view value = b_.substr(value_at, length);
      // implicit VR: a value that starts with an item is walked as the sequence it may be read as
      if (vr == "SQ" || (!explicit_vr && tag != kPixelData && length >= 8 && tag_at(value_at) == kItem))
        defined_sequence(value_at, value_at + length, explicit_vr, depth + 1, tag);
      if (meta_)
        meta_value(tag, value);
      else if (top)
        top_value(tag, vr, value);
      at = value_at + length;
    }
    if (undefined_item) fail(kItem, "of undefined length never ends (no item delimitation (FFFE,E00D))");
    return at;
  }

  // tags GDCM asserts on when malformed, which a CT or MR series does not need
  void check_tag(uint32_t tag, bool top) const {
    const uint32_t group = tag >> 16;
    if (group == 0x0000 || group == 0x0001 || group == 0x0003 || group == 0x0005 || group == 0x0007 || group == 0xFFFF)
      fail(tag, "a group no file may hold");
    if (tag == 0x00FF4AA5 || tag == 0x01F71070) fail(tag, "a private element GDCM rewrites on reading");
    if (!top) return;
    if ((group & 0xFF00) == 0x6000 || (group & 0xFF00) == 0x5000)
      fail(tag, "overlays (60xx) and curves (50xx) are not read");
    if (tag == 0x00080010 || tag == 0x00280005 || tag == 0x00280012) fail(tag, "a retired ACR-NEMA element, not read");
    if (tag == 0x00880200) fail(tag, "icon images are not read");
    const uint32_t e = tag & 0xFFFF;
    if (group == 0x0028 && ((e >= 0x1101 && e <= 0x1103) || (e >= 0x1201 && e <= 0x1203) ||
                            (e >= 0x1221 && e <= 0x1223) || e == 0x3000 || e == 0x3006))
      fail(tag, "lookup tables are not read");
  }

  // an element GDCM reads as its dictionary's type: that VR (explicit), whole values, one when
  // GDCM reads one
  void check_type(uint32_t tag, std::string_view vr, uint32_t length) const {
    for (const Typed& t : kTyped) {
      if (t.tag != tag) continue;
      if (!vr.empty() && vr != t.vr) fail(tag, fmt::format("VR {}, must be {}", vr, t.vr));
      if (const int size = value_size(t.vr); size && length % size)
        fail(tag, fmt::format("length {} is not a whole number of {}-byte {} values", length, size, t.vr));
      if (t.length && length != t.length && length != 0)
        fail(tag, fmt::format("length {}, must be one {} value ({} bytes)", length, t.vr, t.length));
      return;
    }
  }

  size_t undefined_sequence(size_t at, size_t end, bool explicit_vr, int depth, uint32_t tag) {
    if (depth > kMaxSequenceDepth) fail(tag, fmt::format("sequences nested deeper than {}", kMaxSequenceDepth));
    while (true) {
      if (end - at < 8) fail(tag, "a sequence of undefined length never ends (no sequence delimitation (FFFE,E0DD))");
      const uint32_t t = tag_at(at), length = u32(at + 4);
      if (t == kSequenceEnd) {
        if (length != 0) fail(t, fmt::format("length {}, must be 0", length));
        return at + 8;
      }
      at = item(at, end, explicit_vr, depth, tag);
    }
  }

  void defined_sequence(size_t at, size_t end, bool explicit_vr, int depth, uint32_t tag) {
    if (depth > kMaxSequenceDepth) fail(tag, fmt::format("sequences nested deeper than {}", kMaxSequenceDepth));
    while (at < end) {
      if (end - at < 8) fail(tag, fmt::format("{} stray bytes after its last item", end - at));
      at = item(at, end, explicit_vr, depth, tag);
    }
  }

  // one item at `at` of the sequence `tag`; returns after it
  size_t item(size_t at, size_t end, bool explicit_vr, int depth, uint32_t tag) {
    const uint32_t t = tag_at(at), length = u32(at + 4);
    if (t != kItem)
      fail(tag,
           fmt::format("({:04X},{:04X}) where an item (FFFE,E000) or the sequence's end belongs", t >> 16, t & 0xFFFF));
    if (length == kUndefined) return data_set(at + 8, end, explicit_vr, depth, true, false);
    if (length > end - at - 8) fail(kItem, past_end(length, end - at - 8, end));
    if (length % 2) fail(kItem, fmt::format("odd length {}", length));
    data_set(at + 8, at + 8 + length, explicit_vr, depth, false, false);
    return at + 8 + length;
  }

  void meta_value(uint32_t tag, std::string_view value) {
    const std::string uid(trimmed(value));
    if (tag == kTransferSyntax) {
      if (uid == kImplicitLe || uid == kExplicitLe) {
        out_.transfer_syntax_uid = uid;
        return;
      }
      std::string name = fmt::format("an unknown transfer syntax ({})", printable(uid));
      for (const Syntax& s : kSyntaxes)
        if (uid == s.uid) name = fmt::format("{} ({})", s.name, uid);
      fail(tag, fmt::format("{} is not accepted (only Implicit VR Little Endian ({}) and Explicit VR Little Endian "
                            "({}) are read; convert compressed series first, e.g. gdcmconv --raw)",
                            name, kImplicitLe, kExplicitLe));
    }
    if (tag == kMediaStorage) {
      seen_media_storage_ = true;
      media_storage_ = uid;
      out_.dicomdir = uid == kDicomdir;
      if (!out_.dicomdir && !in(uid, kImageClasses))
        fail(tag, fmt::format("'{}' is not a CT, MR or secondary capture image", printable(uid)));
    }
  }

  // the numbers of the image GDCM and ITK compute with, bounded before they see them
  void top_value(uint32_t tag, std::string_view vr, std::string_view value) {
    const auto us = [&]() -> int64_t {
      if (value.size() != 2 || (!vr.empty() && vr != "US"))
        fail(tag, fmt::format("{} bytes{}, must be one US value (2 bytes)", value.size(),
                              vr.empty() ? "" : fmt::format(" of VR {}", vr)));
      return uint16_t(uint8_t(value[0]) | uint8_t(value[1]) << 8);
    };
    const auto numbers = [&](size_t n, double* out, const char* what) {
      if (!parse_numbers(value, n, out))
        fail(tag, fmt::format("'{}' is not {} finite number{}", printable(trimmed(value)), what, n > 1 ? "s" : ""));
    };
    const auto within = [&](double x, double lo, double hi, const char* unit) {
      if (!(x >= lo && x <= hi)) fail(tag, fmt::format("{:g}{} is not in [{:g}, {:g}]{}", x, unit, lo, hi, unit));
    };
    switch (tag) {
      case 0x00080016:  // SOPClassUID: GDCM may take the image's kind from it
        if (trimmed(value) != media_storage_)
          fail(tag, fmt::format("'{}', but MediaStorageSOPClassUID (0002,0002) is '{}'", printable(trimmed(value)),
                                printable(media_storage_)));
        seen_sop_class_ = true;
        return;
      case kSeriesUid:
        out_.series_uid = std::string(trimmed(value));
        return;
      case 0x00280010:  // Rows
      case 0x00280011:  // Columns
        if (const int64_t n = us(); n < 1) fail(tag, fmt::format("{}, must be 1 to 65535", n));
        (tag == 0x00280010 ? out_.rows : out_.columns) = us();
        return;
      case 0x00280002:  // SamplesPerPixel
        if (us() != 1) fail(tag, fmt::format("{}, only grayscale images (1) are read", us()));
        return;
      case 0x00280006:  // PlanarConfiguration
        if (us() != 0) fail(tag, fmt::format("{}, must be 0", us()));
        return;
      case 0x00280100:  // BitsAllocated
        out_.bits_allocated = us();
        if (out_.bits_allocated != 8 && out_.bits_allocated != 16 && out_.bits_allocated != 32)
          fail(tag, fmt::format("{}, must be 8, 16 or 32", out_.bits_allocated));
        return;
      case 0x00280101:  // BitsStored
        bits_stored_ = us();
        if (bits_stored_ < 1 || bits_stored_ > out_.bits_allocated)
          fail(tag, fmt::format("{}, must be 1 to BitsAllocated ({})", bits_stored_, out_.bits_allocated));
        return;
      case 0x00280102:  // HighBit
        if (us() + 1 != bits_stored_) fail(tag, fmt::format("{}, must be BitsStored - 1 ({})", us(), bits_stored_ - 1));
        return;
      case 0x00280103:  // PixelRepresentation
        if (us() > 1) fail(tag, fmt::format("{}, must be 0 or 1", us()));
        return;
      case 0x00280004: {  // PhotometricInterpretation
        const std::string_view pi = trimmed(value);
        if (pi != "MONOCHROME1" && pi != "MONOCHROME2")
          fail(tag, fmt::format("'{}', only MONOCHROME1 or MONOCHROME2 images are read", printable(pi)));
        return;
      }
      case 0x00280008: {  // NumberOfFrames
        double frames = 0;
        numbers(1, &frames, "a");
        if (frames != std::floor(frames)) fail(tag, fmt::format("{:g} is not a whole number", frames));
        within(frames, 1, double(kMaxFrames), "");
        out_.frames = int64_t(frames);
        return;
      }
      case 0x00200032: {  // ImagePositionPatient
        double p[3];
        numbers(3, p, "three");
        for (const double x : p)
          if (std::abs(x) > kMaxPositionMm) fail(tag, fmt::format("{:g} mm is beyond +-{:g} mm", x, kMaxPositionMm));
        return;
      }
      case 0x00200037: {  // ImageOrientationPatient
        double o[6];
        numbers(6, o, "six");
        const double row = std::hypot(o[0], o[1], o[2]), column = std::hypot(o[3], o[4], o[5]);
        for (const auto& [length, name] : {std::pair{row, "row"}, std::pair{column, "column"}})
          if (!(std::abs(length - 1) <= kOrientationLengthTolerance))
            fail(tag, fmt::format("the {} direction's length is {:g}, not 1 (within {:g})", name, length,
                                  kOrientationLengthTolerance));
        const double cosine = (o[0] * o[3] + o[1] * o[4] + o[2] * o[5]) / (row * column);
        if (!(std::abs(cosine) <= kMaxOrientationCosine))
          fail(tag, fmt::format("row and column directions are not orthogonal (cosine {:.4f}, at most {:g})", cosine,
                                kMaxOrientationCosine));
        return;
      }
      case 0x00280030: {  // PixelSpacing
        double s[2];
        numbers(2, s, "two");
        for (const double x : s) within(x, kMinSpacingMm, kMaxSpacingMm, " mm");
        return;
      }
      case 0x00180050:    // SliceThickness
      case 0x00180088: {  // SpacingBetweenSlices
        double x = 0;
        if (trimmed(value).empty()) return;
        numbers(1, &x, "a");
        within(x, -kMaxPositionMm, kMaxPositionMm, " mm");
        return;
      }
      case 0x00281052:    // RescaleIntercept
      case 0x00281053: {  // RescaleSlope
        double x = 0;
        numbers(1, &x, "a");
        within(x, -kMaxRescale, kMaxRescale, "");
        return;
      }
      case kPixelData:
        pixel_data(vr, value.size());
        return;
      default:
        return;
    }
  }

  // native pixel data: exactly rows x columns x frames x bits/8 bytes (a pad byte when odd)
  void pixel_data(std::string_view vr, size_t length) {
    if (!vr.empty() && vr != "OB" && vr != "OW") fail(kPixelData, fmt::format("VR {}, must be OB or OW", vr));
    if (out_.rows == 0) fail(0x00280010, "missing (Pixel Data needs it)");
    if (out_.columns == 0) fail(0x00280011, "missing (Pixel Data needs it)");
    if (out_.bits_allocated == 0) fail(0x00280100, "missing (Pixel Data needs it)");
    // at most 65535 x 65535 x 65536 x 4: no overflow
    const int64_t expected = out_.rows * out_.columns * out_.frames * (out_.bits_allocated / 8);
    if (int64_t(length) != expected + expected % 2)
      fail(kPixelData, fmt::format("{} bytes, Rows x Columns x NumberOfFrames x BitsAllocated/8 is {} x {} x {} x {}/8 "
                                   "= {}",
                                   length, out_.rows, out_.columns, out_.frames, out_.bits_allocated, expected));
    has_pixels_ = true;
  }

  const std::string& file_;
  std::string_view b_;
  CheckedFile out_;
  bool meta_ = false, seen_media_storage_ = false, seen_sop_class_ = false, has_pixels_ = false;
  std::string media_storage_;
  int64_t bits_stored_ = 0;
};

}  // namespace

bool has_dicom_magic(std::string_view bytes) {
  return bytes.size() >= 132 && bytes.substr(128, 4) == "DICM";
}

CheckedFile precheck_dicom(const std::string& file, std::string_view bytes) {
  return Walker(file, bytes).run();
}

CheckedFile precheck_dicom_file(const std::string& path) {
  std::string bytes;
  try {
    bytes = json::read_regular_file(path, "the DICOM file", kMaxFileBytes);
  } catch (const json::FileError& e) {
    throw DicomError(e.what());
  }
  return precheck_dicom(path, bytes);
}

}  // namespace pcisim::anatomy::dicom
