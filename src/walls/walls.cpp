// Vertical planes of a building: outer walls from the footprint (or from an inferred outline), inner
// walls from the regularised heightmap lines, or walls from detected wall lines.
#include "city3d/walls.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "city3d/error.hpp"
#include "city3d/log.hpp"
#include "city3d/rings.hpp"

namespace city3d {

void WallParams::validate() const {
  std::ostringstream problems;
  if (!(min_wall_length >= 0.0)) problems << " min_wall_length must be >= 0 (got " << min_wall_length << ");";
  if (!(footprint_margin >= 0.0))
    problems << " footprint_margin must be >= 0 (got " << footprint_margin << ");";
  if (!(sample_step > 0.0) || !std::isfinite(sample_step))
    problems << " sample_step must be > 0 (got " << sample_step << ");";
  if (min_escaping_rays < 1 || min_escaping_rays > 15)
    problems << " min_escaping_rays must be in [1, 15] (got " << min_escaping_rays << ");";
  if (!(ray_fan_step > 0.0 && ray_fan_step <= 45.0))
    problems << " ray_fan_step must be in (0, 45] degrees (got " << ray_fan_step << ");";
  if (!(side_probe > 0.0) || !std::isfinite(side_probe))
    problems << " side_probe must be > 0 (got " << side_probe << ");";
  if (min_detected_lines < 0)
    problems << " min_detected_lines must be >= 0 (got " << min_detected_lines << ");";
  if (!(detected_length_ratio >= 0.0))
    problems << " detected_length_ratio must be >= 0 (got " << detected_length_ratio << ");";
  throw_if_invalid("walls", problems.str());
}

namespace detail {
namespace {

constexpr double kCollinearTolerance = 1e-3;  // metres: footprint vertices this close to the line are dropped

double length(const Point2& a, const Point2& b) { return std::hypot(b.x - a.x, b.y - a.y); }


double point_segment_distance(const Point2& p, const Point2& a, const Point2& b) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? ((p.x - a.x) * dx + (p.y - a.y) * dy) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(p.x - a.x - t * dx, p.y - a.y - t * dy);
}

// Drops repeated vertices and vertices on the straight line between their neighbours.
Ring2 merge_collinear(Ring2 ring) {
  bool changed = true;
  while (changed && ring.size() > 3) {
    changed = false;
    for (std::size_t i = 0; i < ring.size() && ring.size() > 3; ++i) {
      const Point2& prev = ring[(i + ring.size() - 1) % ring.size()];
      const Point2& next = ring[(i + 1) % ring.size()];
      if (length(prev, ring[i]) <= kCollinearTolerance ||
          point_segment_distance(ring[i], prev, next) <= kCollinearTolerance) {
        ring.erase(ring.begin() + static_cast<std::ptrdiff_t>(i));
        changed = true;
        break;
      }
    }
  }
  return ring;
}

VerticalPlane make_plane(Point2 a, Point2 b, Point2 normal, bool outer, VerticalPlane::Source source) {
  VerticalPlane w;
  w.a = a;
  w.b = b;
  w.normal = normal;
  w.offset = 0.5 * (normal.x * (a.x + b.x) + normal.y * (a.y + b.y));
  w.outer = outer;
  w.source = source;
  return w;
}

// Left unit normal of a -> b.
Point2 left_normal(const Point2& a, const Point2& b) {
  const double len = length(a, b);
  return Point2{-(b.y - a.y) / len, (b.x - a.x) / len};
}

// Orders a segment's endpoints canonically (lexicographically) so inner normals do not depend on
// the direction the line happened to be traced in.
std::pair<Point2, Point2> canonical(Point2 a, Point2 b) {
  if (b.x < a.x || (b.x == a.x && b.y < a.y)) std::swap(a, b);
  return {a, b};
}

struct FootprintShape {
  std::vector<Ring2> rings;  // all rings, outer CCW, holes CW

  explicit FootprintShape(const std::vector<Polygon2>& polygons) {
    for (const auto& poly : polygons) {
      if (poly.outer.size() >= 3) {
        Ring2 r = merge_collinear(poly.outer);
        if (signed_area(r) < 0) std::reverse(r.begin(), r.end());
        rings.push_back(std::move(r));
      }
      for (const auto& h : poly.holes) {
        if (h.size() < 3) continue;
        Ring2 r = merge_collinear(h);
        if (signed_area(r) > 0) std::reverse(r.begin(), r.end());
        rings.push_back(std::move(r));
      }
    }
  }

  bool contains(const Point2& p) const {  // even-odd rule over every ring
    bool inside = false;
    for (const auto& r : rings)
      for (std::size_t i = 0, j = r.size() - 1; i < r.size(); j = i++) {
        if ((r[i].y > p.y) != (r[j].y > p.y) &&
            p.x < (r[j].x - r[i].x) * (p.y - r[i].y) / (r[j].y - r[i].y) + r[i].x)
          inside = !inside;
      }
    return inside;
  }

