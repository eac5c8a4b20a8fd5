// Coverage of a footprint by the tiles given and by its points (crop.hpp): the area share inside
// the union of the tiles' extents, by clipping the footprint to the cells of that union's grid, and
// the share of its cells that hold a point.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <tuple>
#include <utility>
#include <vector>

#include "city3d/crop.hpp"

namespace city3d {
namespace {

/// Twice the signed area of a ring (shoelace formula, positive when counter-clockwise).
double twice_area(const Ring2& ring) {
  double sum = 0.0;
  for (std::size_t i = 0, n = ring.size(); i < n; ++i) {
    const Point2& a = ring[i];
    const Point2& b = ring[(i + 1) % n];
    sum += a.x * b.y - b.x * a.y;
  }
  return sum;
}

/// The ring clipped to an axis-aligned box (Sutherland-Hodgman, one box side at a time). The result
/// of a concave ring may run along the box's sides, but its area is that of the ring inside the box.
Ring2 clip(const Ring2& ring, const Box2& box) {
  Ring2 out = ring;
  // Each side: inside(p) and the crossing point of segment a-b with the side's line.
  for (int side = 0; side < 4 && !out.empty(); ++side) {
    const auto inside = [&](const Point2& p) {
      switch (side) {
        case 0: return p.x >= box.min.x;
        case 1: return p.x <= box.max.x;
        case 2: return p.y >= box.min.y;
        default: return p.y <= box.max.y;
      }
    };
    const auto cross = [&](const Point2& a, const Point2& b) {
      const bool vertical_line = side < 2;
      const double at = side == 0 ? box.min.x : side == 1 ? box.max.x : side == 2 ? box.min.y : box.max.y;
      if (vertical_line) {
        const double t = (at - a.x) / (b.x - a.x);
        return Point2{at, a.y + t * (b.y - a.y)};
      }
      const double t = (at - a.y) / (b.y - a.y);
      return Point2{a.x + t * (b.x - a.x), at};
    };
    Ring2 in;
    in.swap(out);
    for (std::size_t i = 0, n = in.size(); i < n; ++i) {
      const Point2& a = in[(i + n - 1) % n];
      const Point2& b = in[i];
      if (inside(b)) {
        if (!inside(a)) out.push_back(cross(a, b));
        out.push_back(b);
      } else if (inside(a)) {
        out.push_back(cross(a, b));
      }
    }
  }
  return out;
}

/// Area of the footprint inside a box: each outer ring's part minus its holes' parts (holes lie
/// inside their outer ring and apart from each other).
double area_inside(const std::vector<Polygon2>& footprint, const Box2& box) {
  double twice = 0.0;
  for (const Polygon2& p : footprint) {
    twice += std::fabs(twice_area(clip(p.outer, box)));
    for (const Ring2& hole : p.holes) twice -= std::fabs(twice_area(clip(hole, box)));
  }
  return std::max(twice / 2, 0.0);
}

double area_of(const std::vector<Polygon2>& footprint) {
  double twice = 0.0;
  for (const Polygon2& p : footprint) {
    twice += std::fabs(twice_area(p.outer));
    for (const Ring2& hole : p.holes) twice -= std::fabs(twice_area(hole));
  }
  return std::max(twice / 2, 0.0);
}

/// Even-odd test over every ring of every polygon (holes excluded).
bool inside(const std::vector<Polygon2>& footprint, double x, double y) {
  for (const Polygon2& p : footprint) {
    bool in = false;
    const auto ring_crossings = [&](const Ring2& ring) {
      for (std::size_t i = 0, n = ring.size(); i < n; ++i) {
        const Point2& a = ring[i];
        const Point2& b = ring[(i + 1) % n];
        if ((a.y > y) != (b.y > y) && x < a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y)) in = !in;
      }
    };
    ring_crossings(p.outer);
    for (const Ring2& hole : p.holes) ring_crossings(hole);
    if (in) return true;
  }
  return false;
}

/// The share of the footprint's area inside the union of `extents`: the union cut into the cells of
/// the grid its boxes' sides make, each cell in the union clipping the footprint once.
double area_share(const std::vector<Polygon2>& footprint, const std::vector<Box2>& extents) {
  Box2 box;
  for (const Polygon2& p : footprint)
    for (const Point2& v : p.outer) box.add(v);
  const double total = area_of(footprint);
  if (box.empty() || !(total > 0)) return 0.0;
  std::vector<Box2> meeting;
  for (const Box2& e : extents) {
    if (e.empty() || !e.intersects(box)) continue;
    // Inside one extent: all of it (the usual case, and exactly 1).
    if (e.min.x <= box.min.x && e.min.y <= box.min.y && e.max.x >= box.max.x && e.max.y >= box.max.y) return 1.0;
    meeting.push_back(e);
  }
  if (meeting.empty()) return 0.0;
  std::vector<double> xs{box.min.x, box.max.x}, ys{box.min.y, box.max.y};
  for (const Box2& e : meeting) {
    for (double x : {e.min.x, e.max.x})
      if (x > box.min.x && x < box.max.x) xs.push_back(x);
    for (double y : {e.min.y, e.max.y})
      if (y > box.min.y && y < box.max.y) ys.push_back(y);
  }
  std::sort(xs.begin(), xs.end());
  std::sort(ys.begin(), ys.end());
  double covered = 0.0;
  for (std::size_t i = 0; i + 1 < xs.size(); ++i)
    for (std::size_t j = 0; j + 1 < ys.size(); ++j) {
      const double cx = (xs[i] + xs[i + 1]) / 2, cy = (ys[j] + ys[j + 1]) / 2;
      const bool in_union = std::any_of(meeting.begin(), meeting.end(), [&](const Box2& e) {
        return cx >= e.min.x && cx <= e.max.x && cy >= e.min.y && cy <= e.max.y;
      });
      if (!in_union || xs[i + 1] <= xs[i] || ys[j + 1] <= ys[j]) continue;
      Box2 cell;
      cell.add({xs[i], ys[j]});
      cell.add({xs[i + 1], ys[j + 1]});
      covered += area_inside(footprint, cell);
    }
  return std::clamp(covered / total, 0.0, 1.0);
}

/// Of the footprint's cells (lattice `cell`, aligned in world coordinates; the footprint and `points`
/// local, world = local + origin): the share where the presence lattice has a point, and of those the
/// share holding one of `points` (NaN when none has a point).
std::pair<double, double> cell_shares(const std::vector<Polygon2>& footprint, const Point3& origin,
                                      const PointPresence& presence, const std::vector<Point3>& points,
                                      double cell) {
  const double unknown = std::numeric_limits<double>::quiet_NaN();
  Box2 box;
  for (const Polygon2& p : footprint)
    for (const Point2& v : p.outer) box.add(v);
  if (box.empty() || presence.nx == 0) return {0.0, unknown};
  // A coverage cell is exactly m x m presence cells: both lattices start at world 0.
  const auto m = static_cast<std::int64_t>(std::llround(cell / presence.cell));
  const auto first_i = static_cast<std::int64_t>(std::floor((box.min.x + origin.x) / cell));
  const auto last_i = static_cast<std::int64_t>(std::floor((box.max.x + origin.x) / cell));
  const auto first_j = static_cast<std::int64_t>(std::floor((box.min.y + origin.y) / cell));
  const auto last_j = static_cast<std::int64_t>(std::floor((box.max.y + origin.y) / cell));
  // The cells of the box holding a building point (the points lie in the footprint, so in its box).
  const std::int64_t nx = last_i - first_i + 1, ny = last_j - first_j + 1;
  std::vector<bool> building(static_cast<std::size_t>(nx * ny), false);
  for (const Point3& p : points) {
    const auto i = static_cast<std::int64_t>(std::floor((p.x + origin.x) / cell)) - first_i;
    const auto j = static_cast<std::int64_t>(std::floor((p.y + origin.y) / cell)) - first_j;
    if (i >= 0 && j >= 0 && i < nx && j < ny) building[static_cast<std::size_t>(j * nx + i)] = true;
  }
  std::size_t cells = 0, with_points = 0, with_building = 0;
  for (std::int64_t j = first_j; j <= last_j; ++j)
    for (std::int64_t i = first_i; i <= last_i; ++i) {
      if (!inside(footprint, (i + 0.5) * cell - origin.x, (j + 0.5) * cell - origin.y)) continue;
      ++cells;
      bool any = false;
      for (std::int64_t b = j * m; b < (j + 1) * m && !any; ++b)
        for (std::int64_t a = i * m; a < (i + 1) * m && !any; ++a) any = presence.at(a, b);
      with_points += any;
      with_building += any && building[static_cast<std::size_t>((j - first_j) * nx + (i - first_i))];
    }
  if (cells > 0)
    return {
        static_cast<double>(with_points) / static_cast<double>(cells),
        with_points > 0 ? static_cast<double>(with_building) / static_cast<double>(with_points) : unknown};
  // A footprint narrower than a cell everywhere: one cell, its box.
  const bool any = std::find(presence.marked.begin(), presence.marked.end(), true) != presence.marked.end();
  return {any ? 1.0 : 0.0, any ? (points.empty() ? 0.0 : 1.0) : unknown};
}

}  // namespace

