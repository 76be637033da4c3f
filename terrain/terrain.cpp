#include "terrain/terrain.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace stride::terrain {

namespace {
// Heights this close are one surface: no face between them (a ramp's foot meets the ground at a
// kink, not a wall; the 0.1 mm floor also hides the rounding of a plane's edge).
constexpr double kMinFace = 1e-4;
// How far either side of a line the two heights of a face are read [m].
constexpr double kSide = 1e-7;
// A point this far below the lower side of a face still feels the face (a foot standing in the
// corner of a riser has sunk into the ground by the contact solver's slop, 0.1 mm).
constexpr double kBelowLowSide = 0.01;
// How far sideways a point inside the terrain looks for the face it came through [m]: deeper than
// that it leaves upwards (a tunnel a 1 kHz step never makes: 5 cm in 1 ms is 50 m/s).
constexpr double kMaxInsideSearch = 0.05;

// SplitMix64 (Steele, Lea, Flood 2014): a stateless hash of a rough cell's indices, so that a
// cell's height needs no table and no draw order.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

Eigen::Vector2d axis(double yaw) {
  return {std::cos(yaw), std::sin(yaw)};
}

void fail(const std::string& what) {
  throw std::invalid_argument("terrain: " + what);
}
bool positive(double x) {
  return std::isfinite(x) && x > 0.0;
}
bool finite2(const Eigen::Vector2d& v) {
  return v.allFinite();
}
}  // namespace

void tangentFrame(const Eigen::Vector3d& n, Eigen::Vector3d& t1, Eigen::Vector3d& t2) {
  const Eigen::Vector3d seed =
      std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  t1 = (seed - seed.dot(n) * n).normalized();
  t2 = n.cross(t1);
}

Terrain::Terrain(double ground) {
  if (!std::isfinite(ground)) fail("the ground height must be finite");
  spec_.ground = ground;
  min_ = max_ = Eigen::Vector2d::Zero();
}

Terrain::Terrain(const TerrainSpec& spec) : Terrain(spec.ground) {
  spec_ = spec;
  // Rough patches first: they replace the ground, and a staircase standing on one starts on its
  // cell.
  for (const RoughSpec& r : spec.rough) {
    if (!finite2(r.min) || !finite2(r.max) || !(r.max.array() > r.min.array()).all())
      fail("a rough patch needs max > min");
    if (!positive(r.cell)) fail("a rough patch needs a cell > 0");
    if (!(std::isfinite(r.amplitude) && r.amplitude >= 0.0)) fail("rough amplitude must be >= 0");
    Piece p;
    p.kind = PieceKind::Rough;
    p.center = 0.5 * (r.min + r.max);
    p.half_u = 0.5 * (r.max.x() - r.min.x());
    p.half_w = 0.5 * (r.max.y() - r.min.y());
    p.run = r.cell;
    p.amplitude = r.amplitude;
    p.seed = r.seed;
    // Cells tile the patch from its min corner; the last row and column are cut by max.
    p.cells_u = std::max(1, static_cast<int>(std::ceil(2.0 * p.half_u / r.cell - 1e-9)));
    p.cells_w = std::max(1, static_cast<int>(std::ceil(2.0 * p.half_w / r.cell - 1e-9)));
    rough_.push_back(static_cast<int>(pieces_.size()));
    pieces_.push_back(p);
  }
  for (const BoxSpec& b : spec.boxes) {
    if (!finite2(b.center) || !std::isfinite(b.yaw) || !std::isfinite(b.height))
      fail("a box needs finite numbers");
    if (!positive(b.size.x()) || !positive(b.size.y())) fail("a box needs a size > 0");
    Piece p;
    p.center = b.center;
    p.u = axis(b.yaw);
    p.w = {-p.u.y(), p.u.x()};
    p.half_u = 0.5 * b.size.x();
    p.half_w = 0.5 * b.size.y();
    p.z0 = spec.ground + b.height;
    pieces_.push_back(p);
  }
  for (const RampSpec& r : spec.ramps) {
    const Eigen::Vector2d d = r.to - r.from;
    if (!finite2(r.from) || !finite2(r.to) || !std::isfinite(r.rise))
      fail("a ramp needs finite numbers");
    if (!positive(d.norm())) fail("a ramp needs from != to");
    if (!positive(r.width)) fail("a ramp needs a width > 0");
    Piece p;
    p.center = 0.5 * (r.from + r.to);
    p.u = d.normalized();
    p.w = {-p.u.y(), p.u.x()};
    p.half_u = 0.5 * d.norm();
    p.half_w = 0.5 * r.width;
    p.z0 = spec.ground + 0.5 * r.rise;
    p.slope = r.rise / d.norm();
    pieces_.push_back(p);
  }
  for (const StairsSpec& s : spec.stairs) {
    if (!finite2(s.start) || !std::isfinite(s.yaw) || !std::isfinite(s.rise))
      fail("stairs need finite numbers");
    if (s.steps < 1) fail("stairs need steps >= 1");
    if (!positive(s.run) || !positive(s.width)) fail("stairs need run and width > 0");
    if (!(std::isfinite(s.landing) && s.landing >= 0.0)) fail("the stairs' landing must be >= 0");
    Piece p;
    p.kind = PieceKind::Stairs;
    p.u = axis(s.yaw);
    p.w = {-p.u.y(), p.u.x()};
    const double length = s.steps * s.run + s.landing;
    p.center = s.start + 0.5 * length * p.u;
    p.half_u = 0.5 * length;
    p.half_w = 0.5 * s.width;
    p.steps = s.steps;
    p.rise = s.rise;
    p.run = s.run;
    // On the surface under its start: what the pieces before it make there, read just before the
    // first riser (the staircase itself is not built yet).
    int below = -1;
    p.base = heightAndPiece(s.start - kSide * p.u, below);
    pieces_.push_back(p);
  }
  if (!pieces_.empty()) {
    min_.setConstant(std::numeric_limits<double>::infinity());
    max_.setConstant(-std::numeric_limits<double>::infinity());
    for (const Piece& p : pieces_)
      for (int su = -1; su <= 1; su += 2)
        for (int sw = -1; sw <= 1; sw += 2) {
          const Eigen::Vector2d c = p.center + su * p.half_u * p.u + sw * p.half_w * p.w;
          min_ = min_.cwiseMin(c);
          max_ = max_.cwiseMax(c);
        }
  }
}

