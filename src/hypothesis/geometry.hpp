// Plain geometry helpers shared by the steps of the face hypothesis (no CGAL): point-in-polygon and
// distances in xy, Newell normals and centroids of 3D polygons, roof heights, and a uniform xy grid
// over points. Private to src/hypothesis.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "city3d/planes.hpp"
#include "city3d/types.hpp"

namespace city3d::detail {

// A uniform xy grid over a set of points (the support and plane-ranking loops ask for the points in
// a box; without an index they scanned every point for every cell and wall face). Each entry is a
// payload index; queries return every entry whose bin meets the box (callers test exactly).
class PointGrid {
 public:
  // `xy(i)` gives the position of entry i, for i in 0..count-1.
  template <typename XY>
  PointGrid(std::size_t count, XY xy) {
    Box2 box;
    for (std::size_t i = 0; i < count; ++i) box.add(xy(i));
    if (box.empty()) return;
    origin_ = box.min;
    const double w = box.max.x - box.min.x, h = box.max.y - box.min.y;
    // About four entries per bin, at most ~1M bins, never below 10 cm.
    size_ = std::max(0.1, std::sqrt(std::max(w * h, 1e-6) * 4.0 / static_cast<double>(count)));
    while ((w / size_ + 1.0) * (h / size_ + 1.0) > 1e6) size_ *= 2.0;
    nx_ = static_cast<long>(w / size_) + 1;
    ny_ = static_cast<long>(h / size_) + 1;
    bins_.assign(static_cast<std::size_t>(nx_ * ny_), {});
    for (std::size_t i = 0; i < count; ++i) {
      const Point2 p = xy(i);
      bins_[static_cast<std::size_t>(bin_y(p.y) * nx_ + bin_x(p.x))].push_back(static_cast<std::uint32_t>(i));
    }
  }
  template <typename Visit>
  void for_each_in(double x0, double y0, double x1, double y1, Visit visit) const {
    if (bins_.empty() || x1 < x0 || y1 < y0) return;
    const long i0 = bin_x(x0), i1 = bin_x(x1), j0 = bin_y(y0), j1 = bin_y(y1);
    for (long j = j0; j <= j1; ++j)
      for (long i = i0; i <= i1; ++i)
        for (std::uint32_t k : bins_[static_cast<std::size_t>(j * nx_ + i)]) visit(k);
  }

 private:
  long bin_x(double x) const { return std::clamp(static_cast<long>(std::floor((x - origin_.x) / size_)), 0L, nx_ - 1); }
  long bin_y(double y) const { return std::clamp(static_cast<long>(std::floor((y - origin_.y) / size_)), 0L, ny_ - 1); }
  Point2 origin_{0.0, 0.0};
  double size_ = 1.0;
  long nx_ = 0, ny_ = 0;
  std::vector<std::vector<std::uint32_t>> bins_;
};

// ---------------------------------------------------------------------------------------------
// Plain geometry helpers.

// Even-odd test of (x, y) against one ring.
inline bool inside_polygon(const std::vector<Point2>& poly, double x, double y) {
  bool inside = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const auto& a = poly[i];
    const auto& b = poly[j];
    if ((a.y > y) != (b.y > y) && x < (b.x - a.x) * (y - a.y) / (b.y - a.y) + a.x) inside = !inside;
  }
  return inside;
}

inline double distance_to_segment(const Point2& a, const Point2& b, double x, double y) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? ((x - a.x) * dx + (y - a.y) * dy) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(a.x + t * dx - x, a.y + t * dy - y);
}

// 0 inside the ring, else the distance to its boundary.
inline double distance_to_polygon(const std::vector<Point2>& poly, double x, double y) {
  if (inside_polygon(poly, x, y)) return 0.0;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < poly.size(); ++i)
    best = std::min(best, distance_to_segment(poly[i], poly[(i + 1) % poly.size()], x, y));
  return best;
}

