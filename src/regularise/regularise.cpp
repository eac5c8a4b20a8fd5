// Regularisation of polylines into parallel, collinear and orthogonal segments: DBSCAN clustering of
// segments by direction and distance, then adjustment (paper section 3.2, "Regularity enhancement").
//
// Directions are angles in [0, pi) (a segment and its reverse are the same wall). Averaging uses the
// doubled angle (length-weighted mean of (cos 2t, sin 2t)), so 179 and 1 degrees average to 0, not 90.
// After snapping, segments that share a direction share the very same double, so parallelism and
// orthogonality are exact up to the rounding of one cos/sin evaluation.
#include "city3d/regularise.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numeric>
#include <sstream>

#include "city3d/error.hpp"
#include "city3d/log.hpp"
#include "city3d/rings.hpp"

namespace city3d {

void RegulariseParams::validate() const {
  std::ostringstream problems;
  if (!(angle_threshold >= 0.0 && angle_threshold <= 45.0))
    problems << " angle_threshold must be in [0, 45] degrees (got " << angle_threshold << ");";
  if (!(cluster_distance > 0.0))
    problems << " cluster_distance must be > 0 (got " << cluster_distance << ");";
  if (!(cluster_angle > 0.0 && cluster_angle < 90.0))
    problems << " cluster_angle must be in (0, 90) degrees (got " << cluster_angle << ");";
  if (min_cluster < 1) problems << " min_cluster must be >= 1 (got " << min_cluster << ");";
  if (!(merge_gap >= 0.0)) problems << " merge_gap must be >= 0 (got " << merge_gap << ");";
  if (!(min_footprint_edge >= 0.0))
    problems << " min_footprint_edge must be >= 0 (got " << min_footprint_edge << ");";
  if (!(min_segment_length >= 0.0))
    problems << " min_segment_length must be >= 0 (got " << min_segment_length << ");";
  throw_if_invalid("regularise", problems.str());
}

namespace detail {
namespace {


double deg2rad(double d) { return d * kPi / 180.0; }

double seg_length(const Segment2& s) { return std::hypot(s.b.x - s.a.x, s.b.y - s.a.y); }

// Direction of a segment as an angle in [0, pi).
double direction(const Segment2& s) {
  double t = std::atan2(s.b.y - s.a.y, s.b.x - s.a.x);
  if (t < 0) t += kPi;
  if (t >= kPi) t -= kPi;
  return t;
}

// Smallest angle between two undirected directions, in [0, pi/2].
double angle_between(double t1, double t2) {
  double d = std::fmod(std::abs(t1 - t2), kPi);
  return std::min(d, kPi - d);
}

double normalise_angle(double t) {
  t = std::fmod(t, kPi);
  if (t < 0) t += kPi;
  return t;
}

// Minimum distance from segment s to the supporting line of segment l.
double segment_to_line(const Segment2& s, const Segment2& l) {
  const double dx = l.b.x - l.a.x, dy = l.b.y - l.a.y;
  const double len = std::hypot(dx, dy);
  if (len <= 0) return std::hypot(s.a.x - l.a.x, s.a.y - l.a.y);
  const double da = (dx * (s.a.y - l.a.y) - dy * (s.a.x - l.a.x)) / len;
  const double db = (dx * (s.b.y - l.a.y) - dy * (s.b.x - l.a.x)) / len;
  if ((da <= 0 && db >= 0) || (da >= 0 && db <= 0)) return 0.0;  // crosses the line
  return std::min(std::abs(da), std::abs(db));
}

// Moves s onto the line through its midpoint with direction t (endpoints projected).
Segment2 rotate_to(const Segment2& s, double t) {
  const double ux = std::cos(t), uy = std::sin(t);
  const Point2 m{0.5 * (s.a.x + s.b.x), 0.5 * (s.a.y + s.b.y)};
  auto project = [&](const Point2& p) {
    const double k = (p.x - m.x) * ux + (p.y - m.y) * uy;
    return Point2{m.x + k * ux, m.y + k * uy};
  };
  return Segment2{project(s.a), project(s.b)};
}

// DBSCAN over segments; returns a cluster id per segment, -1 for noise.
std::vector<int> dbscan(const std::vector<Segment2>& segs, const std::vector<double>& dirs, double max_angle,
                        double max_distance, int min_points) {
  const std::size_t n = segs.size();
  std::vector<std::vector<int>> neighbours(n);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      if (angle_between(dirs[i], dirs[j]) > max_angle) continue;
      const double d = std::max(segment_to_line(segs[i], segs[j]), segment_to_line(segs[j], segs[i]));
      if (d > max_distance) continue;
      neighbours[i].push_back(static_cast<int>(j));
      neighbours[j].push_back(static_cast<int>(i));
    }
  std::vector<int> label(n, -2);  // -2 unvisited, -1 noise
  int next = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (label[i] != -2) continue;
    if (static_cast<int>(neighbours[i].size()) + 1 < min_points) {
      label[i] = -1;
      continue;
    }
    const int c = next++;
    label[i] = c;
    std::vector<int> frontier(neighbours[i]);
    for (std::size_t k = 0; k < frontier.size(); ++k) {
      const int j = frontier[k];
      if (label[j] == -1) label[j] = c;  // border point
      if (label[j] != -2) continue;
      label[j] = c;
      if (static_cast<int>(neighbours[j].size()) + 1 >= min_points)
        frontier.insert(frontier.end(), neighbours[j].begin(), neighbours[j].end());
    }
  }
  return label;
}

// Length-weighted mean of undirected directions (doubled-angle average).
double mean_direction(const std::vector<std::size_t>& members, const std::vector<double>& dirs,
                      const std::vector<double>& lengths) {
  double c = 0, s = 0;
  for (std::size_t i : members) {
    c += lengths[i] * std::cos(2 * dirs[i]);
    s += lengths[i] * std::sin(2 * dirs[i]);
  }
  return normalise_angle(0.5 * std::atan2(s, c));
}

}  // namespace
}  // namespace detail