void Terrain::bounds(Eigen::Vector2d& min, Eigen::Vector2d& max) const {
  min = min_;
  max = max_;
}

Eigen::Vector2d Terrain::local(const Piece& piece, const Eigen::Vector2d& xy) {
  const Eigen::Vector2d d = xy - piece.center;
  return {d.dot(piece.u) + piece.half_u, d.dot(piece.w) + piece.half_w};
}

bool Terrain::inside(const Piece& piece, const Eigen::Vector2d& c) {
  return c.x() >= 0.0 && c.x() <= 2.0 * piece.half_u && c.y() >= 0.0 && c.y() <= 2.0 * piece.half_w;
}

double Terrain::roughCell(const Piece& piece, int i, int j) const {
  const std::uint64_t key =
      mix(piece.seed) ^ mix((static_cast<std::uint64_t>(static_cast<std::uint32_t>(i)) << 32) |
                            static_cast<std::uint32_t>(j));
  const double unit = static_cast<double>(mix(key) >> 11) * 0x1.0p-53;  // [0, 1)
  return spec_.ground + piece.amplitude * (2.0 * unit - 1.0);
}

double Terrain::top(const Piece& piece, const Eigen::Vector2d& c) const {
  // On a line between two steps or cells the higher side's (the face's top: terrain.hpp).
  // (Within rounding of the line: a place computed as on it, in world coordinates, lands a few ulps
  // either side of it in the piece's.)
  auto index = [](double x, double run, int last, int& other) {
    const double u = x / run, line = std::round(u);
    if (std::abs(u - line) <= 1e-9 * std::max(1.0, std::abs(u)) && line >= 1.0 && line <= last) {
      other = static_cast<int>(line) - 1;
      return static_cast<int>(line);
    }
    const int k = std::clamp(static_cast<int>(std::floor(u)), 0, last);
    other = k;
    return k;
  };
  switch (piece.kind) {
    case PieceKind::Block:
      return piece.z0 + piece.slope * (c.x() - piece.half_u);
    case PieceKind::Stairs: {
      int k0;
      const int k = index(c.x(), piece.run, piece.steps - 1, k0);
      const int higher = piece.rise > 0.0 ? std::max(k, k0) : std::min(k, k0);
      return piece.base + (higher + 1) * piece.rise;
    }
    case PieceKind::Rough: {
      int i0, j0;
      const int i = index(c.x(), piece.run, piece.cells_u - 1, i0);
      const int j = index(c.y(), piece.run, piece.cells_w - 1, j0);
      return std::max(std::max(roughCell(piece, i, j), roughCell(piece, i0, j)),
                      std::max(roughCell(piece, i, j0), roughCell(piece, i0, j0)));
    }
  }
  return spec_.ground;
}

