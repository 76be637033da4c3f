#pragma once
// The world the robot walks in: a height field made of a flat ground and pieces standing on it
// (boxes, ramps, staircases, rough patches), read by the mock robot, the controller and the
// viewer alike (ARCHITECTURE.md §2; the file format and the contact model: terrain/README.md).
//
// Every piece is a vertical prism: an oriented rectangle on the ground, solid from below up to its
// top surface (a plane for boxes and ramps, steps for a staircase, square cells for a rough patch).
// Where pieces overlap the highest top wins; a rough patch replaces the ground inside its
// rectangle, so a cell below the ground is a hole. The surface is thus a height field H(x, y) whose
// jumps are vertical faces (risers, box sides, a ramp's high end).
//
// Immutable after construction; every query allocates nothing and never throws.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

namespace stride::terrain {

// What a terrain file says (terrain_file.hpp reads it), in its own words.
struct BoxSpec {
  Eigen::Vector2d center = Eigen::Vector2d::Zero(), size = Eigen::Vector2d::Zero();
  double height = 0.0, yaw = 0.0;  // top at ground + height
};
struct RampSpec {
  Eigen::Vector2d from = Eigen::Vector2d::Zero(), to = Eigen::Vector2d::Zero();
  double width = 0.0, rise = 0.0;  // the top rises by `rise` from the `from` edge to the `to` edge
};
struct StairsSpec {
  Eigen::Vector2d start = Eigen::Vector2d::Zero();  // the foot of the first riser, mid-width
  double yaw = 0.0;                                 // direction of travel (0: +x)
  int steps = 0;
  double rise = 0.0, run = 0.0, width = 0.0, landing = 0.0;
};
struct RoughSpec {
  Eigen::Vector2d min = Eigen::Vector2d::Zero(), max = Eigen::Vector2d::Zero();
  double cell = 0.0, amplitude = 0.0;
  std::uint64_t seed = 0;
};
struct TerrainSpec {
  std::string name = "flat";  // the file's stem, for summaries
  double ground = 0.0;
  std::vector<BoxSpec> boxes;
  std::vector<RampSpec> ramps;
  std::vector<StairsSpec> stairs;
  std::vector<RoughSpec> rough;
};

// The surface at a place: the top that wins there, its height and upward unit normal.
struct Surface {
  double height = 0.0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};

// One way a point touches (or is about to touch) the terrain: the unilateral constraint
// distance >= 0 along `normal`, from the surface point `point`. Tangents t1, t2 complete a
// right-handed frame [t1 t2 normal] (friction acts in their plane).
struct Contact {
  enum class Kind : std::uint8_t { Support, Wall };
  Kind kind = Kind::Support;
  double distance = 0.0;  // signed, along normal: < 0 inside the terrain
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d t1 = Eigen::Vector3d::UnitX(), t2 = Eigen::Vector3d::UnitY();
  // True when the frame is exactly the world's (the flat ground's support): users skip the
  // rotation, so that a flat terrain gives the same bits as the plain ground plane did.
  bool world_axes = true;
};

class Terrain {
 public:
  // The flat ground z = ground.
  explicit Terrain(double ground = 0.0);
  // Throws std::invalid_argument for a spec that is not valid (the file loader checks first and
  // names the key).
  explicit Terrain(const TerrainSpec& spec);

  const TerrainSpec& spec() const { return spec_; }
  const std::string& name() const { return spec_.name; }
  // Only the flat ground: no piece at all.
  bool isFlat() const { return pieces_.empty(); }
  double ground() const { return spec_.ground; }

  // H(x, y): the highest top at (x, y). On a vertical face (a riser's line) the higher side's.
  double height(double x, double y) const;
  Surface surface(double x, double y) const;

  // The constraints of a point p within `reach` of the terrain (reach >= 0): the support under it
  // and the vertical faces beside it, at most `max` of them (the nearest), written to `out`.
  // Returns how many. A point inside the terrain gets the one way out that is shortest: up through
  // the top, or sideways through a face it crossed (a foot swept into a riser is pushed back out
  // of the riser, not up onto the step).
  int contacts(const Eigen::Vector3d& p, double reach, Contact* out, int max) const;

