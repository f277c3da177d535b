#include "tests/common/shared_lumen.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "anatomy/phantom/coronary_phantom.h"
#include "physics/guidewire/sdf_lumen.h"
#include "physics/sdf/lumen_sdf.h"

namespace pcisim::physics::test {
namespace {

namespace fs = std::filesystem;

// FNV-1a over raw bytes: a key, not a digest anyone trusts with security
struct Hash {
  uint64_t h = 1469598103934665603ull;
  void add(const void* p, size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  }
  template <class T>
  void add(const T& v) {
    add(&v, sizeof v);
  }
};

// the executable's own build: its size and modification time (any relink changes them)
uint64_t build_key() {
  struct stat st {};
  Hash h;
  if (::stat("/proc/self/exe", &st) == 0) {
    h.add(st.st_size);
    h.add(st.st_mtim.tv_sec);
    h.add(st.st_mtim.tv_nsec);
  }
  return h.h;
}

uint64_t tree_key(const anatomy::VesselTree& tree, double spacing_m) {
  Hash h;
  h.add(spacing_m);
  for (const auto& b : tree.branches) {
    h.add(b.name.data(), b.name.size());
    h.add(b.parent);
    h.add(b.parent_point);
    for (const auto& p : b.points) {
      h.add(p.position_m.x());
      h.add(p.position_m.y());
      h.add(p.position_m.z());
      h.add(p.radius_m);
    }
  }
  return h.h;
}

constexpr char kMagic[8] = {'P', 'C', 'S', 'D', 'F', 'v', '1', '\n'};

template <class T>
bool read_pod(std::ifstream& in, T* v) {
  return static_cast<bool>(in.read(reinterpret_cast<char*>(v), sizeof *v));
}

// the field stored at path, or false when it is missing, torn or of another build
bool read_field(const fs::path& path, uint64_t key, SignedDistanceField* out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  char magic[8];
  uint64_t stored_key = 0, n_table = 0, n_values = 0;
  double spacing_m = 0, band_m = 0;
  Eigen::Vector3d origin_m;
  Eigen::Vector3i dims;
  if (!in.read(magic, 8) || std::memcmp(magic, kMagic, 8) != 0 || !read_pod(in, &stored_key) || stored_key != key)
    return false;
  if (!read_pod(in, &spacing_m) || !read_pod(in, &band_m) || !in.read(reinterpret_cast<char*>(origin_m.data()), 24) ||
      !in.read(reinterpret_cast<char*>(dims.data()), 12) || !read_pod(in, &n_table) || !read_pod(in, &n_values))
    return false;
  if (n_table > (1ull << 31) || n_values > (1ull << 33)) return false;
  std::vector<int32_t> table(n_table);
  std::vector<float> values(n_values);
  if (!in.read(reinterpret_cast<char*>(table.data()), static_cast<std::streamsize>(n_table * sizeof(int32_t))) ||
      !in.read(reinterpret_cast<char*>(values.data()), static_cast<std::streamsize>(n_values * sizeof(float))))
    return false;
  char extra;
  if (in.read(&extra, 1)) return false;  // longer than written: not ours
  *out = SignedDistanceField::from_parts(spacing_m, origin_m, dims, band_m, std::move(table), std::move(values));
  return true;
}

// written beside, then renamed: a reader sees the whole file or none (tests run two at a time)
void write_field(const fs::path& path, uint64_t key, const SignedDistanceField& f) {
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
  const fs::path tmp = path.string() + ".tmp" + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    const double spacing_m = f.spacing_m(), band_m = f.band_m();
    const uint64_t n_table = f.brick_table().size(), n_values = f.values_m().size();
    out.write(kMagic, 8);
    out.write(reinterpret_cast<const char*>(&key), 8);
    out.write(reinterpret_cast<const char*>(&spacing_m), 8);
    out.write(reinterpret_cast<const char*>(&band_m), 8);
    out.write(reinterpret_cast<const char*>(f.origin_m().data()), 24);
    out.write(reinterpret_cast<const char*>(f.dims().data()), 12);
    out.write(reinterpret_cast<const char*>(&n_table), 8);
    out.write(reinterpret_cast<const char*>(&n_values), 8);
    out.write(reinterpret_cast<const char*>(f.brick_table().data()), static_cast<std::streamsize>(n_table * 4));
    out.write(reinterpret_cast<const char*>(f.values_m().data()), static_cast<std::streamsize>(n_values * 4));
    if (!out) {
      out.close();
      fs::remove(tmp, ec);
      return;  // a cache that cannot be written only costs time
    }
  }
  fs::rename(tmp, path, ec);
  if (ec) fs::remove(tmp, ec);
}

std::string hex(const char* prefix, uint64_t v, const char* suffix) {
  char s[64];
  std::snprintf(s, sizeof s, "%s%016llx%s", prefix, static_cast<unsigned long long>(v), suffix);
  return s;
}

// PCISIM_BINARY_DIR/test-fixtures/<executable>/<build>/: a new build of the executable removes
// the fields its older builds left
fs::path fixture_folder(uint64_t build) {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  const fs::path mine = fs::path(PCISIM_BINARY_DIR) / "test-fixtures" / (ec ? "unknown" : exe.filename().string());
  const fs::path folder = mine / hex("", build, "");
  if (!fs::exists(folder, ec)) {
    for (const auto& e : fs::directory_iterator(mine, ec))
      if (e.path() != folder) fs::remove_all(e.path(), ec);
  }
  return folder;
}

std::mutex mutex;
SharedLumenCounts counts;

}  // namespace

std::shared_ptr<const LumenQuery> shared_lumen(const anatomy::VesselTree& tree, double spacing_m) {
  static std::map<uint64_t, std::shared_ptr<const LumenQuery>> memory;
  const uint64_t build = build_key(), key = tree_key(tree, spacing_m) ^ build;
  const std::lock_guard<std::mutex> lock(mutex);
  if (const auto it = memory.find(key); it != memory.end()) {
    ++counts.reused;
    return it->second;
  }
  const fs::path path = fixture_folder(build) / hex("sdf-", key, ".bin");
  SignedDistanceField field;
  if (read_field(path, key, &field)) {
    ++counts.read;
  } else {
    field = build_lumen_sdf(tree, spacing_m);
    write_field(path, key, field);
    ++counts.built;
  }
  auto lumen = std::make_shared<const SdfLumen>(tree, std::move(field));
  memory.emplace(key, lumen);
  return lumen;
}

std::shared_ptr<const LumenQuery> shared_lumen(const WorldSpec& spec) {
  if (!spec.vessel_contact) return nullptr;
  return shared_lumen(anatomy::make_coronary_phantom(anatomy::CoronaryPhantomSpec{spec.anatomy.seed}),
                      spec.vessel_contact->sdf_spacing_m);
}

SharedLumenCounts shared_lumen_counts() {
  const std::lock_guard<std::mutex> lock(mutex);
  return counts;
}

}  // namespace pcisim::physics::test