  double boundary_distance(const Point2& p) const {
    double best = std::numeric_limits<double>::infinity();
    for (const auto& r : rings)
      for (std::size_t i = 0; i < r.size(); ++i)
        best = std::min(best, point_segment_distance(p, r[i], r[(i + 1) % r.size()]));
    return best;
  }
};

// Outer walls: one per (merged) footprint edge; the outside is on the right of a CCW outer ring and
// of a CW hole.
void footprint_walls(const FootprintShape& shape, std::vector<VerticalPlane>& out) {
  for (const auto& r : shape.rings)
    for (std::size_t i = 0; i < r.size(); ++i) {
      const Point2 a = r[i], b = r[(i + 1) % r.size()];
      if (length(a, b) <= 0) continue;
      const Point2 left = left_normal(a, b);
      out.push_back(make_plane(a, b, Point2{-left.x, -left.y}, true, VerticalPlane::Source::footprint));
    }
}

// Inner walls: parts of the lines inside the footprint, kept when enough of them is away from the
// boundary.
void inner_walls(const FootprintShape& shape, const std::vector<std::pair<Point2, Point2>>& lines,
                 const WallParams& params, VerticalPlane::Source source, std::vector<VerticalPlane>& out) {
  for (const auto& [a0, b0] : lines) {
    const auto [a, b] = canonical(a0, b0);
    const double len = length(a, b);
    if (len <= 0) continue;
    const int steps = std::max(1, static_cast<int>(std::ceil(len / params.sample_step)));
    const double step = len / steps;
    int run_start = -1, interior = 0;
    auto flush = [&](int first, int last) {  // samples first..last inside
      const double t0 = static_cast<double>(first) / steps, t1 = static_cast<double>(last) / steps;
      const Point2 pa{a.x + t0 * (b.x - a.x), a.y + t0 * (b.y - a.y)};
      const Point2 pb{a.x + t1 * (b.x - a.x), a.y + t1 * (b.y - a.y)};
      if (interior * step >= params.min_wall_length && length(pa, pb) >= params.min_wall_length &&
          length(pa, pb) > 0)
        out.push_back(make_plane(pa, pb, left_normal(pa, pb), false, source));
    };
    for (int k = 0; k <= steps; ++k) {
      const double t = static_cast<double>(k) / steps;
      const Point2 p{a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)};
      const bool inside = shape.contains(p);
      if (inside) {
        if (run_start < 0) {
          run_start = k;
          interior = 0;
        }
        if (shape.boundary_distance(p) > params.footprint_margin) ++interior;
      } else if (run_start >= 0) {
        flush(run_start, k - 1);
        run_start = -1;
      }
    }
    if (run_start >= 0) flush(run_start, steps);
  }
}

// Does the ray from p in direction d cross any line other than `self`?
bool ray_blocked(const Point2& p, const Point2& d, const std::vector<std::pair<Point2, Point2>>& lines,
                 std::size_t self) {
  for (std::size_t j = 0; j < lines.size(); ++j) {
    if (j == self) continue;
    const Point2 a = lines[j].first, b = lines[j].second;
    const double ex = b.x - a.x, ey = b.y - a.y;
    const double denom = d.x * ey - d.y * ex;
    if (std::abs(denom) < 1e-12) continue;
    const double wx = a.x - p.x, wy = a.y - p.y;
    const double t = (wx * ey - wy * ex) / denom;    // along the ray
    const double s = (wx * d.y - wy * d.x) / denom;  // along the line
    if (t > 1e-6 && s >= -1e-9 && s <= 1 + 1e-9) return true;
  }
  return false;
}

// Walls without a footprint: outer when one side faces the outside (rays escape), see walls.hpp.
void outline_walls(const std::vector<std::pair<Point2, Point2>>& all_lines, const WallParams& params,
                   VerticalPlane::Source source, std::vector<VerticalPlane>& out) {
  std::vector<std::pair<Point2, Point2>> lines;
  for (const auto& [a, b] : all_lines)
    if (length(a, b) >= std::max(params.min_wall_length, 1e-9)) lines.push_back(canonical(a, b));
  const double step = params.ray_fan_step * kPi / 180.0;
  const double fan[] = {0.0, -step, step, -2 * step, 2 * step};
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const Point2 a = lines[i].first, b = lines[i].second;
    const Point2 n = left_normal(a, b);
    int escapes[2] = {0, 0};  // left, right
    for (double f : {0.25, 0.5, 0.75}) {
      const Point2 p{a.x + f * (b.x - a.x), a.y + f * (b.y - a.y)};
      for (int side = 0; side < 2; ++side) {
        const double sign = side == 0 ? 1.0 : -1.0;
        for (double angle : fan) {
          const double c = std::cos(angle), s = std::sin(angle);
          const Point2 d{sign * (c * n.x - s * n.y), sign * (s * n.x + c * n.y)};
          if (!ray_blocked(p, d, lines, i)) ++escapes[side];
        }
      }
    }
    const int best = escapes[0] >= escapes[1] ? 0 : 1;
    const bool outer = escapes[best] >= params.min_escaping_rays && escapes[best] > escapes[1 - best];
    const Point2 normal = outer && best == 1 ? Point2{-n.x, -n.y} : n;
    out.push_back(make_plane(a, b, normal, outer, source));
  }
}

