// Plane geometry of rings and polygons (rings.hpp).
#include "city3d/rings.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

namespace city3d {
namespace {

double cross(const Point2& o, const Point2& u, const Point2& w) {
  return (u.x - o.x) * (w.y - o.y) - (u.y - o.y) * (w.x - o.x);
}

// Whether segments pq and rs cross at a point inside both.
bool segments_cross(const Point2& p, const Point2& q, const Point2& r, const Point2& s) {
  return cross(p, q, r) * cross(p, q, s) < 0 && cross(r, s, p) * cross(r, s, q) < 0;
}

}  // namespace

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
    for (std::size_t j = 0; j < b.size(); ++j)
      if (segments_cross(a[i], a[(i + 1) % a.size()], b[j], b[(j + 1) % b.size()])) return true;
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

namespace {

constexpr double kPi = 3.14159265358979323846;

double distance(const Point2& a, const Point2& b) { return std::hypot(a.x - b.x, a.y - b.y); }

double angle_of(const Point2& from, const Point2& to) { return std::atan2(to.y - from.y, to.x - from.x); }

// The counter-clockwise turn from angle `from` to angle `to`, in [0, 2 pi).
double turn(double from, double to) {
  const double t = std::fmod(to - from, 2 * kPi);
  return t < 0 ? t + 2 * kPi : t;
}

// Whether `edge` of `ring` (from vertex edge to edge + 1) belongs to vertex i itself: one of its two
// edges, or an edge reached from them along the ring without leaving `near` of the vertex (a vertex a
// few millimetres from its neighbour is no pinch).
bool own_edge(const Ring2& ring, std::size_t i, std::size_t edge, double near) {
  const std::size_t n = ring.size();
  for (std::size_t k = 0, e = i; k < n; ++k, e = (e + 1) % n) {
    if (e == edge) return true;
    if (distance(ring[(e + 1) % n], ring[i]) >= near) break;
  }
  for (std::size_t k = 0, e = (i + n - 1) % n; k < n; ++k, e = (e + n - 1) % n) {
    if (e == edge) return true;
    if (distance(ring[e], ring[i]) >= near) break;
  }
  return false;
}

// Where vertex i of `ring` goes to open its pinch with edge j of `other` (which may be `ring`): along
// the bisector of the sector between its own two edges that holds none of the other ring's edges
// there, far enough for `clearance`; nothing when the other ring runs into both sectors (the rings cross)
// or along one of the vertex's own edges.
std::optional<Point2> opened_position(const Ring2& ring, std::size_t i, const Ring2& other, std::size_t j,
                                      double clearance) {
  const std::size_t n = ring.size(), m = other.size();
  const Point2 v = ring[i], a = ring[(i + n - 1) % n], b = ring[(i + 1) % n];
  // The other ring's directions from v: the ends of its edge, or past an end that is at v.
  Point2 ends[2] = {other[j], other[(j + 1) % m]};
  if (distance(ends[0], v) < clearance / 2) ends[0] = other[(j + m - 1) % m];
  if (distance(ends[1], v) < clearance / 2) ends[1] = other[(j + 2) % m];
  const double to_a = angle_of(v, a), to_b = angle_of(v, b);
  const double first = turn(to_b, to_a);  // the sector counter-clockwise from edge vb to edge va
  int in_first = 0, in_second = 0;
  for (const Point2& end : ends) {
    if (distance(end, v) <= 0.0) return std::nullopt;
    const double t = turn(to_b, angle_of(v, end));
    if (t == 0.0 || t == first) return std::nullopt;
    (t < first ? in_first : in_second) += 1;
  }
  if (in_first > 0 && in_second > 0) return std::nullopt;
  const double start = in_first > 0 ? to_a : to_b;
  const double span = in_first > 0 ? 2 * kPi - first : first;
  const double half = span / 2;
  const double reach = std::min({clearance / std::sin(std::min(half, kPi / 2)), 10 * clearance,
                                 distance(v, a) / 3, distance(v, b) / 3});
  return Point2{v.x + reach * std::cos(start + half), v.y + reach * std::sin(start + half)};
}

// The first vertex (ring, vertex) nearer than `near` to an edge (other ring, edge) not its own.
std::optional<std::array<std::size_t, 4>> find_pinch(const std::vector<Ring2*>& rings, double near) {
  for (std::size_t r = 0; r < rings.size(); ++r)
    for (std::size_t i = 0; i < rings[r]->size(); ++i)
      for (std::size_t q = 0; q < rings.size(); ++q) {
        const Ring2& other = *rings[q];
        for (std::size_t j = 0; j < other.size(); ++j) {
          if (segment_distance((*rings[r])[i], other[j], other[(j + 1) % other.size()]) >= near) continue;
          if (q == r && own_edge(other, i, j, near)) continue;
          return std::array<std::size_t, 4>{r, i, q, j};
        }
      }
  return std::nullopt;
}

}  // namespace

TidiedFootprint tidy_footprint(std::vector<Polygon2>& polygons, double merge_distance, double spike_width) {
  TidiedFootprint tidied;
  const auto tidy = [&](Ring2& ring) {
    for (bool changed = true; changed && ring.size() > 3;) {
      changed = false;
      for (std::size_t i = 0; i < ring.size() && ring.size() > 3; ++i) {
        const std::size_t n = ring.size();
        const Point2 &a = ring[(i + n - 1) % n], &v = ring[i], &b = ring[(i + 1) % n];
        const bool merged = distance(a, v) < merge_distance;
        const bool spike =
            !merged && distance(a, b) < spike_width && segment_distance(v, a, b) > distance(a, b);
        if (!merged && !spike) continue;
        (merged ? tidied.merged : tidied.spikes) += 1;
        ring.erase(ring.begin() + static_cast<std::ptrdiff_t>(i));
        changed = true;
        --i;
      }
    }
  };
  for (Polygon2& p : polygons) {
    tidy(p.outer);
    for (Ring2& h : p.holes) tidy(h);
  }
  return tidied;
}

std::vector<Point2> open_pinches(std::vector<Polygon2>& polygons, double clearance, Point2* unopened) {
  std::vector<Ring2*> rings;
  for (Polygon2& p : polygons) {
    rings.push_back(&p.outer);
    for (Ring2& h : p.holes) rings.push_back(&h);
  }
  for (const Ring2* r : rings)
    if (r->size() < 3) return {};
  std::optional<std::array<std::size_t, 4>> pinch = find_pinch(rings, clearance / 2);
  if (!pinch) return {};
  const std::vector<Polygon2> given = polygons;
  std::vector<double> areas;
  for (const Ring2* r : rings) areas.push_back(twice_signed_area(*r));
  std::vector<Point2> opened;
  std::vector<std::pair<std::size_t, std::size_t>> moved;  // (ring, vertex)
  const auto give_up = [&](const Point2& at) {
    polygons = given;
    if (unopened) *unopened = at;
    return std::vector<Point2>{};
  };
  // One move per pinch, or two when the first was held back by a short edge; a footprint of more
  // pinches than this is left as it is (each search looks at every vertex and edge).
  constexpr std::size_t kMaxMoves = 64;
  for (; pinch; pinch = find_pinch(rings, clearance / 2)) {
    const auto [r, i, q, j] = *pinch;
    Ring2& ring = *rings[r];
    const std::optional<Point2> to =
        moved.size() < kMaxMoves ? opened_position(ring, i, *rings[q], j, clearance) : std::nullopt;
    if (!to) return give_up(ring[i]);
    opened.push_back(ring[i]);
    ring[i] = *to;
    moved.emplace_back(r, i);
  }
  // The moves must not have made a ring cross another, or turned one over.
  for (std::size_t r = 0; r < rings.size(); ++r)
    if ((twice_signed_area(*rings[r]) > 0) != (areas[r] > 0)) return give_up(opened.front());
  for (const auto& [r, i] : moved) {
    const Ring2& ring = *rings[r];
    const std::size_t n = ring.size();
    for (const std::size_t e : {(i + n - 1) % n, i})
      for (std::size_t q = 0; q < rings.size(); ++q)
        for (std::size_t j = 0; j < rings[q]->size(); ++j) {
          const Ring2& other = *rings[q];
          if (segments_cross(ring[e], ring[(e + 1) % n], other[j], other[(j + 1) % other.size()]))
            return give_up(opened.front());
        }
  }
  return opened;
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
