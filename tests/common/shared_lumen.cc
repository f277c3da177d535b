#include "tests/common/shared_lumen.h"

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "anatomy/phantom/coronary_phantom.h"
#include "physics/guidewire/sdf_lumen.h"
#include "physics/sdf/lumen_sdf.h"
#include "tests/common/fixture_file.h"

namespace pcisim::physics::test {
namespace {

uint64_t tree_key(const anatomy::VesselTree& tree, double spacing_m) {
  pcisim::test::FixtureKey h;
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
bool read_field(const std::string& path, uint64_t key, SignedDistanceField* out) {
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

// the field at path (shared_fixture_file renames it into place once written)
void write_field(const std::string& path, uint64_t key, const SignedDistanceField& f) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
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
  if (!out) throw std::runtime_error(path + ": cannot write the shared contact field");
}

std::string file_name(uint64_t key) {
  char name[40];
  std::snprintf(name, sizeof name, "sdf-%016llx.bin", static_cast<unsigned long long>(key));
  return name;
}

std::mutex mutex;
SharedLumenCounts counts;

}  // namespace

std::shared_ptr<const LumenQuery> shared_lumen(const anatomy::VesselTree& tree, double spacing_m) {
  static std::map<uint64_t, std::shared_ptr<const LumenQuery>> memory;
  const uint64_t key = tree_key(tree, spacing_m);
  const std::lock_guard<std::mutex> lock(mutex);
  if (const auto it = memory.find(key); it != memory.end()) {
    ++counts.reused;
    return it->second;
  }
  // made by the first process of this build to ask (built here, then counted as built)
  SignedDistanceField field;
  bool built = false;
  const std::string path = pcisim::test::shared_fixture_file(file_name(key), [&](const std::string& tmp) {
    field = build_lumen_sdf(tree, spacing_m);
    built = true;
    write_field(tmp, key, field);
  });
  if (built) {
    ++counts.built;
  } else if (read_field(path, key, &field)) {
    ++counts.read;
  } else {
    field = build_lumen_sdf(tree, spacing_m);  // a file that does not read back whole: never trusted
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

bool read_stored_field(const anatomy::VesselTree& tree, double spacing_m, SignedDistanceField* out) {
  const uint64_t key = tree_key(tree, spacing_m);
  return read_field(pcisim::test::fixture_path(file_name(key)), key, out);
}

SharedLumenCounts shared_lumen_counts() {
  const std::lock_guard<std::mutex> lock(mutex);
  return counts;
}

}  // namespace pcisim::physics::test