double Terrain::heightAndPiece(const Eigen::Vector2d& xy, int& which) const {
  // The ground, unless a rough patch replaces it here.
  bool ground = true;
  for (int r : rough_)
    if (inside(pieces_[r], local(pieces_[r], xy))) {
      ground = false;
      break;
    }
  double h = ground ? spec_.ground : -std::numeric_limits<double>::infinity();
  which = -1;
  for (size_t k = 0; k < pieces_.size(); ++k) {
    const Piece& p = pieces_[k];
    const Eigen::Vector2d c = local(p, xy);
    if (!inside(p, c)) continue;
    const double z = top(p, c);
    if (z > h) {
      h = z;
      which = static_cast<int>(k);
    }
  }
  return h;
}

double Terrain::height(double x, double y) const {
  if (pieces_.empty()) return spec_.ground;
  int which;
  return heightAndPiece({x, y}, which);
}

Surface Terrain::surface(double x, double y) const {
  Surface s;
  if (pieces_.empty()) {
    s.height = spec_.ground;
    return s;
  }
  int which;
  s.height = heightAndPiece({x, y}, which);
  if (which >= 0 && pieces_[which].kind == PieceKind::Block && pieces_[which].slope != 0.0) {
    const Piece& p = pieces_[which];
    s.normal = Eigen::Vector3d(-p.slope * p.u.x(), -p.slope * p.u.y(), 1.0).normalized();
  }
  return s;
}

namespace {
// The support constraint of p on a surface (height and normal at p's place): the distance along
// the normal to the surface's plane.
Contact support(const Eigen::Vector3d& p, const Surface& s) {
  Contact c;
  c.kind = Contact::Kind::Support;
  c.normal = s.normal;
  c.distance = (p.z() - s.height) * s.normal.z();
  c.point = p - c.distance * s.normal;
  if (s.normal.x() != 0.0 || s.normal.y() != 0.0) {
    tangentFrame(s.normal, c.t1, c.t2);
    c.world_axes = false;
  }
  return c;
}

// Keeps the `max` nearest of the walls found so far (out[0..n)), adding one. The same face twice
// (a box's corner, reached from both of its sides) counts once.
void keepNearest(Contact* out, int& n, int max, const Contact& c) {
  for (int i = 0; i < n; ++i)
    if ((out[i].point - c.point).squaredNorm() < 1e-20 && out[i].normal.dot(c.normal) > 1.0 - 1e-12)
      return;
  if (n < max) {
    out[n++] = c;
    return;
  }
  int far = 0;
  for (int i = 1; i < n; ++i)
    if (out[i].distance > out[far].distance) far = i;
  if (c.distance < out[far].distance) out[far] = c;
}
}  // namespace

