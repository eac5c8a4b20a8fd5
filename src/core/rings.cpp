// Plane geometry of rings and polygons (rings.hpp).
#include "city3d/rings.hpp"

#include <algorithm>
#include <cmath>

namespace city3d {

double signed_area(const Ring2& ring) {
  double twice = 0;
  for (std::size_t k = 0; k < ring.size(); ++k) {
    const Point2 &a = ring[k], &b = ring[(k + 1) % ring.size()];
    twice += a.x * b.y - b.x * a.y;
  }
  return twice / 2;
}

double ring_area(const Ring2& ring) { return std::fabs(signed_area(ring)); }

double polygons_area(const std::vector<Polygon2>& polygons) {
  double area = 0.0;
  for (const Polygon2& p : polygons) {
    area += ring_area(p.outer);
    for (const Ring2& h : p.holes) area -= ring_area(h);
  }
  return area;
}

double twice_signed_area(const Ring2& ring) {
  if (ring.size() < 3) return 0.0;
  const Point2 origin = ring.front();
  double sum = 0.0;
  for (std::size_t i = 1; i + 1 < ring.size(); ++i) {
    const double ax = ring[i].x - origin.x, ay = ring[i].y - origin.y;
    const double bx = ring[i + 1].x - origin.x, by = ring[i + 1].y - origin.y;
    sum += ax * by - bx * ay;
  }
  return sum;
}

bool inside_ring(const Ring2& ring, const Point2& p) {
  bool in = false;
  for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++)
    if ((ring[i].y > p.y) != (ring[j].y > p.y) &&
        p.x < (ring[j].x - ring[i].x) * (p.y - ring[i].y) / (ring[j].y - ring[i].y) + ring[i].x)
      in = !in;
  return in;
}

bool rings_near(const Ring2& a, const Ring2& b, double gap) {
  if (inside_ring(b, a.front()) || inside_ring(a, b.front())) return true;
  for (const auto& [p, q] : {std::pair{&a, &b}, std::pair{&b, &a}})
    for (const Point2& v : *p)
      for (std::size_t k = 0; k < q->size(); ++k)
        if (segment_distance(v, (*q)[k], (*q)[(k + 1) % q->size()]) < gap) return true;
  // Crossing edges without a vertex near the other ring cannot happen at this gap unless an edge
  // passes through; test the crossings too.
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) {
      const Point2 &p = a[i], &p2 = a[(i + 1) % a.size()], &q = b[j], &q2 = b[(j + 1) % b.size()];
      const auto side = [](const Point2& o, const Point2& u, const Point2& w) {
        return (u.x - o.x) * (w.y - o.y) - (u.y - o.y) * (w.x - o.x);
      };
      if (side(p, p2, q) * side(p, p2, q2) < 0 && side(q, q2, p) * side(q, q2, p2) < 0) return true;
    }
  return false;
}

std::size_t points_inside(const Ring2& ring, const std::vector<std::uint32_t>& indices,
                          const std::vector<Point3>& points) {
  std::size_t in = 0;
  for (std::uint32_t i : indices) in += inside_ring(ring, {points[i].x, points[i].y});
  return in;
}

double segment_distance(const Point2& p, const Point2& a, const Point2& b) {
  const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
  const double t = len2 > 0 ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / len2, 0.0, 1.0) : 0.0;
  return std::hypot(p.x - a.x - t * dx, p.y - a.y - t * dy);
}

Ring2 convex_hull(std::vector<Point2> pts) {
  std::sort(pts.begin(), pts.end(), [](const Point2& a, const Point2& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  pts.erase(std::unique(pts.begin(), pts.end(), [](const Point2& a, const Point2& b) { return a.x == b.x && a.y == b.y; }),
            pts.end());
  if (pts.size() < 3) return pts;
  auto cross = [](const Point2& o, const Point2& a, const Point2& b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
  };
  Ring2 hull(2 * pts.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  for (std::size_t i = pts.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], pts[i - 1]) <= 0) --k;
    hull[k++] = pts[i - 1];
  }
  hull.resize(k - 1);
  return hull;
}

}  // namespace city3d