RegularisationResult regularise(const std::vector<Polyline2>& polylines,
                                const std::vector<Polygon2>* footprint_local,
                                const RegulariseParams& params) {
  using namespace detail;
  params.validate();
  RegularisationResult result;

  // 1. Segments.
  std::vector<Segment2> segs;
  for (const auto& line : polylines)
    for (std::size_t i = 1; i < line.size(); ++i) {
      const Segment2 s{line[i - 1], line[i]};
      if (seg_length(s) >= std::max(params.min_segment_length, 1e-9)) segs.push_back(s);
    }
  result.segments_before = segs.size();
  if (segs.empty()) return result;
  const std::size_t n = segs.size();
  std::vector<double> dirs(n), lengths(n);
  for (std::size_t i = 0; i < n; ++i) {
    dirs[i] = direction(segs[i]);
    lengths[i] = seg_length(segs[i]);
  }

  // 2. Clusters (noise segments become singleton groups).
  const std::vector<int> label =
      dbscan(segs, dirs, deg2rad(params.cluster_angle), params.cluster_distance, params.min_cluster);
  int groups = 0;
  for (int l : label) groups = std::max(groups, l + 1);
  std::vector<int> group(n);
  for (std::size_t i = 0; i < n; ++i) group[i] = label[i] >= 0 ? label[i] : groups++;
  std::vector<std::vector<std::size_t>> members(groups);
  for (std::size_t i = 0; i < n; ++i) members[group[i]].push_back(i);

  // 3. Cluster mean directions.
  std::vector<double> group_dir(groups), group_len(groups, 0.0);
  for (int g = 0; g < groups; ++g) {
    group_dir[g] = mean_direction(members[g], dirs, lengths);
    for (std::size_t i : members[g]) group_len[g] += lengths[i];
  }

  // 4. Footprint edge directions.
  const double threshold = deg2rad(params.angle_threshold);
  std::vector<char> from_footprint(groups, 0);
  if (footprint_local) {
    std::vector<double> fp_dirs;
    for (const auto& poly : *footprint_local) {
      std::vector<const Ring2*> rings{&poly.outer};
      for (const auto& h : poly.holes) rings.push_back(&h);
      for (const Ring2* ring : rings)
        for (std::size_t i = 0; i < ring->size(); ++i) {
          const Segment2 e{(*ring)[i], (*ring)[(i + 1) % ring->size()]};
          if (seg_length(e) >= std::max(params.min_footprint_edge, 1e-9)) fp_dirs.push_back(direction(e));
        }
    }
    for (int g = 0; g < groups; ++g) {
      double best = threshold;
      for (double f : fp_dirs) {
        const double d = angle_between(group_dir[g], f);
        if (d <= best) {
          best = d;
          group_dir[g] = f;
          from_footprint[g] = 1;
        }
      }
    }
  }

  // 5. Snap near-parallel and near-orthogonal directions to earlier (longer) ones.
  std::vector<int> order(groups);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) {
    if (from_footprint[x] != from_footprint[y]) return from_footprint[x] > from_footprint[y];
    return group_len[x] > group_len[y];
  });
  std::vector<double> references;      // distinct directions, in [0, pi)
  std::vector<int> group_ref(groups);  // index into references
  for (int g : order) {
    int found = -1;
    for (std::size_t r = 0; r < references.size() && found < 0; ++r) {
      if (angle_between(group_dir[g], references[r]) <= threshold) found = static_cast<int>(r);
    }
    for (std::size_t r = 0; r < references.size() && found < 0; ++r) {
      if (angle_between(group_dir[g], references[r] + 0.5 * kPi) <= threshold) {
        const double perpendicular = normalise_angle(references[r] + 0.5 * kPi);
        // Reuse an existing reference equal to the perpendicular, so that equal directions share ids.
        for (std::size_t q = 0; q < references.size(); ++q)
          if (references[q] == perpendicular) found = static_cast<int>(q);
        if (found < 0) {
          references.push_back(perpendicular);
          found = static_cast<int>(references.size()) - 1;
        }
      }
    }
    if (found < 0) {
      references.push_back(group_dir[g]);
      found = static_cast<int>(references.size()) - 1;
    }
    group_ref[g] = found;
  }
  for (std::size_t i = 0; i < n; ++i) segs[i] = rotate_to(segs[i], references[group_ref[group[i]]]);

  // 6 and 7. Per direction: common lines for close offsets, then merge overlapping extents.
  for (std::size_t r = 0; r < references.size(); ++r) {
    const double ux = std::cos(references[r]), uy = std::sin(references[r]);
    const double nx = -uy, ny = ux;
    struct Item {
      double offset, t0, t1, length;
    };
    std::vector<Item> items;
    for (std::size_t i = 0; i < n; ++i) {
      if (group_ref[group[i]] != static_cast<int>(r)) continue;
      const Point2 m{0.5 * (segs[i].a.x + segs[i].b.x), 0.5 * (segs[i].a.y + segs[i].b.y)};
      const double ta = segs[i].a.x * ux + segs[i].a.y * uy, tb = segs[i].b.x * ux + segs[i].b.y * uy;
      items.push_back({m.x * nx + m.y * ny, std::min(ta, tb), std::max(ta, tb), lengths[i]});
    }
    std::stable_sort(items.begin(), items.end(),
                     [](const Item& x, const Item& y) { return x.offset < y.offset; });
    for (std::size_t first = 0; first < items.size();) {
      std::size_t last = first + 1;
      while (last < items.size() && items[last].offset - items[first].offset <= params.cluster_distance)
        ++last;
      double wsum = 0, osum = 0;
      for (std::size_t k = first; k < last; ++k) {
        wsum += items[k].length;
        osum += items[k].length * items[k].offset;
      }
      const double offset = wsum > 0 ? osum / wsum : items[first].offset;
      std::vector<std::pair<double, double>> extents;
      for (std::size_t k = first; k < last; ++k) extents.push_back({items[k].t0, items[k].t1});
      std::sort(extents.begin(), extents.end());
      std::vector<std::pair<double, double>> merged;
      for (const auto& e : extents) {
        if (!merged.empty() && e.first <= merged.back().second + params.merge_gap)
          merged.back().second = std::max(merged.back().second, e.second);
        else
          merged.push_back(e);
      }
      for (const auto& [t0, t1] : merged)
        result.segments.push_back(Segment2{{t0 * ux + offset * nx, t0 * uy + offset * ny},
                                           {t1 * ux + offset * nx, t1 * uy + offset * ny}});
      first = last;
    }
  }
  result.segments_after = result.segments.size();
  log_debug("regularise: " + std::to_string(result.segments_before) + " segments -> " +
            std::to_string(result.segments_after) + " (" + std::to_string(references.size()) +
            " directions)");
  return result;
}