double point_spacing(const Box3& bounds, std::uint64_t points) {
  if (bounds.empty() || points == 0) return 0.0;
  const double area = (bounds.max.x - bounds.min.x) * (bounds.max.y - bounds.min.y);
  return std::sqrt(std::max(area, 0.0) / static_cast<double>(points));
}

Box2 tile_extent(const Box3& bounds, std::uint64_t points) {
  Box2 extent;
  if (bounds.empty() || points == 0) return extent;
  const double grow = point_spacing(bounds, points) / 2;
  extent.add({bounds.min.x - grow, bounds.min.y - grow});
  extent.add({bounds.max.x + grow, bounds.max.y + grow});
  return extent;
}

double coverage_cell_size(double spacing, double presence_cell) {
  const double cell = std::max(1.0, 3 * spacing);
  return presence_cell * std::ceil(cell / presence_cell - 1e-9);
}

FootprintCoverage footprint_coverage(const BuildingInput& input, const std::vector<Box2>& extents, double spacing) {
  FootprintCoverage c;
  c.area = area_share(input.footprint.polygons, extents);
  std::tie(c.cells, c.building) = cell_shares(input.footprint.polygons, input.origin, input.presence,
                                              input.points, coverage_cell_size(spacing, input.presence.cell));
  return c;
}

}  // namespace city3d
