#include <gtest/gtest.h>

#include "anatomy/phantom/coronary_phantom.h"

#ifdef PCISIM_HAVE_JSON
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "anatomy/vessel/vessel_tree_json.h"
#endif

namespace pcisim::anatomy {
namespace {

#ifdef PCISIM_HAVE_JSON

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("pcisim_vtj_" + std::to_string(::getpid()) + "_" + name)).string();
}

std::string write_text(const std::string& name, const std::string& text) {
  const std::string path = temp_path(name);
  std::ofstream(path) << text;
  return path;
}

// the message read_vessel_tree_json throws for this text, or "" if it did not throw
std::string error_for(const std::string& name, const std::string& text) {
  const std::string path = write_text(name, text);
  std::string message;
  try {
    read_vessel_tree_json(path);
  } catch (const std::runtime_error& e) {
    message = e.what();
  }
  std::filesystem::remove(path);
  EXPECT_NE(message.find(path), std::string::npos) << "the message should name the file: " << message;
  return message;
}

// a small valid tree with the one field under test replaced
std::string tree_text(const std::string& second_branch_extra, const std::string& radius = "0.001",
                      const std::string& parent = "0", const std::string& parent_point = "1") {
  return R"({
  // comments are allowed
  "format": "pcisim-vessel-tree", "version": 1,
  "branches": [
    {"name": "aorta", "parent": -1, "parent_point": -1, "points": [
      {"position_m": [0, 0, 0], "radius_m": 0.014}, {"position_m": [0, 0, 0.001], "radius_m": 0.014}]},
    {"name": "LM", "parent": )" +
         parent + R"(, "parent_point": )" + parent_point + R"(, "points": [
      {"position_m": [0, 0, 0.001], "radius_m": 0.002}, {"position_m": [0.001, 0, 0.001], "radius_m": 0.002},
      {"position_m": [0.002, 0, 0.001], "radius_m": )" +
         radius + "}]" + second_branch_extra + R"(}
  ]
})";
}

TEST(VesselTreeJsonTest, RoundTripKeepsEveryBit) {
  const VesselTree tree = make_coronary_phantom({.seed = 3});
  const std::string path = temp_path("roundtrip.json");
  write_vessel_tree_json(tree, path);
  const VesselTree back = read_vessel_tree_json(path);
  std::filesystem::remove(path);
  ASSERT_EQ(back.branches.size(), tree.branches.size());
  for (size_t i = 0; i < tree.branches.size(); ++i) {
    const auto& a = tree.branches[i];
    const auto& b = back.branches[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.parent, b.parent);
    EXPECT_EQ(a.parent_point, b.parent_point);
    ASSERT_EQ(a.points.size(), b.points.size());
    for (size_t k = 0; k < a.points.size(); ++k) {
      EXPECT_EQ(a.points[k].position_m, b.points[k].position_m);
      EXPECT_EQ(a.points[k].radius_m, b.points[k].radius_m);
    }
  }
}

TEST(VesselTreeJsonTest, ValidSmallFileReads) {
  const std::string path = write_text("small.json", tree_text(""));
  const VesselTree t = read_vessel_tree_json(path);
  std::filesystem::remove(path);
  ASSERT_EQ(t.branches.size(), 2u);
  EXPECT_EQ(t.branches[1].name, "LM");
  EXPECT_EQ(t.branches[1].parent, 0);
  EXPECT_EQ(t.branches[1].parent_point, 1);
  EXPECT_DOUBLE_EQ(t.branches[1].points[2].radius_m, 0.001);
}

