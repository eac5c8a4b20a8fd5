// The outline a LoD2 rung builds on, and the plan-view facts of planes and parts (outline.hpp).
#include "pipeline/outline.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "city3d/error.hpp"
#include "city3d/log.hpp"
#include "city3d/rings.hpp"

namespace city3d::detail {
namespace {

// The parts of an inferred outline to model (largest first): the largest, and every further part of
// min_extra_part_area or more that holds more than extra_part_plane_share of the points of some roof plane
// and keeps clear (by part_gap) of the parts already kept (fitting an outline to its points can push two
// parts into each other: then the part as inferred, and if that touches too, it is left out rather than made
// to touch). Leaving a part out shows in unexplained_points.
std::vector<Polygon2> separate_parts(const std::vector<Polygon2>& parts, const std::vector<Polygon2>& as_inferred,
                                     const std::vector<PlanarSegment>& roofs, const std::vector<Point3>& points,
                                     const OutlineParams& params) {
  std::vector<std::size_t> kept_index{0};
  std::vector<Polygon2> kept{parts.front()};
  const auto near_kept = [&](const Polygon2& part) {
    std::vector<std::size_t> near;
    for (std::size_t j = 0; j < kept.size(); ++j)
      if (rings_near(part.outer, kept[j].outer, params.part_gap)) near.push_back(j);
    return near;
  };
  for (std::size_t k = 1; k < parts.size(); ++k) {
    if (ring_area(parts[k].outer) < params.min_extra_part_area) continue;
    const bool has_plane = std::any_of(roofs.begin(), roofs.end(), [&](const PlanarSegment& s) {
      return static_cast<double>(points_inside(parts[k].outer, s.points, points)) >
             params.extra_part_plane_share * static_cast<double>(s.points.size());
    });
    if (!has_plane) continue;
    // The part as regularised and fitted to its points; else as inferred (the regions of the
    // occupancy raster lie apart, but fitting moves edges out by up to 1.5 m), with the parts it
    // would touch taken as inferred too.
    if (near_kept(parts[k]).empty()) {
      kept.push_back(parts[k]);
      kept_index.push_back(k);
      continue;
    }
    const std::vector<std::size_t> near = near_kept(as_inferred[k]);
    std::vector<Polygon2> trial = kept;
    for (std::size_t j : near) trial[j] = as_inferred[kept_index[j]];
    bool clear = true;
    for (std::size_t i = 0; i < trial.size() && clear; ++i) {
      clear = !rings_near(as_inferred[k].outer, trial[i].outer, params.part_gap);
      for (std::size_t j : near)
        if (j != i && rings_near(trial[j].outer, trial[i].outer, params.part_gap)) clear = false;
    }
    if (!clear) continue;
    kept = std::move(trial);
    kept.push_back(as_inferred[k]);
    kept_index.push_back(k);
  }
  log_debug("outline: " + std::to_string(parts.size()) + " parts inferred, " + std::to_string(kept.size()) + " modelled");
  return kept;
}

}  // namespace

std::vector<Polygon2> building_outline(const BuildingInput& input, const Heightmap& heightmap,
                                       const std::vector<PlanarSegment>& roofs, const ReconstructionParams& params,
                                       bool wide_outline, BuildingReport& report) {
  if (input.footprint_given) return input.footprint.polygons;
  const std::vector<Point3>& points = input.points;
  std::vector<Polygon2> outline;
  const std::vector<Polygon2> inferred =
      infer_outline(heightmap, points, params.polylines.max_hausdorff, params.outline.min_region_area,
                    wide_outline ? params.outline.wide_gap_spacings : params.outline.gap_spacings);
  for (const Polygon2& p : inferred)
    outline.push_back(
        fit_outline_to_points(regularise_outline(p, params.regularise.angle_threshold, params.outline.snap),
                              points, params.outline.fit));
  if (outline.empty() && !input.footprint.polygons.empty()) {
    // Too small for the heightmap to hold an outline (under min_region_area): the convex
    // hull of the points (building_from_cloud), regularised like an inferred outline.
    outline.push_back(regularise_outline(input.footprint.polygons.front(), params.regularise.angle_threshold,
                                         params.outline.snap));
    add_note(report, "outline: convex hull of the points");
  }
  if (outline.empty()) throw ReconstructionError(ReconstructionStage::walls, "no outline could be inferred from the points");
  if (outline.size() > 1) outline = separate_parts(outline, inferred, roofs, points, params.outline);
  if (outline.size() > 1) add_note(report, "outline: " + std::to_string(outline.size()) + " parts");
  return outline;
}

std::pair<Point2, Point2> wall_line(const PlanarSegment& wall, const std::vector<Point3>& points) {
  const double nx = wall.plane.a, ny = wall.plane.b;
  const double len = std::hypot(nx, ny);
  const double dx = -ny / len, dy = nx / len;  // along the wall
  double lo = 1e300, hi = -1e300, cx = 0, cy = 0;
  for (std::uint32_t i : wall.points) {
    const double t = points[i].x * dx + points[i].y * dy;
    lo = std::min(lo, t);
    hi = std::max(hi, t);
    cx += points[i].x;
    cy += points[i].y;
  }
  cx /= wall.points.size();
  cy /= wall.points.size();
  const double tc = cx * dx + cy * dy;
  return {{cx + (lo - tc) * dx, cy + (lo - tc) * dy}, {cx + (hi - tc) * dx, cy + (hi - tc) * dy}};
}

std::vector<PlanarSegment> roofs_of_part(const std::vector<PlanarSegment>& roofs, const Polygon2& part,
                                         const std::vector<Point3>& points, double share) {
  std::vector<PlanarSegment> held;
  for (const PlanarSegment& s : roofs) {
    if (static_cast<double>(points_inside(part.outer, s.points, points)) >=
        share * static_cast<double>(s.points.size()))
      held.push_back(s);
  }
  return held;
}

double point_spacing(const std::vector<Polygon2>& outline, std::size_t points) {
  const double area = polygons_area(outline);
  return points > 0 && area > 0 ? std::sqrt(area / static_cast<double>(points)) : 0.0;
}

}  // namespace city3d::detail
