// Face hypothesis, step 3: which roof planes are lifted onto each cell of the arrangement, and the
// floor below them. A plane is a candidate over a cell when enough of its points lie in or near the
// cell and its face over the cell rises over no point (surface_support.hpp); the best-supported few
// are kept (the integer program grows with cells x planes).
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
    bool blade = false;
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
      const double d = distance_to_polygon(poly, pt.x, pt.y);
      if (d <= cm) ++near_count[memberships[i].first];
      if (d <= 0.0) ++inside_count[memberships[i].first];
    });
    for (std::size_t r = 0; r < R; ++r) {
      const std::size_t need = std::min<std::size_t>(static_cast<std::size_t>(params.min_support_points),
                                                     roofs[r].points.size());
      if (need > 0 && near_count[r] >= need)
        ranked[c].push_back({inside_count[r], near_count[r], static_cast<int>(r), false});
    }
    // Best-supported first (points inside the cell, then points near it, then plane index); keep
    // at most max_planes_per_cell. When there are more, planes whose face over the cell would rise
    // over no point (more than max_unsupported_area of it: a steep plane extended beyond its points, a
    // blade above the roof) come after the others: they must not take a better plane's place.
    auto& list = ranked[c];
    if (list.size() > max_planes)
      for (auto& pr : list)
        pr.blade = unsupported_over(roofs[static_cast<std::size_t>(pr.plane)], poly, local_top,
                                    params.surface_support) > params.max_unsupported_area;
    std::sort(list.begin(), list.end(), [](const PlaneRank& x, const PlaneRank& y) {
      if (x.blade != y.blade) return y.blade;
      if (x.inside != y.inside) return x.inside > y.inside;
      if (x.near != y.near) return x.near > y.near;
      return x.plane < y.plane;
    });
    if (list.size() > max_planes) list.resize(max_planes);
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

std::vector<InputCurve> support_cuts(const std::vector<Point3>& points, const std::vector<PlanarSegment>& roofs,
                                     const PlainArrangement& arr, const std::vector<std::vector<int>>& cell_planes,
                                     const std::vector<std::vector<std::size_t>>& points_inside,
                                     const LocalTopRaster& local_top, const HypothesisParams& params) {
  // The height range of each plane's points.
  std::vector<double> top(roofs.size(), -std::numeric_limits<double>::infinity());
  for (std::size_t r = 0; r < roofs.size(); ++r)
    for (std::uint32_t k : roofs[r].points) top[r] = std::max(top[r], points[k].z);
  std::vector<InputCurve> cuts;
  for (std::size_t c = 0; c < arr.cells.size(); ++c) {
    const auto& poly = arr.cells[c].polygon;
    for (std::size_t k = 0; k < cell_planes[c].size(); ++k) {
      const int r = cell_planes[c][k];
      // A plane without points of its own in the cell is not its roof anywhere: the selection's E_u
      // keeps its face out. A plane with some is cut, even with few: most of its points can lie beside
      // the cell, and the contour then stands in for a line the arrangement lacks (a ridge, a hip).
      if (points_inside[c][k] < static_cast<std::size_t>(params.min_support_points)) continue;
      const PlanarSegment& roof = roofs[static_cast<std::size_t>(r)];
      const double level = top[static_cast<std::size_t>(r)] + params.support_cut_height;
      double highest = -std::numeric_limits<double>::infinity(), lowest = -highest;
      for (const Point2& p : poly) {
        const double z = roof_height(roof, p.x, p.y);
        highest = std::max(highest, z);
        lowest = std::min(lowest, z);
      }
      // Only a blade is cut: a face that rises more than support_cut_rise beyond the cut within the
      // cell, and whose part beyond it lies over no point. A face that leaves its points' height range
      // by less is weighed by E_u as it is (a cut there would only add cells).
      if (!(highest > level + params.support_cut_rise && lowest < level)) continue;
      if (!(unsupported_over(roof, poly, local_top, params.surface_support) > params.max_unsupported_area)) continue;
      // The contour a x + b y = -(c level + d) in plan, and where it runs inside the cell: the crossings
      // of the polygon's edges, in order along the line, pair up (even-odd; a vertex on the line counts
      // as on the positive side).
      const Plane3& pl = roof.plane;
      const double norm = std::hypot(pl.a, pl.b);
      const double offset = pl.c * level + pl.d;
      const Point2 dir{-pl.b / norm, pl.a / norm};
      const Point2 base{-offset * pl.a / (norm * norm), -offset * pl.b / (norm * norm)};
      std::vector<double> crossings;
      for (std::size_t i = 0; i < poly.size(); ++i) {
        const Point2 &p = poly[i], &q = poly[(i + 1) % poly.size()];
        const double sp = pl.a * p.x + pl.b * p.y + offset, sq = pl.a * q.x + pl.b * q.y + offset;
        if ((sp >= 0.0) == (sq >= 0.0)) continue;
        const double t = sp / (sp - sq);
        const Point2 x{p.x + t * (q.x - p.x), p.y + t * (q.y - p.y)};
        crossings.push_back((x.x - base.x) * dir.x + (x.y - base.y) * dir.y);
      }
      std::sort(crossings.begin(), crossings.end());
      // Each piece overshoots the cell's boundary a little, so that the exact arrangement sees it
      // cross; the overshoot is an antenna, which the arrangement removes.
      constexpr double kOvershoot = 0.01;
      for (std::size_t i = 0; i + 1 < crossings.size(); i += 2) {
        const double t0 = crossings[i] - kOvershoot, t1 = crossings[i + 1] + kOvershoot;
        cuts.push_back({{base.x + t0 * dir.x, base.y + t0 * dir.y}, {base.x + t1 * dir.x, base.y + t1 * dir.y},
                        CurveKind::roof_line, -1});
      }
    }
  }
  return cuts;
}

}  // namespace city3d::detail