TEST(VesselTreeJsonTest, BadFilesNameTheFileAndTheField) {
  struct Case {
    const char* name;
    std::string text;
    const char* expect;
  };
  const Case cases[] = {
      {"radius", tree_text("", "-0.5"), "branches[1].points[2].radius_m: expected a number > 0"},
      {"radius_string", tree_text("", "\"big\""), "branches[1].points[2].radius_m: expected a number > 0"},
      {"parent", tree_text("", "0.001", "4"), "branches[1].parent: expected an integer in [-1, 0], got 4"},
      {"parent_point", tree_text("", "0.001", "0", "7"),
       "branches[1].parent_point: expected an integer in [0, 1], got 7"},
      {"unknown", tree_text(", \"colour\": 1"), "branches[1].colour: unknown key"},
      {"syntax", "{ \"branches\": [ ", "not valid JSON"},
      {"root", "[1, 2]", "(root): expected an object"},
      {"format", R"({"format": "obj", "version": 1, "branches": []})", "format: expected \"pcisim-vessel-tree\""},
      {"empty", R"({"format": "pcisim-vessel-tree", "version": 1, "branches": []})",
       "branches: expected a non-empty array"},
      {"position", R"({"format": "pcisim-vessel-tree", "version": 1, "branches": [{"name": "a", "parent": -1,
         "points": [{"position_m": [0, 0], "radius_m": 0.001}, {"position_m": [0, 0, 1], "radius_m": 0.001}]}]})",
       "branches[0].points[0].position_m: expected an array of 3 numbers"},
      {"coordinate", R"({"format": "pcisim-vessel-tree", "version": 1, "branches": [{"name": "a", "parent": -1,
         "points": [{"position_m": [0, 0, 0], "radius_m": 0.001}, {"position_m": [0, "x", 1], "radius_m": 0.001}]}]})",
       "branches[0].points[1].position_m[1]: expected a number"},
      {"missing", R"({"format": "pcisim-vessel-tree", "version": 1, "branches": [{"name": "a", "parent": -1}]})",
       "branches[0].points: missing"},
      {"duplicate", R"({"format": "pcisim-vessel-tree", "version": 1, "branches": [
         {"name": "a", "parent": -1, "points": [{"position_m": [0, 0, 0], "radius_m": 0.001}, {"position_m": [0, 0, 1], "radius_m": 0.001}]},
         {"name": "a", "parent": 0, "parent_point": 0, "points": [{"position_m": [0, 0, 0], "radius_m": 0.001}, {"position_m": [0, 0, 1], "radius_m": 0.001}]}]})",
       "branches[1].name: duplicate branch name \"a\""},
      {"few_points", R"({"format": "pcisim-vessel-tree", "version": 1, "branches": [{"name": "a", "parent": -1,
         "points": [{"position_m": [0, 0, 0], "radius_m": 0.001}]}]})",
       "branches[0].points: expected an array of at least 2 points"},
  };
  for (const Case& c : cases) {
    const std::string message = error_for(std::string(c.name) + ".json", c.text);
    EXPECT_NE(message.find(c.expect), std::string::npos)
        << "case " << c.name << ": got \"" << message << "\", expected it to contain \"" << c.expect << "\"";
  }
  // a file that is not there
  const std::string nowhere = temp_path("does_not_exist.json");
  try {
    read_vessel_tree_json(nowhere);
    ADD_FAILURE() << "reading a missing file should throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(nowhere + ": cannot open"), std::string::npos) << e.what();
  }
  // a FIFO (which would block a plain open for ever) and a folder are refused, not waited on
  const std::string fifo = temp_path("pipe.json");
  std::filesystem::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string folder = temp_path("folder.json");
  std::filesystem::create_directories(folder);
  for (const std::string& path : {fifo, folder}) {
    try {
      read_vessel_tree_json(path);
      ADD_FAILURE() << "read " << path;
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()),
                path + ": not a regular file (" + (path == fifo ? "a FIFO" : "a folder") + ", never read as the file)");
    }
  }
  std::filesystem::remove(fifo);
  std::filesystem::remove(folder);
  // nesting past the JSON reader's depth is refused (a deep enough file overflowed the stack)
  EXPECT_NE(error_for("deep.json", std::string(100000, '[') + std::string(100000, ']')).find("nested deeper than 64"),
            std::string::npos);
  // a folder that is not there, for writing
  try {
    write_vessel_tree_json(make_coronary_phantom({}), "/nonexistent-dir/x.json");
    ADD_FAILURE() << "writing into a missing folder should throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/x.json"), std::string::npos) << e.what();
  }
}

