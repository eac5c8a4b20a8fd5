// Face hypothesis, step 3: which roof planes are lifted onto each cell of the arrangement, and the
// floor below them. A plane is a candidate over a cell when enough of its points lie in or near the
// cell and its face over the cell rises over no point (surface_support.hpp); the best-supported few
// are kept (the integer program grows with cells x planes). A cell whose one plane is a blade over it
// is offered the nearest planes that are not.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "city3d/log.hpp"
#include "city3d/surface_support.hpp"
#include "hypothesis/steps.hpp"

namespace city3d::detail {

namespace {

// The area of plane r's face over a cell that lies more than the tolerance above the local top.
double unsupported_over(const PlanarSegment& roof, const std::vector<Point2>& cell, const LocalTopRaster& local_top,
                        const SurfaceSupportParams& params) {
  std::vector<Point3> face;
  face.reserve(cell.size());
  for (const Point2& p : cell) face.push_back({p.x, p.y, roof_height(roof, p.x, p.y)});
  return local_top.unsupported_area(face, params);
}

}  // namespace

std::vector<std::vector<int>> cell_roof_planes(const std::vector<Point3>& points,
                                               const std::vector<PlanarSegment>& roofs,
                                               const PlainArrangement& arr, const LocalTopRaster& local_top,
                                               const HypothesisParams& params,
                                               std::vector<std::vector<std::size_t>>* points_inside) {
  const std::size_t R = roofs.size();
  const std::size_t cell_count = arr.cells.size();
  struct PlaneRank {
    std::size_t inside, near;
    int plane;
  };
  std::vector<std::vector<PlaneRank>> ranked(cell_count);
  std::vector<std::vector<int>> cell_planes(cell_count);
  if (points_inside) points_inside->assign(cell_count, {});
  // Every (plane, point) membership, indexed in xy.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> memberships;
  for (std::size_t r = 0; r < R; ++r)
    for (std::uint32_t k : roofs[r].points) memberships.emplace_back(static_cast<std::uint32_t>(r), k);
  const PointGrid membership_grid(memberships.size(), [&](std::size_t i) {
    const Point3& p = points[memberships[i].second];
    return Point2{p.x, p.y};
  });
  std::vector<std::size_t> near_count(R), inside_count(R);
  // A large arrangement gets fewer planes per cell: the problem grows with cells x planes.
  const bool large = cell_count > static_cast<std::size_t>(params.large_cell_count);
  const auto max_planes = static_cast<std::size_t>(large ? std::min(params.max_planes_per_cell, params.max_planes_per_large_cell)
                                                         : params.max_planes_per_cell);
  if (large && max_planes < static_cast<std::size_t>(params.max_planes_per_cell))
    log_debug("hypothesis: " + std::to_string(cell_count) + " cells, at most " + std::to_string(max_planes) +
              " roof planes per cell");
  for (std::size_t c = 0; c < cell_count; ++c) {
    const auto& poly = arr.cells[c].polygon;
    Box2 box;
    for (const auto& p : poly) box.add(p);
    const double cm = params.cell_support_margin;
    std::fill(near_count.begin(), near_count.end(), 0);
    std::fill(inside_count.begin(), inside_count.end(), 0);
    membership_grid.for_each_in(box.min.x - cm, box.min.y - cm, box.max.x + cm, box.max.y + cm, [&](std::uint32_t i) {
      const Point3& pt = points[memberships[i].second];
      if (pt.x < box.min.x - cm || pt.x > box.max.x + cm || pt.y < box.min.y - cm || pt.y > box.max.y + cm) return;
      const int reach = polygon_reach(poly, pt.x, pt.y, cm);
      if (reach >= 1) ++near_count[memberships[i].first];
      if (reach == 2) ++inside_count[memberships[i].first];
    });
    for (std::size_t r = 0; r < R; ++r) {
      const std::size_t need = std::min<std::size_t>(static_cast<std::size_t>(params.min_support_points),
                                                     roofs[r].points.size());
      if (need > 0 && near_count[r] >= need)
        ranked[c].push_back({inside_count[r], near_count[r], static_cast<int>(r)});
    }
    // Best-supported first (points inside the cell, then points near it, then plane index); keep
    // at most max_planes_per_cell. When there are more, planes whose face over the cell would rise
    // over no point (more than max_unsupported_area of it: a steep plane extended beyond its points, a
    // blade above the roof) come after the others: they must not take a better plane's place.
    // The blade test is made in that order and only until max_planes others are found: the planes
    // after them are dropped whether blades or not.
    auto& list = ranked[c];
    std::sort(list.begin(), list.end(), [](const PlaneRank& x, const PlaneRank& y) {
      if (x.inside != y.inside) return x.inside > y.inside;
      if (x.near != y.near) return x.near > y.near;
      return x.plane < y.plane;
    });
    if (list.size() > max_planes) {
      std::vector<PlaneRank> kept, blades;
      for (const PlaneRank& pr : list) {
        if (kept.size() == max_planes) break;
        const bool blade = unsupported_over(roofs[static_cast<std::size_t>(pr.plane)], poly, local_top,
                                            params.surface_support) > params.max_unsupported_area;
        (blade ? blades : kept).push_back(pr);
      }
      for (std::size_t b = 0; b < blades.size() && kept.size() < max_planes; ++b) kept.push_back(blades[b]);
      list = std::move(kept);
    }
    if (list.size() == 1 && max_planes > 1 &&
        unsupported_over(roofs[static_cast<std::size_t>(list[0].plane)], poly, local_top,
                         params.surface_support) > params.max_unsupported_area) {
      // The one plane near the cell is a blade over it (a steep plane beyond its points, often the part
      // beyond a support cut's contour): the planes whose points come nearest that are no blade there
      // are offered beside it, nearest first, so that the selection has another roof to choose.
      std::vector<std::pair<double, int>> others;
      for (std::size_t r = 0; r < R; ++r) {
        if (static_cast<int>(r) == list[0].plane) continue;
        double d = std::numeric_limits<double>::infinity();
        for (std::uint32_t k : roofs[r].points)
          d = std::min(d, distance_to_polygon(poly, points[k].x, points[k].y));
        others.push_back({d, static_cast<int>(r)});
      }
      std::sort(others.begin(), others.end());
      for (const auto& [d, r] : others) {
        if (list.size() == max_planes) break;
        if (unsupported_over(roofs[static_cast<std::size_t>(r)], poly, local_top, params.surface_support) <=
            params.max_unsupported_area)
          list.push_back({0, 0, r});
      }
    }
    for (const auto& pr : list) cell_planes[c].push_back(pr.plane);
    std::sort(cell_planes[c].begin(), cell_planes[c].end());
    if (points_inside) {
      (*points_inside)[c].clear();
      for (int r : cell_planes[c]) (*points_inside)[c].push_back(inside_count[static_cast<std::size_t>(r)]);
    }
    if (cell_planes[c].empty()) {
      // No plane has points near this cell: take the plane(s) whose points come nearest.
      std::vector<double> nearest(R, std::numeric_limits<double>::infinity());
      for (std::size_t r = 0; r < R; ++r)
        for (std::uint32_t k : roofs[r].points)
          nearest[r] = std::min(nearest[r], distance_to_polygon(poly, points[k].x, points[k].y));
      const double best = *std::min_element(nearest.begin(), nearest.end());
      for (std::size_t r = 0; r < R; ++r)
        if (nearest[r] <= best + cm) cell_planes[c].push_back(static_cast<int>(r));
      if (points_inside) (*points_inside)[c].assign(cell_planes[c].size(), 0);

    }
  }
  return cell_planes;
}

// Over measured ground, a plane that dips below ground_z + floor_clearance over a cell is dropped
// there when another candidate of the cell stays above (an unmeasured ground_z is only an upper bound
// of the ground: the bar is then unmeasured_floor_drop lower); the floor is then lowered (never
// raised) to floor_clearance below the lowest remaining roof vertex.
double place_floor(const std::vector<PlanarSegment>& roofs, const PlainArrangement& arr,
                   std::vector<std::vector<int>>& cell_planes, double ground_z, bool ground_measured,
                   const HypothesisParams& params) {
  const std::size_t cell_count = arr.cells.size();
  const double clearance = params.floor_clearance;
  const double bar = ground_z + clearance - (ground_measured ? 0.0 : params.unmeasured_floor_drop);
  auto lowest_over = [&](std::size_t c, int r) {
    double low = std::numeric_limits<double>::infinity();
    for (const auto& p : arr.cells[c].polygon) low = std::min(low, roof_height(roofs[static_cast<std::size_t>(r)], p.x, p.y));
    return low;
  };
  double floor_z = ground_z;
  for (std::size_t c = 0; c < cell_count; ++c) {
    auto& list = cell_planes[c];
    std::vector<int> above;
    for (int r : list)
      if (lowest_over(c, r) >= bar) above.push_back(r);
    if (!above.empty()) list = std::move(above);
    for (int r : list) floor_z = std::min(floor_z, lowest_over(c, r) - clearance);
  }
  if (floor_z < ground_z)
    log_debug("hypothesis: floor lowered by " + std::to_string(ground_z - floor_z) + " m below the roofs");
  return floor_z;
}

namespace {

// The pieces of the line n . x = t (n a unit normal) that run inside the polygon, as curves. The
// crossings of the polygon's edges, in order along the line, pair up (even-odd; a vertex on the line
// counts as on the positive side); each piece overshoots the boundary a little, so that the exact
// arrangement sees it cross (the overshoot is an antenna, which the arrangement removes).
void add_chords(const std::vector<Point2>& poly, const Point2& n, double t, std::vector<InputCurve>& cuts) {
  const Point2 dir{-n.y, n.x};
  const Point2 base{t * n.x, t * n.y};
  std::vector<double> crossings;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Point2 &p = poly[i], &q = poly[(i + 1) % poly.size()];
    const double sp = n.x * p.x + n.y * p.y - t, sq = n.x * q.x + n.y * q.y - t;
    if ((sp >= 0.0) == (sq >= 0.0)) continue;
    const double f = sp / (sp - sq);
    const Point2 x{p.x + f * (q.x - p.x), p.y + f * (q.y - p.y)};
    crossings.push_back((x.x - base.x) * dir.x + (x.y - base.y) * dir.y);
  }
  std::sort(crossings.begin(), crossings.end());
  constexpr double kOvershoot = 0.01;
  for (std::size_t i = 0; i + 1 < crossings.size(); i += 2) {
    const double t0 = crossings[i] - kOvershoot, t1 = crossings[i + 1] + kOvershoot;
    cuts.push_back({{base.x + t0 * dir.x, base.y + t0 * dir.y}, {base.x + t1 * dir.x, base.y + t1 * dir.y},
                    CurveKind::roof_line, -1});
  }
}

// A line that separates a plane's own points in a cell from the part of its face there that rises over
// no point: among the directions of the cell's edges (a building's lines are few, and mostly parallel or
// orthogonal), the one along which the two sets overlap least, projected on its normal; the threshold
// midway across the gap. Returns false when every direction leaves more than support_cut_mixed of either set
// on the wrong side (the two are interleaved: no line ends the face where its points end).
bool separating_line(const std::vector<Point2>& poly, const std::vector<Point2>& own,
                     const std::vector<Point2>& bare, const HypothesisParams& params, Point2& normal,
                     double& threshold) {
  const double max_mixed = params.support_cut_mixed;
  std::vector<Point2> normals;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Point2 &p = poly[i], &q = poly[(i + 1) % poly.size()];
    const double length = std::hypot(q.x - p.x, q.y - p.y);
    if (!(length > params.support_cut_min_edge)) continue;
    Point2 n{-(q.y - p.y) / length, (q.x - p.x) / length};
    if (n.x < 0.0 || (n.x == 0.0 && n.y < 0.0)) n = {-n.x, -n.y};  // one of +-n
    const bool seen = std::any_of(normals.begin(), normals.end(), [&](const Point2& m) {
      return std::abs(m.x * n.y - m.y * n.x) < params.support_cut_same_direction;
    });
    if (!seen) normals.push_back(n);
  }
  double best_mixed = std::numeric_limits<double>::infinity(), best_gap = 0.0;
  for (const Point2& n : normals) {
    std::vector<std::pair<double, int>> values;  // (projection, 0 own / 1 bare)
    for (const Point2& p : own) values.emplace_back(n.x * p.x + n.y * p.y, 0);
    for (const Point2& p : bare) values.emplace_back(n.x * p.x + n.y * p.y, 1);
    std::sort(values.begin(), values.end());
    // Sweep the cut between consecutive values: on one side own below and bare above, or the reverse.
    std::size_t own_left = 0, bare_left = 0;
    for (std::size_t i = 0; i + 1 < values.size(); ++i) {
      (values[i].second ? bare_left : own_left)++;
      const double gap = values[i + 1].first - values[i].first;
      if (!(gap > 0.0)) continue;
      const std::size_t own_right = own.size() - own_left, bare_right = bare.size() - bare_left;
      for (int side = 0; side < 2; ++side) {
        const std::size_t wrong_own = side ? own_left : own_right, wrong_bare = side ? bare_right : bare_left;
        const double mixed = std::max(static_cast<double>(wrong_own) / static_cast<double>(own.size()),
                                      static_cast<double>(wrong_bare) / static_cast<double>(bare.size()));
        if (mixed < best_mixed - 1e-12 || (mixed <= best_mixed + 1e-12 && gap > best_gap)) {
          best_mixed = mixed;
          best_gap = gap;
          normal = n;
          threshold = 0.5 * (values[i].first + values[i + 1].first);
        }
      }
    }
  }
  return best_mixed <= max_mixed;
}

}  // namespace