void Terrain::wallAt(const Eigen::Vector3d& p, double h_here, const Eigen::Vector2d& a,
                     const Eigen::Vector2d& b, double reach, Contact* out, int& n, int max,
                     double& inside_exit, Contact& inside_wall) const {
  const Eigen::Vector2d xy = p.head<2>(), ab = b - a;
  const double t = std::clamp((xy - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  const Eigen::Vector2d e = a + t * ab;
  const Eigen::Vector2d to_p = xy - e;
  const double dh = to_p.norm();
  if (dh > std::max(reach, std::min(h_here - p.z(), kMaxInsideSearch))) return;
  const Eigen::Vector2d m = Eigen::Vector2d(-ab.y(), ab.x()).normalized();
  int wa, wb;
  const double ha = heightAndPiece(e + kSide * m, wa), hb = heightAndPiece(e - kSide * m, wb);
  if (std::abs(ha - hb) < kMinFace) return;
  const double hi = std::max(ha, hb), lo = std::min(ha, hb);
  if (!(p.z() < hi && p.z() > lo - kBelowLowSide)) return;  // above the face, or under both sides
  const Eigen::Vector2d to_low = ha < hb ? m : Eigen::Vector2d(-m);
  const double side = to_p.dot(to_low);
  Contact c;
  c.kind = Contact::Kind::Wall;
  c.point = Eigen::Vector3d(e.x(), e.y(), p.z());
  c.world_axes = false;
  // In front of the face (on its low side, where the ground is below the face's top), or in it
  // from the high side (crossed: p's place is the high side's, p under its top).
  if (side > 0.0 && h_here < hi - kMinFace && dh <= reach) {
    const Eigen::Vector2d dir = dh > 1e-12 ? Eigen::Vector2d(to_p / dh) : to_low;
    c.normal = Eigen::Vector3d(dir.x(), dir.y(), 0.0);
    c.distance = dh;
    tangentFrame(c.normal, c.t1, c.t2);
    keepNearest(out, n, max, c);
  } else if (side <= 0.0 && t > 0.0 && t < 1.0 && h_here > hi - kMinFace &&
             p.z() > lo - kBelowLowSide) {
    // Inside the high side's solid, above the low side: out through this face takes dh.
    const double exit = std::max(0.0, -side);
    if (exit < inside_exit) {
      inside_exit = exit;
      c.normal = Eigen::Vector3d(to_low.x(), to_low.y(), 0.0);
      c.distance = -exit;
      tangentFrame(c.normal, c.t1, c.t2);
      inside_wall = c;
    }
  }
}

int Terrain::contacts(const Eigen::Vector3d& p, double reach, Contact* out, int max) const {
  if (max < 1) return 0;
  const Surface here = surface(p.x(), p.y());
  // A point that is not a place (NaN) gets the ground's support only: no line index is computed
  // from it (a NaN cast to an index is undefined behaviour).
  if (pieces_.empty() || !p.allFinite()) {
    out[0] = support(p, here);
    return 1;
  }
  // Walls (after the support slot), and the shortest way out sideways if p is inside a face.
  int n = 0;
  Contact* walls = out + 1;
  const int max_walls = max - 1;
  double inside_exit = std::numeric_limits<double>::infinity();
  Contact inside_wall;
  const Eigen::Vector2d xy = p.head<2>();
  // A point inside the terrain looks for the face it crossed as far as it is deep (a foot resting
  // on the ground swept into a riser within one step may be past the reach), up to a bound.
  const double search = std::max(reach, std::min(here.height - p.z(), kMaxInsideSearch));
  for (const Piece& piece : pieces_) {
    const Eigen::Vector2d c = local(piece, xy);
    const double lu = 2.0 * piece.half_u, lw = 2.0 * piece.half_w;
    // Far from the rectangle: none of its lines is within reach.
    if (c.x() < -search || c.x() > lu + search || c.y() < -search || c.y() > lw + search) continue;
    auto at = [&](double x, double y) -> Eigen::Vector2d {
      return piece.center + (x - piece.half_u) * piece.u + (y - piece.half_w) * piece.w;
    };
    auto line = [&](double x0, double y0, double x1, double y1) {
      wallAt(p, here.height, at(x0, y0), at(x1, y1), reach, walls, n, max_walls, inside_exit,
             inside_wall);
    };
    line(0, 0, lu, 0);
    line(lu, 0, lu, lw);
    line(lu, lw, 0, lw);
    line(0, lw, 0, 0);
    if (piece.kind == PieceKind::Block) continue;
    // Interior lines within reach: a staircase's risers, a rough patch's cell edges.
    const int last_u = piece.kind == PieceKind::Stairs ? piece.steps - 1 : piece.cells_u - 1;
    const int i0 = std::max(1, static_cast<int>(std::ceil((c.x() - search) / piece.run)));
    const int i1 = std::min(last_u, static_cast<int>(std::floor((c.x() + search) / piece.run)));
    for (int i = i0; i <= i1; ++i) line(i * piece.run, 0, i * piece.run, lw);
    if (piece.kind == PieceKind::Rough) {
      const int j0 = std::max(1, static_cast<int>(std::ceil((c.y() - search) / piece.run)));
      const int j1 =
          std::min(piece.cells_w - 1, static_cast<int>(std::floor((c.y() + search) / piece.run)));
      for (int j = j0; j <= j1; ++j) line(0, j * piece.run, lu, j * piece.run);
    }
  }
  Contact up = support(p, here);
  if (up.distance < 0.0 && inside_exit < -up.distance) {
    // Crossed a face sideways (a foot swept into a riser): out through that face, standing on the
    // low side's surface just in front of it.
    const Eigen::Vector2d front =
        inside_wall.point.head<2>() + kSide * inside_wall.normal.head<2>();
    up = support(p, surface(front.x(), front.y()));
    keepNearest(walls, n, max_walls, inside_wall);
  }
  out[0] = up;
  return 1 + n;
}

double Terrain::edgeDistance(double x, double y, double min_rise, double radius) const {
  // The walk along a line where the step changes, and the bisection's tolerance [m].
  constexpr double kWalk = 1e-3, kLocate = 1e-6;
  double best = std::numeric_limits<double>::infinity();
  if (pieces_.empty() || !std::isfinite(x) || !std::isfinite(y) || !(radius >= 0.0) ||
      !std::isfinite(radius))
    return best;
  const Eigen::Vector2d xy(x, y);
  auto edgeAt = [&](const Eigen::Vector2d& e, const Eigen::Vector2d& m) {
    int wa, wb;
    return std::abs(heightAndPiece(e + kSide * m, wa) - heightAndPiece(e - kSide * m, wb)) >
           min_rise;
  };
  // One line segment [a, b]: its nearest edge point within min(best, radius).
  auto line = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const Eigen::Vector2d ab = b - a;
    const double length = ab.norm();
    if (!(length > 0.0)) return;
    const Eigen::Vector2d dir = ab / length, m(-dir.y(), dir.x());
    auto at = [&](double s) -> Eigen::Vector2d { return a + s * dir; };
    auto distance = [&](double s) { return (xy - at(s)).norm(); };
    const double s0 = std::clamp((xy - a).dot(dir), 0.0, length);
    if (distance(s0) > std::min(best, radius)) return;
    if (edgeAt(at(s0), m)) {
      best = distance(s0);
      return;
    }
    // The distance grows away from s0 on either side: the first edge point each way is the
    // nearest on that side.
    for (double sign : {1.0, -1.0}) {
      double below = s0;
      for (int k = 1;; ++k) {
        const double s = std::clamp(s0 + sign * k * kWalk, 0.0, length);
        if (s == below || distance(s) > std::min(best, radius)) break;
        if (edgeAt(at(s), m)) {
          double above = s;
          while (std::abs(above - below) > kLocate) {
            const double mid = 0.5 * (below + above);
            (edgeAt(at(mid), m) ? above : below) = mid;
          }
          best = std::min(best, distance(above));
          break;
        }
        below = s;
      }
    }
  };
  for (const Piece& piece : pieces_) {
    const Eigen::Vector2d c = local(piece, xy);
    const double lu = 2.0 * piece.half_u, lw = 2.0 * piece.half_w;
    if (c.x() < -radius || c.x() > lu + radius || c.y() < -radius || c.y() > lw + radius) continue;
    auto at = [&](double u, double w) -> Eigen::Vector2d {
      return piece.center + (u - piece.half_u) * piece.u + (w - piece.half_w) * piece.w;
    };
    line(at(0, 0), at(lu, 0));
    line(at(lu, 0), at(lu, lw));
    line(at(lu, lw), at(0, lw));
    line(at(0, lw), at(0, 0));
    if (piece.kind == PieceKind::Block) continue;
    const int last_u = piece.kind == PieceKind::Stairs ? piece.steps - 1 : piece.cells_u - 1;
    const int i0 = std::max(1, static_cast<int>(std::ceil((c.x() - radius) / piece.run)));
    const int i1 = std::min(last_u, static_cast<int>(std::floor((c.x() + radius) / piece.run)));
    for (int i = i0; i <= i1; ++i) line(at(i * piece.run, 0), at(i * piece.run, lw));
    if (piece.kind == PieceKind::Rough) {
      const int j0 = std::max(1, static_cast<int>(std::ceil((c.y() - radius) / piece.run)));
      const int j1 =
          std::min(piece.cells_w - 1, static_cast<int>(std::floor((c.y() + radius) / piece.run)));
      for (int j = j0; j <= j1; ++j) line(at(0, j * piece.run), at(lu, j * piece.run));
    }
  }
  return best;
}

}  // namespace stride::terrain
