// Terrain files (terrain/terrain_file.hpp): every kind of entry read, every refusal a
// TerrainFileError (terrain's own type: terrain/ includes nothing of config/) naming the file and
// the key, findTerrainFile by name and by path, and every shipped file of config/terrain loads into
// a Terrain.

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "terrain/terrain_file.hpp"

namespace stride::terrain {
namespace test_terrain_file {

namespace fs = std::filesystem;

// The programs catch std::exception (std::runtime_error) and print what(): the terrain's own error
// type reaches them as config's ConfigError did, with the same message.
static_assert(std::is_base_of_v<std::runtime_error, TerrainFileError>);

// The message of the TerrainFileError that parsing `yaml` throws ("" if none, or another type).
std::string refusal(const std::string& yaml, const std::string& source = "course.yaml") {
  try {
    parseTerrain(yaml, source);
  } catch (const TerrainFileError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("not a TerrainFileError: ") + e.what();
  }
  return "";
}

// A fresh folder under the system's temporary one, removed at the end of the test.
struct TempDir {
  fs::path path;
  TempDir() {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path = fs::temp_directory_path() /
           ("stride_terrain_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  void write(const std::string& relative, const std::string& text) const {
    fs::create_directories((path / relative).parent_path());
    std::ofstream(path / relative) << text;
  }
};

TEST(TerrainFile, ReadsEveryKind) {
  const TerrainSpec s = parseTerrain(R"(
ground: 0.05
boxes:
  - {center: [1.0, 2.0], size: [0.4, 0.6], height: 0.1, yaw: 0.5}
  - {center: [-1, 0], size: [1, 1], height: 0.2}
ramps:
  - {from: [0, 0], to: [2, 0.5], width: 0.8, rise: 0.3}
stairs:
  - {start: [3, 0], yaw: 1.5707963, steps: 4, rise: 0.12, run: 0.28, width: 1.2, landing: 0.6}
  - {start: [5, 0], steps: 1, rise: -0.1, run: 0.3, width: 1}
rough:
  - {min: [-2, -1], max: [-1, 1], cell: 0.1, amplitude: 0.03, seed: 42}
  - {min: [0, 3], max: [1, 4], cell: 0.2, amplitude: 0}
)",
                                     "/some/where/my_course.yaml");
  EXPECT_EQ(s.name, "my_course");
  EXPECT_EQ(s.ground, 0.05);
  ASSERT_EQ(s.boxes.size(), 2u);
  EXPECT_EQ(s.boxes[0].center, Eigen::Vector2d(1.0, 2.0));
  EXPECT_EQ(s.boxes[0].size, Eigen::Vector2d(0.4, 0.6));
  EXPECT_EQ(s.boxes[0].height, 0.1);
  EXPECT_EQ(s.boxes[0].yaw, 0.5);
  EXPECT_EQ(s.boxes[1].yaw, 0.0);  // by default
  ASSERT_EQ(s.ramps.size(), 1u);
  EXPECT_EQ(s.ramps[0].from, Eigen::Vector2d(0, 0));
  EXPECT_EQ(s.ramps[0].to, Eigen::Vector2d(2, 0.5));
  EXPECT_EQ(s.ramps[0].width, 0.8);
  EXPECT_EQ(s.ramps[0].rise, 0.3);
  ASSERT_EQ(s.stairs.size(), 2u);
  EXPECT_EQ(s.stairs[0].start, Eigen::Vector2d(3, 0));
  EXPECT_EQ(s.stairs[0].yaw, 1.5707963);
  EXPECT_EQ(s.stairs[0].steps, 4);
  EXPECT_EQ(s.stairs[0].rise, 0.12);
  EXPECT_EQ(s.stairs[0].run, 0.28);
  EXPECT_EQ(s.stairs[0].width, 1.2);
  EXPECT_EQ(s.stairs[0].landing, 0.6);
  EXPECT_EQ(s.stairs[1].yaw, 0.0);
  EXPECT_EQ(s.stairs[1].landing, 0.0);
  EXPECT_EQ(s.stairs[1].rise, -0.1);
  ASSERT_EQ(s.rough.size(), 2u);
  EXPECT_EQ(s.rough[0].min, Eigen::Vector2d(-2, -1));
  EXPECT_EQ(s.rough[0].max, Eigen::Vector2d(-1, 1));
  EXPECT_EQ(s.rough[0].cell, 0.1);
  EXPECT_EQ(s.rough[0].amplitude, 0.03);
  EXPECT_EQ(s.rough[0].seed, 42u);
  EXPECT_EQ(s.rough[1].seed, 0u);
  // What it describes is a terrain: the box's top where the file puts it.
  const Terrain t(s);
  EXPECT_NEAR(t.height(-1.0, 0.0), 0.25, 1e-12);
  EXPECT_NEAR(t.height(10.0, 10.0), 0.05, 1e-12);
}

TEST(TerrainFile, EmptyIsFlat) {
  for (const char* text : {"", "# nothing\n", "ground: 0.3\n", "boxes: []\nstairs:\n"}) {
    const TerrainSpec s = parseTerrain(text, "flat.yaml");
    EXPECT_TRUE(s.boxes.empty() && s.ramps.empty() && s.stairs.empty() && s.rough.empty()) << text;
    EXPECT_TRUE(Terrain(s).isFlat());
  }
  EXPECT_EQ(parseTerrain("ground: 0.3\n", "flat.yaml").ground, 0.3);
}

// Each refusal names the file and the key, and says what is wrong.
TEST(TerrainFile, Refusals) {
  struct Case {
    const char* yaml;
    std::vector<std::string> said;
  };
  const std::vector<Case> cases = {
      {"ground: 0\nhills: []\n", {"'course.yaml'", "hills", "unknown key"}},
      {"boxes:\n  - {center: [0, 0], size: [1, 1], height: 0.1, colour: red}\n",
       {"'course.yaml'", "boxes[0].colour", "unknown key"}},
      {"stairs:\n  - {start: [0, 0], steps: 2, rise: 0.1, run: 0.3, width: 1, lenght: 2}\n",
       {"stairs[0].lenght", "unknown key"}},
      {"boxes:\n  - {center: [0, 0], size: [1, 1], height: 0.1}\n"
       "  - {center: [0, 0], size: [-1, 1], height: 0.1}\n",
       {"'course.yaml'", "boxes[1].size", "must be > 0"}},
      {"ramps:\n  - {from: [0, 0], to: [1, 0], width: -0.5, rise: 0.1}\n",
       {"ramps[0].width", "must be > 0"}},
      {"stairs:\n  - {start: [0, 0], steps: 2, rise: 0.1, run: 0.3, width: 1, landing: -1}\n",
       {"stairs[0].landing", ">= 0"}},
      {"rough:\n  - {min: [0, 0], max: [1, 1], cell: 0, amplitude: 0.1}\n",
       {"'course.yaml'", "rough[0].cell", "must be > 0"}},
      {"rough:\n  - {min: [0, 0], max: [1, 1], cell: 0.1, amplitude: -0.1}\n",
       {"rough[0].amplitude", ">= 0"}},
      {"rough:\n  - {min: [0, 0], max: [1, 0], cell: 0.1, amplitude: 0.1}\n", {"rough[0].max"}},
      {"ramps:\n  - {from: [0, 0], to: [1, 0], rise: 0.1}\n",
       {"'course.yaml'", "ramps[0].width", "missing"}},
      {"boxes:\n  - {size: [1, 1], height: 0.1}\n", {"boxes[0].center", "missing"}},
      {"ramps:\n  - {from: [1, 1], to: [1, 1], width: 1, rise: 0.1}\n", {"ramps[0].to"}},
      {"boxes:\n  - {center: [0, 0], size: [1, 1], height: tall}\n",
       {"'course.yaml'", "boxes[0].height", "expected a number"}},
      {"ground: low\n", {"ground", "expected a number"}},
      {"boxes:\n  - {center: [0, zero], size: [1, 1], height: 0.1}\n", {"boxes[0].center"}},
      {"boxes:\n  - {center: [0, 0, 0], size: [1, 1], height: 0.1}\n",
       {"boxes[0].center", "[x, y]"}},
      {"ground: .nan\n", {"ground", "finite"}},
      {"stairs:\n  - {start: [0, 0], steps: 0, rise: 0.1, run: 0.3, width: 1}\n",
       {"'course.yaml'", "stairs[0].steps", "whole number"}},
      {"stairs:\n  - {start: [0, 0], steps: 2.5, rise: 0.1, run: 0.3, width: 1}\n",
       {"stairs[0].steps", "whole number"}},
      {"rough:\n  - {min: [0, 0], max: [1, 1], cell: 0.1, amplitude: 0.1, seed: 1.5}\n",
       {"rough[0].seed"}},
      {"boxes: {center: [0, 0]}\n", {"boxes", "list"}},
      {"boxes:\n  - 3\n", {"boxes[0]"}},
      {"- 1\n- 2\n", {"'course.yaml'"}},
      {"ground: [0\nboxes: }\n", {"'course.yaml'", "does not parse"}},
  };
  for (const Case& c : cases) {
    const std::string what = refusal(c.yaml);
    ASSERT_FALSE(what.empty()) << "accepted:\n" << c.yaml;
    EXPECT_EQ(what.find("not a TerrainFileError"), std::string::npos) << what;
    for (const std::string& s : c.said)
      EXPECT_NE(what.find(s), std::string::npos) << "'" << s << "' not in: " << what;
  }
}

TEST(TerrainFile, LoadsAFileAndRefusesAMissingOne) {
  TempDir dir;
  dir.write("steps.yaml",
            "stairs:\n  - {start: [0, 0], steps: 2, rise: 0.1, run: 0.3, width: 1}\n");
  const TerrainSpec s = loadTerrainFile((dir.path / "steps.yaml").string());
  EXPECT_EQ(s.name, "steps");
  ASSERT_EQ(s.stairs.size(), 1u);
  EXPECT_EQ(s.stairs[0].steps, 2);
  // Errors in a file name it.
  dir.write("bad.yaml", "ramps:\n  - {from: [0, 0], to: [1, 0], width: 0, rise: 0.1}\n");
  const std::string bad = (dir.path / "bad.yaml").string();
  try {
    loadTerrainFile(bad);
    ADD_FAILURE() << "a width of 0 accepted";
  } catch (const TerrainFileError& e) {
    EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("ramps[0].width"), std::string::npos) << e.what();
  }
  const std::string missing = (dir.path / "nowhere.yaml").string();
  try {
    loadTerrainFile(missing);
    ADD_FAILURE() << "a file that does not exist loaded";
  } catch (const TerrainFileError& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
}

TEST(TerrainFile, FindByNameAndByPath) {
  TempDir first, second;
  second.write("terrain/hill.yaml", "ground: 0.1\n");
  second.write("terrain/dale.yaml", "ground: -0.1\n");
  first.write("terrain/dale.yaml", "ground: -0.2\n");
  const std::vector<std::string> dirs = {first.path.string(), second.path.string()};
  EXPECT_EQ(fs::path(findTerrainFile("hill", dirs)), second.path / "terrain" / "hill.yaml");
  // The first folder that has it.
  EXPECT_EQ(fs::path(findTerrainFile("dale", dirs)), first.path / "terrain" / "dale.yaml");
  // By path, as given.
  const std::string path = (second.path / "terrain" / "hill.yaml").string();
  EXPECT_EQ(findTerrainFile(path, dirs), path);
  EXPECT_EQ(findTerrainFile(path, {}), path);
  // Not found: where it looked is said.
  try {
    findTerrainFile("mountain", dirs);
    ADD_FAILURE() << "found a terrain that is not there";
  } catch (const TerrainFileError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("mountain"), std::string::npos) << what;
    EXPECT_NE(what.find((first.path / "terrain" / "mountain.yaml").string()), std::string::npos)
        << what;
    EXPECT_NE(what.find((second.path / "terrain" / "mountain.yaml").string()), std::string::npos)
        << what;
  }
  const std::string missing = (second.path / "terrain" / "mountain.yaml").string();
  try {
    findTerrainFile(missing, dirs);
    ADD_FAILURE() << "found a path that is not there";
  } catch (const TerrainFileError& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
}

// Every file shipped in config/terrain loads and makes a terrain with something on its ground.
TEST(TerrainFile, ShippedFilesLoad) {
  const fs::path folder = fs::path(STRIDE_CONFIG_DIR) / "terrain";
  std::vector<fs::path> files;
  if (fs::is_directory(folder))
    for (const fs::directory_entry& e : fs::directory_iterator(folder))
      if (e.path().extension() == ".yaml") files.push_back(e.path());
  ASSERT_FALSE(files.empty()) << "no terrain file in " << folder;
  for (const fs::path& f : files) {
    SCOPED_TRACE(f.string());
    TerrainSpec s;
    ASSERT_NO_THROW(s = loadTerrainFile(f.string()));
    EXPECT_EQ(s.name, f.stem().string());
    EXPECT_EQ(findTerrainFile(s.name, {STRIDE_CONFIG_DIR}), f.string());
    std::unique_ptr<Terrain> t;
    ASSERT_NO_THROW(t = std::make_unique<Terrain>(s));
    Eigen::Vector2d lo, hi;
    t->bounds(lo, hi);
    EXPECT_TRUE(lo.allFinite() && hi.allFinite());
    EXPECT_TRUE(std::isfinite(t->height(0.0, 0.0)));
  }
}

}  // namespace test_terrain_file
}  // namespace stride::terrain
