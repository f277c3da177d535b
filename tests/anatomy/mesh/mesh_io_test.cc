// Mesh files (anatomy/mesh/mesh_io): a file over the mesh size limit is refused unread, naming its
// size and the limit; text formats are parsed in place (no copy of the file into a stream); the
// words a text mesh may hold (CRLF, tabs, '+', exponents, a/b/c corners, negative indices) read as
// before, and a word that is not a number is refused; millimetre text becomes metres with one
// rounding, so a surface written in millimetres (write_ply_mm) reads back bit for bit.
#include "anatomy/mesh/mesh_io.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <charconv>
#include <random>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <utility>

#include "realtime/allocation_count.h"

namespace pcisim::anatomy {
namespace {

namespace fs = std::filesystem;

class MeshIo : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pcisim-mesh-io-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

std::string refusal(const std::function<void()>& read) {
  try {
    read();
  } catch (const MeshIoError& e) {
    return e.what();
  }
  return "";
}

TEST_F(MeshIo, AFileOverTheMeshLimitIsRefusedUnreadNamingItsSizeAndTheLimit) {
  // a sparse file one byte over 512 MiB: takes no disk, and reading it would take half a gigabyte
  const std::string big = path("big.stl");
  std::ofstream(big) << "solid x\n";
  fs::resize_file(big, kMaxMeshFileBytes + 1);
  // "unread" by what it asked of the heap, not by a clock: reading it would take a 512 MiB buffer
  std::string why;
  long long largest = 0;
  {
    realtime::AllocationCount count;
    why = refusal([&] { read_mesh(big); });
    largest = count.largest();
  }
  EXPECT_EQ(why.rfind(big + ": 536870913 bytes, over the 536870912 byte limit", 0), 0u) << why;
  EXPECT_LT(largest, 1 << 20) << "the file was read before it was refused";
  // a file at the limit is read (and refused for what it holds, not for its size)
  fs::resize_file(big, 1000);
  EXPECT_EQ(refusal([&] { read_mesh(big); }).find("over the"), std::string::npos);
}

TEST_F(MeshIo, AFifoOrAFolderIsRefusedNotWaitedOn) {
  const std::string fifo = path("pipe.obj");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(refusal([&] { read_mesh(fifo); }).find("pipe.obj: not a regular file"), std::string::npos);
  fs::create_directories(path("dir.stl"));
  EXPECT_NE(refusal([&] { read_mesh(path("dir.stl")); }).find("dir.stl: not a regular file"), std::string::npos);
}

// text formats are parsed where the bytes lie: 4 MB of a file (a long comment, padding) never
// makes an allocation of its size (a std::istringstream of the file made two)
TEST_F(MeshIo, TextMeshesAreParsedWithoutCopyingTheFile) {
  const std::string padding(4 << 20, ' ');
  const std::string comments = [] {
    std::string c;
    while (c.size() < (4u << 20)) c += "# a comment line of the kind exporters write\n";
    return c;
  }();
  std::string ply_comments;
  while (ply_comments.size() < (1u << 20)) ply_comments += "comment a header line of the kind exporters write\n";
  const std::string stl = "solid t" + padding +
                          "\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
                          "endloop\nendfacet\nendsolid t\n";
  const std::string obj = comments + "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  const std::string ply = "ply\nformat ascii 1.0\n" + ply_comments +
                          "element vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\n"
                          "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2" +
                          padding + "\n";
  for (const auto& [format, bytes] : {std::pair{".stl", &stl}, std::pair{".obj", &obj}, std::pair{".ply", &ply}}) {
    TriangleMesh mesh;
    long long largest = 0;
    {
      realtime::AllocationCount count;
      mesh = parse_mesh(std::string("t") + format, format, *bytes);
      largest = count.largest();
    }
    EXPECT_EQ(mesh.triangles.size(), 1u) << format;
    EXPECT_LT(largest, 64 << 10) << format << ": an allocation of " << largest << " bytes for a " << bytes->size()
                                 << " byte file";
  }
}

TEST_F(MeshIo, TheWordsOfTextMeshesReadAsBefore) {
  // CRLF, tabs, signs, exponents, v/vt/vn corners, negative (from the end) indices, a quad
  const std::string obj =
      "# x\r\nv +1.5e0\t0 -0\r\nv 2.5 0.0 0\r\nv 2.5 1E+0 0\r\nv 1.5 1 0\r\nvt 0 0\r\n"
      "f 1/1/1 2//2 3/3 -1\r\n";
  const TriangleMesh m = parse_mesh("t.obj", ".obj", obj, 1.0);
  ASSERT_EQ(m.vertices_m.size(), 4u);
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.vertices_m[0], Eigen::Vector3d(1.5, 0, 0));
  EXPECT_EQ(m.vertices_m[2], Eigen::Vector3d(2.5, 1, 0));
  EXPECT_EQ(m.triangles[1], (std::array<int, 3>{0, 2, 3}));
  // an STL coordinate below float's range is zero (as a stream read it), one above is refused
  const std::string tiny =
      "solid t\nfacet normal 0 0 1\n outer loop\n  vertex 1e-50 0 0\n  vertex 1 0 0\n  vertex 0 1 0\n"
      " endloop\nendfacet\nendsolid t\n";
  const TriangleMesh s = parse_mesh("t.stl", ".stl", tiny, 1.0);
  ASSERT_EQ(s.vertices_m.size(), 3u);
  EXPECT_EQ(s.vertices_m[0].x(), 0.0);
  std::string huge = tiny;
  huge.replace(huge.find("1e-50"), 5, "1e+50");
  EXPECT_EQ(refusal([&] { parse_mesh("t.stl", ".stl", huge, 1.0); }),
            "t.stl: triangle 0: a vertex is not three finite numbers");
  // words that are not numbers are refused naming the line or the word
  EXPECT_EQ(refusal([&] { parse_mesh("t.obj", ".obj", "v 1 2 3x\n", 1.0); }),
            "t.obj: line 1: a vertex needs three finite numbers");
  EXPECT_EQ(refusal([&] { parse_mesh("t.obj", ".obj", "v 1 2 3\nv 1 2 4\nv 1 3 3\nf 1 2 z3\n", 1.0); }),
            "t.obj: line 4: bad face corner 'z3'");
  EXPECT_EQ(refusal([&] {
              parse_mesh("t.ply", ".ply",
                         "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                         "property float z\nend_header\n0 0 0\n1 0 zero\n0 1 0\n",
                         1.0);
            }),
            "t.ply: data: 'zero' is not a number");
}

// millimetres in text become metres with one rounding (the decimal exponent moved by 3): the
// nearest double to the decimal metres, where parsing then multiplying by 1e-3 was an ulp off
// for about one coordinate in seven; so write_ply_mm then read_mesh is the identity
TEST_F(MeshIo, MillimetreTextReadsToTheNearestMetreAndAWrittenPlyBitForBit) {
  const std::string ply_head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  auto metres = [](const char* text) {
    double v = 0;
    std::from_chars(text, text + std::char_traits<char>::length(text), v);
    return v;
  };
  const TriangleMesh t = parse_mesh("t.ply", ".ply",
                                    ply_head +
                                        "30.1 -0.18753614417489281 +1.5E+01\n"
                                        "0 0 0\n1e-3 0 0\n3 0 1 2\n");
  EXPECT_EQ(t.vertices_m[0].x(), metres("30.1e-3"));
  EXPECT_NE(t.vertices_m[0].x(), 30.1 * 1e-3) << "30.1 x 1e-3 rounds twice, an ulp off";
  EXPECT_EQ(t.vertices_m[0].y(), metres("-0.18753614417489281e-3"));
  EXPECT_EQ(t.vertices_m[0].z(), 0.015);
  EXPECT_EQ(t.vertices_m[2].x(), 1e-6);
  const TriangleMesh o = parse_mesh("t.obj", ".obj", "v 123.456 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n");
  EXPECT_EQ(o.vertices_m[0].x(), metres("123.456e-3"));
  EXPECT_NE(o.vertices_m[0].x(), 123.456 * 1e-3);
  // any doubles, written and read back
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.2, 0.2);
  TriangleMesh m;
  for (int i = 0; i < 3000; ++i) m.vertices_m.emplace_back(u(rng), u(rng), i % 7 == 0 ? 0.0 : u(rng) * 1e-6);
  for (int i = 0; i + 2 < 3000; i += 3) m.triangles.push_back({i, i + 1, i + 2});
  write_ply_mm(m, path("m.ply"), "pcisim test");
  const TriangleMesh back = read_mesh(path("m.ply"));
  EXPECT_EQ(back.vertices_m, m.vertices_m);
  EXPECT_EQ(back.triangles, m.triangles);
  std::ifstream in(path("m.ply"));
  std::string header((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(header.find("\ncomment SPACE=LPS units=mm\n"), std::string::npos);
}

}  // namespace
}  // namespace pcisim::anatomy