std::vector<std::pair<Point2, Point2>> as_pairs(const RegularisationResult& r) {
  std::vector<std::pair<Point2, Point2>> out;
  for (const auto& s : r.segments) out.push_back({s.a, s.b});
  return out;
}

double total_length(const std::vector<std::pair<Point2, Point2>>& lines) {
  double s = 0;
  for (const auto& [a, b] : lines) s += length(a, b);
  return s;
}

const char* mode_name(WallMode m) {
  switch (m) {
    case WallMode::automatic:
      return "automatic";
    case WallMode::footprint:
      return "footprint";
    case WallMode::inferred:
      return "inferred";
    case WallMode::detected:
      return "detected";
  }
  return "?";
}

}  // namespace
}  // namespace detail

std::vector<VerticalPlane> infer_walls(const RegularisationResult& lines,
                                       const std::vector<Polygon2>* footprint_local,
                                       const std::vector<std::pair<Point2, Point2>>& detected_wall_lines,
                                       const WallParams& params) {
  using namespace detail;
  params.validate();
  const bool has_footprint = footprint_local && !footprint_local->empty();
  const auto inferred = as_pairs(lines);

  WallMode mode = params.mode;
  if (mode == WallMode::automatic) {
    if (has_footprint)
      mode = WallMode::footprint;
    else if (static_cast<int>(detected_wall_lines.size()) >= std::max(1, params.min_detected_lines) &&
             total_length(detected_wall_lines) >= params.detected_length_ratio * total_length(inferred))
      mode = WallMode::detected;
    else
      mode = WallMode::inferred;
  }
  if (mode == WallMode::footprint && !has_footprint)
    throw ConfigError("walls: wall mode 'footprint' needs a footprint, and this building has none");
  if (mode == WallMode::detected && detected_wall_lines.empty())
    throw ReconstructionError(ReconstructionStage::walls, "wall mode 'detected' but no wall lines were detected");

  std::vector<VerticalPlane> walls;
  switch (mode) {
    case WallMode::footprint: {
      const FootprintShape shape(*footprint_local);
      footprint_walls(shape, walls);
      inner_walls(shape, inferred, params, VerticalPlane::Source::inferred, walls);
      break;
    }
    case WallMode::detected:
      if (has_footprint) {
        // Outer when it runs along the footprint boundary (at both ends and the middle), inner otherwise.
        const FootprintShape shape(*footprint_local);
        for (const auto& [a0, b0] : detected_wall_lines) {
          const auto [a, b] = canonical(a0, b0);
          const double len = length(a, b);
          if (len < std::max(params.min_wall_length, 1e-9)) continue;
          const Point2 m{0.5 * (a.x + b.x), 0.5 * (a.y + b.y)};
          const bool along = shape.boundary_distance(a) <= params.footprint_margin &&
                             shape.boundary_distance(m) <= params.footprint_margin &&
                             shape.boundary_distance(b) <= params.footprint_margin;
          Point2 n = left_normal(a, b);
          if (along) {
            const double probe = params.footprint_margin + params.side_probe;
            const Point2 q{m.x + probe * n.x, m.y + probe * n.y};
            if (shape.contains(q)) n = Point2{-n.x, -n.y};
          }
          walls.push_back(make_plane(a, b, n, along, VerticalPlane::Source::detected));
        }
      } else {
        outline_walls(detected_wall_lines, params, VerticalPlane::Source::detected, walls);
      }
      break;
    case WallMode::inferred:
    case WallMode::automatic:
      outline_walls(inferred, params, VerticalPlane::Source::inferred, walls);
      break;
  }
  std::size_t outer = 0;
  for (const auto& w : walls) outer += w.outer ? 1 : 0;
  log_debug(std::string("walls: mode ") + mode_name(mode) + ", " + std::to_string(outer) + " outer and " +
            std::to_string(walls.size() - outer) + " inner walls");
  return walls;
}

}  // namespace city3d