namespace {


bool segments_cross(const Point2& a, const Point2& b, const Point2& c, const Point2& d) {
  auto orient = [](const Point2& p, const Point2& q, const Point2& r) {
    const double v = (q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x);
    return (v > 0) - (v < 0);
  };
  return orient(a, b, c) * orient(a, b, d) < 0 && orient(c, d, a) * orient(c, d, b) < 0;
}

bool ring_is_simple(const Ring2& r) {
  const std::size_t n = r.size();
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // neighbours through the closing edge
      if (segments_cross(r[i], r[(i + 1) % n], r[j], r[(j + 1) % n])) return false;
    }
  return true;
}

}  // namespace

void OutlineSnapParams::validate() const {
  std::ostringstream problems;
  if (!(dominant_window > 0.0 && dominant_window <= 45.0))
    problems << " dominant_window must be in (0, 45] degrees (got " << dominant_window << ");";
  if (!(min_corner_angle > 0.0 && min_corner_angle < 90.0))
    problems << " min_corner_angle must be in (0, 90) degrees (got " << min_corner_angle << ");";
  if (!(max_shift > 0.0) || !std::isfinite(max_shift))
    problems << " max_shift must be > 0 (got " << max_shift << ");";
  if (!(max_area_change > 0.0) || !std::isfinite(max_area_change))
    problems << " max_area_change must be > 0 (got " << max_area_change << ");";
  if (!problems.str().empty()) throw ConfigError("outline snap: invalid parameters:" + problems.str());
}

