#pragma once
// Terrain files, config/terrain/*.yaml: the one documented format (terrain/README.md).
//
//   ground: 0.0                 # height of the flat ground around everything [m]
//   boxes:  [{center: [x, y], size: [sx, sy], height: h, yaw: 0.0}]
//   ramps:  [{from: [x0, y0], to: [x1, y1], width: w, rise: r}]
//   stairs: [{start: [x, y], yaw: 0.0, steps: n, rise: r, run: d, width: w, landing: l}]
//   rough:  [{min: [x0, y0], max: [x1, y1], cell: c, amplitude: a, seed: s}]
//
// Every error (a file that does not parse, an unknown key, a missing one, a negative size, a cell
// of 0) is a TerrainFileError naming the file and the key.

#include <stdexcept>
#include <string>
#include <vector>

#include "terrain/terrain.hpp"

namespace stride::terrain {

// A terrain file that cannot be read, found or accepted; what() names the file and the key
// ("terrain file 'mine.yaml': stairs[0].run: must be > 0 (got -0.25)"). The terrain's own type, not
// config's ConfigError: terrain/ sits on the floor below config/ and includes nothing of it. Like
// ConfigError it is a std::runtime_error, which is what the programs catch and print.
class TerrainFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reads and checks a terrain file; the spec's name is the file's stem ("stairs_anymal_c").
TerrainSpec loadTerrainFile(const std::string& path);
// The same from YAML text; `source` names it in errors and gives the name.
TerrainSpec parseTerrain(const std::string& yaml, const std::string& source);

// A terrain by file path, or by name in <config_dir>/terrain/<name>.yaml (the first folder that
// has it). Throws TerrainFileError listing where it looked.
std::string findTerrainFile(const std::string& name_or_path,
                            const std::vector<std::string>& config_dirs);
// Where the programs look for terrains by name: the source tree's config/ (a build tree) and the
// installed share/stride/config beside the running program's bin/.
std::vector<std::string> terrainConfigDirs();

}  // namespace stride::terrain