// ---- the bounds (anatomy/case/case_limits.h, docs/anatomy.md "Limits") ----

// a tree of `branches` straight branches of `points` points `step_m` apart (each a root), radius r_m
std::string straight_tree(int branches, int points, double step_m, double r_m = 0.001) {
  std::string text = R"({"format": "pcisim-vessel-tree", "version": 1, "branches": [)";
  for (int b = 0; b < branches; ++b) {
    text += (b ? "," : "") + std::string(R"({"name": "b)") + std::to_string(b) + R"(", "parent": -1, "points": [)";
    for (int k = 0; k < points; ++k)
      text += (k ? "," : "") + std::string(R"({"position_m": [)") + std::to_string(0.001 * b) + ", 0, " +
              std::to_string(step_m * k) + R"(], "radius_m": )" + std::to_string(r_m) + "}";
    text += "]}";
  }
  return text + "]}";
}

// a radius of 1e6 m lofted a tube of billions of triangles (std::bad_alloc); 0.1 m started for 20 s
TEST(VesselTreeJsonTest, ARadiusBeyondAnAorticRootIsRefused) {
  for (const char* r : {"1e6", "0.1", "0.031"}) {
    const std::string message = error_for("radius.json", tree_text("", r));
    EXPECT_NE(message.find("branches[1].points[2].radius_m: "), std::string::npos) << message;
    EXPECT_NE(message.find("m, outside [1e-06, 0.03] m"), std::string::npos) << message;
  }
  EXPECT_NE(error_for("tiny.json", tree_text("", "1e-300")).find("branches[1].points[2].radius_m: 1e-300 m, outside"),
            std::string::npos);
  // the widest allowed reads
  const std::string path = write_text("wide.json", tree_text("", "0.03"));
  EXPECT_DOUBLE_EQ(read_vessel_tree_json(path).branches[1].points[2].radius_m, 0.03);
  std::filesystem::remove(path);
}

// a branch whose points repeat 300 times started for over 20 s: points per branch and in the
// tree, repeated consecutive points and the total length are bounded before the work
TEST(VesselTreeJsonTest, TooManyRepeatedOrTooLongCenterlinesAreRefused) {
  EXPECT_NE(error_for("branch.json", straight_tree(1, 4001, 1e-5))
                .find("branches[0].points: 4001 points, more than 4000 (the limit per branch)"),
            std::string::npos);
  EXPECT_NE(error_for("tree.json", straight_tree(6, 3400, 1e-5))
                .find("branches[5].points: the tree reaches 20400 points here, more than 20000"),
            std::string::npos);
  EXPECT_NE(error_for("long.json", straight_tree(2, 1100, 1e-3))
                .find("branches[1].points[902].position_m: the centerlines' total length passes 2 m here"),
            std::string::npos);
  // each point twice (a point repeated: the tube has no direction there)
  std::string twice = tree_text("");
  const std::string point = R"({"position_m": [0.001, 0, 0.001], "radius_m": 0.002})";
  twice.replace(twice.find(point), point.size(), point + ", " + point);
  EXPECT_NE(error_for("twice.json", twice)
                .find("branches[1].points[2].position_m: 0 m from points[1], closer than 1e-06 m (consecutive points "
                      "must differ)"),
            std::string::npos);
  // a coordinate no patient has (squares of it overflow further on)
  EXPECT_NE(error_for("far.json", straight_tree(1, 2, 20.0))
                .find("branches[0].points[1].position_m[2]: 20 m, more than 10 m from the origin"),
            std::string::npos);
  EXPECT_NE(error_for("branches.json", straight_tree(513, 2, 1e-3)).find("branches: 513 branches, more than 512"),
            std::string::npos);
}

#else

TEST(VesselTreeJsonTest, SkippedWithoutJson) {
  GTEST_SKIP() << "built without nlohmann-json: vessel tree JSON I/O is left out";
}

#endif

}  // namespace
}  // namespace pcisim::anatomy