Polygon2 regularise_outline(const Polygon2& polygon, double angle_threshold,
                            const OutlineSnapParams& params) {
  params.validate();
  const Ring2& ring = polygon.outer;
  const std::size_t n = ring.size();
  if (n < 4) return polygon;
  const double threshold = angle_threshold * kPi / 180.0;
  std::vector<double> angle(n), length(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Point2& a = ring[i];
    const Point2& b = ring[(i + 1) % n];
    angle[i] = std::atan2(b.y - a.y, b.x - a.x);
    length[i] = std::hypot(b.x - a.x, b.y - a.y);
  }
  // Angles modulo 90 degrees, folded to [0, pi/2): the dominant direction is the one with the most
  // edge length within dominant_window, refined by the length-weighted circular mean (on 4x the angle).
  auto fold = [&](double t) {
    const double q = kPi / 2;
    return t - std::floor(t / q) * q;
  };
  double best_score = -1, dominant = 0;
  for (std::size_t i = 0; i < n; ++i) {
    double score = 0, sx = 0, sy = 0;
    for (std::size_t j = 0; j < n; ++j) {
      double d = std::abs(fold(angle[j]) - fold(angle[i]));
      d = std::min(d, kPi / 2 - d);
      if (d < params.dominant_window * kPi / 180.0) {
        score += length[j];
        sx += length[j] * std::cos(4 * fold(angle[j]));
        sy += length[j] * std::sin(4 * fold(angle[j]));
      }
    }
    if (score > best_score) {
      best_score = score;
      dominant = std::atan2(sy, sx) / 4;
    }
  }
  // Snap each edge; lines are (unit direction, offset along the normal).
  struct Line {
    double angle, offset, weight;
  };
  std::vector<Line> lines;
  for (std::size_t i = 0; i < n; ++i) {
    double t = angle[i];
    const double k = std::round((t - dominant) / (kPi / 2));
    if (std::abs(t - dominant - k * kPi / 2) < threshold) t = dominant + k * kPi / 2;
    const Point2& a = ring[i];
    const Point2& b = ring[(i + 1) % n];
    const double mx = (a.x + b.x) / 2, my = (a.y + b.y) / 2;
    lines.push_back({t, -std::sin(t) * mx + std::cos(t) * my, length[i]});
  }
  auto same_direction = [](double s, double t) { return std::abs(std::remainder(s - t, 2 * 3.14159265358979323846)) < 1e-9; };
  // Merge runs of consecutive parallel lines (cyclically), weighting offsets by length.
  std::vector<Line> merged;
  std::size_t start = 0;
  while (start < n && same_direction(lines[start].angle, lines[(start + n - 1) % n].angle)) ++start;
  if (start == n) return polygon;  // every edge parallel: degenerate
  for (std::size_t k = 0; k < n; ++k) {
    const Line& l = lines[(start + k) % n];
    if (!merged.empty() && same_direction(merged.back().angle, l.angle)) {
      Line& m = merged.back();
      m.offset = (m.offset * m.weight + l.offset * l.weight) / (m.weight + l.weight);
      m.weight += l.weight;
    } else {
      merged.push_back(l);
    }
  }
  if (merged.size() < 3) return polygon;
  Polygon2 result;
  for (std::size_t i = 0; i < merged.size(); ++i) {
    const Line& p = merged[(i + merged.size() - 1) % merged.size()];
    const Line& q = merged[i];
    // Intersection of p and q: -sin(t) x + cos(t) y = offset for both.
    const double a1 = -std::sin(p.angle), b1 = std::cos(p.angle), a2 = -std::sin(q.angle), b2 = std::cos(q.angle);
    const double det = a1 * b2 - a2 * b1;
    if (std::abs(det) < std::sin(params.min_corner_angle * kPi / 180.0))
      return polygon;  // nearly parallel neighbours: keep input
    result.outer.push_back({(p.offset * b2 - q.offset * b1) / det, (a1 * q.offset - a2 * p.offset) / det});
  }
  // Every new corner must stay near the input outline's corners, the area must hold, and the ring
  // must stay simple; otherwise the snapping did more harm than good.
  for (const Point2& c : result.outer) {
    double best = 1e300;
    for (const Point2& v : ring) best = std::min(best, std::hypot(c.x - v.x, c.y - v.y));
    if (best > params.max_shift) return polygon;
  }
  const double before = signed_area(ring), after = signed_area(result.outer);
  if (!(after > 0) || std::abs(after - before) > params.max_area_change * std::abs(before) ||
      !ring_is_simple(result.outer))
    return polygon;
  result.holes = polygon.holes;
  return result;
}