std::vector<InputCurve> support_cuts(const std::vector<Point3>& points, const std::vector<PlanarSegment>& roofs,
                                     const PlainArrangement& arr, const std::vector<std::vector<int>>& cell_planes,
                                     const std::vector<std::vector<std::size_t>>& points_inside,
                                     const LocalTopRaster& local_top, const HypothesisParams& params) {
  // The height range of each plane's points.
  std::vector<double> top(roofs.size(), -std::numeric_limits<double>::infinity());
  for (std::size_t r = 0; r < roofs.size(); ++r)
    for (std::uint32_t k : roofs[r].points) top[r] = std::max(top[r], points[k].z);
  const SurfaceSupportParams& sp = params.surface_support;
  std::vector<InputCurve> cuts;
  for (std::size_t c = 0; c < arr.cells.size(); ++c) {
    const auto& poly = arr.cells[c].polygon;
    const std::size_t most =
        points_inside[c].empty() ? 0 : *std::max_element(points_inside[c].begin(), points_inside[c].end());
    for (std::size_t k = 0; k < cell_planes[c].size(); ++k) {
      const int r = cell_planes[c][k];
      // A plane without points of its own in the cell is not its roof anywhere: the selection's E_u
      // keeps its face out. A plane with some is cut, even with few: most of its points can lie beside
      // the cell, and the cut then stands in for a line the arrangement lacks (a ridge, a hip, a step).
      if (points_inside[c][k] < static_cast<std::size_t>(params.min_support_points)) continue;
      const PlanarSegment& roof = roofs[static_cast<std::size_t>(r)];
      const Plane3& pl = roof.plane;
      const double level = top[static_cast<std::size_t>(r)] + params.support_cut_height;
      double highest = -std::numeric_limits<double>::infinity(), lowest = -highest;
      for (const Point2& p : poly) {
        const double z = roof_height(roof, p.x, p.y);
        highest = std::max(highest, z);
        lowest = std::min(lowest, z);
      }
      const double norm = std::hypot(pl.a, pl.b);
      if (highest > level + params.support_cut_rise && lowest < level && norm > 0.0) {
        // A blade: a face that rises more than support_cut_rise beyond its points' top plus
        // support_cut_height within the cell, over no point there, is cut at its contour at that
        // height, a x + b y = -(c level + d).
        if (!(unsupported_over(roof, poly, local_top, sp) > params.max_unsupported_area)) continue;
        add_chords(poly, {pl.a / norm, pl.b / norm}, -(pl.c * level + pl.d) / norm, cuts);
        continue;
      }
      // A face that overhangs lower ground or a lower part (a roof plane over an annex beside it): where
      // more than support_cut_area of it rises over no point, the line that separates its own points in
      // the cell from that part, if one does. Only for the cell's own roof (a plane with at least half as
      // many points in it as the plane with most): a cut adds cells and edges, and the complexity term,
      // normalised by the number of edges, then weighs every corner less.
      if (2 * points_inside[c][k] < most) continue;
      std::vector<Point3> face;
      for (const Point2& p : poly) face.push_back({p.x, p.y, roof_height(roof, p.x, p.y)});
      Box2 box;
      for (const Point2& p : poly) box.add(p);
      if (!(highest - local_top.lower_bound_in(box) > sp.tolerance)) continue;
      std::vector<Point2> bare;
      std::vector<Point3> samples;
      const double piece = sample_polygon(face, sp.sample_spacing, samples);
      for (const Point3& p : samples)
        if (local_top.above(p.x, p.y, p.z, sp.tolerance)) bare.push_back({p.x, p.y});
      const double bare_area = piece * static_cast<double>(bare.size());
      if (!(bare_area > params.support_cut_area)) continue;
      std::vector<Point2> own;
      for (std::uint32_t i : roof.points)
        if (inside_polygon(poly, points[i].x, points[i].y)) own.push_back({points[i].x, points[i].y});
      Point2 n;
      double t = 0.0;
      if (own.size() >= static_cast<std::size_t>(params.min_support_points) &&
          separating_line(poly, own, bare, params, n, t))
        add_chords(poly, n, t, cuts);
    }
  }
  return cuts;
}

}  // namespace city3d::detail