// Where (x, y) lies against the ring, as distance_to_polygon(poly, x, y) would tell it, without taking
// every edge's distance: 2 where that distance is 0 (inside, or on an edge), 1 where it is at most
// `reach`, 0 where it is farther. An edge's squared distance settles it unless it is within a relative
// 1e-12 of reach squared (far above the rounding of both, a few units of 1e-16); only then is its
// distance taken as distance_to_segment takes it.
inline int polygon_reach(const std::vector<Point2>& poly, double x, double y, double reach) {
  if (inside_polygon(poly, x, y)) return 2;
  const double reach2 = reach * reach;
  bool near = false;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Point2& a = poly[i];
    const Point2& b = poly[(i + 1) % poly.size()];
    const double dx = b.x - a.x, dy = b.y - a.y;
    const double len2 = dx * dx + dy * dy;
    const double t = std::clamp(len2 > 0 ? ((x - a.x) * dx + (y - a.y) * dy) / len2 : 0.0, 0.0, 1.0);
    const double ex = a.x + t * dx - x, ey = a.y + t * dy - y;
    if (ex == 0.0 && ey == 0.0) return 2;
    if (near) continue;
    const double d2 = ex * ex + ey * ey;
    near = d2 < reach2 * (1.0 - 1e-12) || (d2 <= reach2 * (1.0 + 1e-12) && std::hypot(ex, ey) <= reach);
  }
  return near ? 1 : 0;
}

// Newell's normal of a 3D polygon: its length is the polygon's area.
struct Vec3 {
  double x, y, z;
};
inline Vec3 newell_normal(const std::vector<Point3>& poly) {
  Vec3 n{0, 0, 0};
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const auto& p = poly[i];
    const auto& q = poly[(i + 1) % poly.size()];
    n.x += (p.y - q.y) * (p.z + q.z);
    n.y += (p.z - q.z) * (p.x + q.x);
    n.z += (p.x - q.x) * (p.y + q.y);
  }
  return {0.5 * n.x, 0.5 * n.y, 0.5 * n.z};
}

inline Point3 centroid(const std::vector<Point3>& poly) {
  // Area-weighted centroid of the fan triangles (all coplanar, so the weights have one sign).
  double total = 0.0;
  Point3 sum{0.0, 0.0, 0.0};
  for (std::size_t i = 1; i + 1 < poly.size(); ++i) {
    const auto& a = poly[0];
    const auto& b = poly[i];
    const auto& c = poly[i + 1];
    const Vec3 u{b.x - a.x, b.y - a.y, b.z - a.z}, v{c.x - a.x, c.y - a.y, c.z - a.z};
    const double area = 0.5 * std::sqrt(std::pow(u.y * v.z - u.z * v.y, 2) + std::pow(u.z * v.x - u.x * v.z, 2) +
                                        std::pow(u.x * v.y - u.y * v.x, 2));
    total += area;
    sum.x += area * (a.x + b.x + c.x) / 3.0;
    sum.y += area * (a.y + b.y + c.y) / 3.0;
    sum.z += area * (a.z + b.z + c.z) / 3.0;
  }
  if (total <= 0.0) {
    sum = {0.0, 0.0, 0.0};
    for (const auto& p : poly) {
      sum.x += p.x;
      sum.y += p.y;
      sum.z += p.z;
    }
    total = static_cast<double>(std::max<std::size_t>(poly.size(), 1));
  }
  return {sum.x / total, sum.y / total, sum.z / total};
}

// Height of a (non-vertical) roof plane over (x, y).
inline double roof_height(const PlanarSegment& roof, double x, double y) {
  const Plane3& p = roof.plane;
  return -(p.a * x + p.b * y + p.d) / p.c;
}

// Even-odd test over every ring of every footprint polygon.
inline bool inside_footprint(const std::vector<Polygon2>& footprint, double x, double y) {
  bool inside = false;  // even-odd over every ring
  for (const auto& poly : footprint) {
    if (inside_polygon(poly.outer, x, y)) inside = !inside;
    for (const auto& hole : poly.holes)
      if (inside_polygon(hole, x, y)) inside = !inside;
  }
  return inside;
}

}  // namespace city3d::detail