void OutlineFitParams::validate() const {
  std::ostringstream problems;
  if (!(band > 0.0) || !std::isfinite(band)) problems << " band must be > 0 (got " << band << ");";
  if (!(end_margin >= 0.0) || !std::isfinite(end_margin))
    problems << " end_margin must be >= 0 (got " << end_margin << ");";
  if (min_points < 1) problems << " min_points must be >= 1 (got " << min_points << ");";
  if (!(outermost_share > 0.0 && outermost_share <= 1.0))
    problems << " outermost_share must be in (0, 1] (got " << outermost_share << ");";
  if (!(max_shift > 0.0) || !std::isfinite(max_shift))
    problems << " max_shift must be > 0 (got " << max_shift << ");";
  if (!(max_area_change > 0.0) || !std::isfinite(max_area_change))
    problems << " max_area_change must be > 0 (got " << max_area_change << ");";
  if (!problems.str().empty()) throw ConfigError("outline fit: invalid parameters:" + problems.str());
}

Polygon2 fit_outline_to_points(const Polygon2& outline, const std::vector<Point3>& points,
                               const OutlineFitParams& params) {
  params.validate();
  const double band = params.band, end_margin = params.end_margin, max_shift = params.max_shift;
  const int min_points = params.min_points;
  const Ring2& ring = outline.outer;
  const std::size_t n = ring.size();
  if (n < 3 || points.empty()) return outline;
  // Each edge as a line: unit direction d, outward normal u = (d.y, -d.x) (right of a CCW ring),
  // offset c = u . p of its points.
  struct Line {
    Point2 d, u;
    double offset;
  };
  std::vector<Line> lines(n);
  std::vector<double> offsets;
  for (std::size_t i = 0; i < n; ++i) {
    const Point2& a = ring[i];
    const Point2& b = ring[(i + 1) % n];
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    if (!(len > 0)) return outline;
    Line& l = lines[i];
    l.d = {(b.x - a.x) / len, (b.y - a.y) / len};
    l.u = {l.d.y, -l.d.x};
    l.offset = l.u.x * a.x + l.u.y * a.y;
    const double margin = std::min(end_margin, len / 4);
    offsets.clear();
    for (const Point3& p : points) {
      const double t = l.d.x * (p.x - a.x) + l.d.y * (p.y - a.y);
      if (t < margin || t > len - margin) continue;
      const double o = l.u.x * p.x + l.u.y * p.y - l.offset;
      if (std::abs(o) <= band) offsets.push_back(o);
    }
    if (static_cast<int>(offsets.size()) < std::max(min_points, 1)) continue;
    const auto k = std::max<std::size_t>(
        2,
        static_cast<std::size_t>(std::floor(params.outermost_share * static_cast<double>(offsets.size()))));
    const std::size_t index = offsets.size() - std::min(k, offsets.size());
    std::nth_element(offsets.begin(), offsets.begin() + static_cast<std::ptrdiff_t>(index), offsets.end());
    l.offset += offsets[index];
  }
  Polygon2 result;
  for (std::size_t i = 0; i < n; ++i) {
    const Line& p = lines[(i + n - 1) % n];
    const Line& q = lines[i];
    // Corner i: u_p . x = c_p and u_q . x = c_q.
    const double det = p.u.x * q.u.y - q.u.x * p.u.y;
    if (std::abs(det) < 1e-3) {
      // Nearly parallel neighbours (a step in a straight wall): keep the corner on q's line.
      const Point2& v = ring[i];
      const double o = q.u.x * v.x + q.u.y * v.y - q.offset;
      result.outer.push_back({v.x - o * q.u.x, v.y - o * q.u.y});
      continue;
    }
    result.outer.push_back(
        {(p.offset * q.u.y - q.offset * p.u.y) / det, (p.u.x * q.offset - q.u.x * p.offset) / det});
  }
  for (std::size_t i = 0; i < n; ++i)
    if (std::hypot(result.outer[i].x - ring[i].x, result.outer[i].y - ring[i].y) > max_shift) return outline;
  const double before = signed_area(ring), after = signed_area(result.outer);
  if (!(after > 0) || std::abs(after - before) > params.max_area_change * std::abs(before) ||
      !ring_is_simple(result.outer))
    return outline;
  result.holes = outline.holes;
  return result;
}

}  // namespace city3d