  // The horizontal distance from (x, y) to the nearest point of an edge: a line where H jumps by
  // more than `min_rise` (a riser, a box's side, a rough patch's cell edge or border, a ramp's
  // high end; a ramp's foot is a kink, not an edge), on either side of it (at the top of a drop or
  // at the foot of a wall), looked for within `radius` (finite, >= 0). +infinity when there is none
  // within it, when the terrain is flat, and for a place or radius that is not finite. The step is
  // read across each line as contacts() reads it; where it changes along a line (a ramp's side, a
  // rough patch's border, a face partly covered by a higher piece) the line is walked from its
  // point nearest (x, y) outwards in 1 mm steps and the change located by bisection (to 1 µm). What
  // the mock robot's edge_footholds count measures (sim/README.md).
  double edgeDistance(double x, double y, double min_rise, double radius) const;

  // The axis-aligned rectangle [min, max] that holds every piece (the ground's point when flat):
  // what a viewer or a map needs to cover.
  void bounds(Eigen::Vector2d& min, Eigen::Vector2d& max) const;

 private:
  enum class PieceKind : std::uint8_t { Block, Stairs, Rough };
  // An oriented rectangle: centre, unit axes u (length) and w (width), half extents.
  struct Piece {
    PieceKind kind = PieceKind::Block;
    Eigen::Vector2d center = Eigen::Vector2d::Zero(), u = Eigen::Vector2d::UnitX(),
                    w = Eigen::Vector2d::UnitY();
    double half_u = 0.0, half_w = 0.0;
    // Block: top = z0 + slope * (distance along u from the centre).
    double z0 = 0.0, slope = 0.0;
    // Stairs: steps of `run` along u from the rectangle's -u edge, the last one `last_length` long;
    // step k's top is base + (k + 1) * rise. Rough: square cells of `run` from the -u, -w corner,
    // heights ground + amplitude * r(seed, i, j) with r uniform in [-1, 1].
    int steps = 0;
    double base = 0.0, rise = 0.0, run = 0.0, amplitude = 0.0;
    std::uint64_t seed = 0;
    int cells_u = 0, cells_w = 0;
  };
  // (x, y) in the piece's axes, from its -u, -w corner.
  static Eigen::Vector2d local(const Piece& piece, const Eigen::Vector2d& xy);
  static bool inside(const Piece& piece, const Eigen::Vector2d& corner_xy);
  // The top of the piece at a place inside it (its corner coordinates), and its gradient.
  double top(const Piece& piece, const Eigen::Vector2d& corner_xy) const;
  double roughCell(const Piece& piece, int i, int j) const;
  // H(x, y) and which piece gives it (-1: the ground).
  double heightAndPiece(const Eigen::Vector2d& xy, int& piece) const;
  // One line segment [a, b] of a piece: a wall when H jumps across it at the point nearest p
  // (h_here: H at p's place). Kept in out[0..n) when p is in front of it; the shortest way out
  // through a crossed face in inside_exit / inside_wall.
  void wallAt(const Eigen::Vector3d& p, double h_here, const Eigen::Vector2d& a,
              const Eigen::Vector2d& b, double reach, Contact* out, int& n, int max,
              double& inside_exit, Contact& inside_wall) const;

  TerrainSpec spec_;
  std::vector<Piece> pieces_;
  std::vector<int> rough_;  // indices of the rough pieces (they replace the ground)
  Eigen::Vector2d min_ = Eigen::Vector2d::Zero(), max_ = Eigen::Vector2d::Zero();
};

// Completes a unit normal n to a right-handed frame [t1 t2 n]: t1 the world x axis (or y when n is
// nearly x) projected on the tangent plane.
void tangentFrame(const Eigen::Vector3d& n, Eigen::Vector3d& t1, Eigen::Vector3d& t2);

}  // namespace stride::terrain
