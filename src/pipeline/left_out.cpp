// Roof levels and cells for the points a LoD2 model leaves out (see left_out.hpp).
#include "pipeline/left_out.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <utility>

#include "core/union_find.hpp"

namespace city3d::detail {

namespace {

// The loose points: left out, and in no segment (ascending).
std::vector<std::uint32_t> loose_points(std::size_t n, const std::vector<PlanarSegment>& segments,
                                        const std::vector<bool>& unexplained) {
  std::vector<bool> segmented(n);
  for (const PlanarSegment& s : segments)
    for (std::uint32_t i : s.points) segmented[i] = true;
  std::vector<std::uint32_t> loose;
  for (std::uint32_t i = 0; i < n; ++i)
    if (unexplained[i] && !segmented[i]) loose.push_back(i);
  return loose;
}

// The groups of `loose` whose points are linked within `radius` in plan and `height` in height, links
// chained; each group ascending, the groups in the order of their smallest point.
std::vector<std::vector<std::uint32_t>> linked_groups(const std::vector<Point3>& points,
                                                      const std::vector<std::uint32_t>& loose, double radius,
                                                      double height) {
  // Union-find over the loose points; neighbours from a grid of radius-sized cells.
  UnionFind linked(loose.size());
  std::map<std::pair<long long, long long>, std::vector<std::uint32_t>> grid;
  const auto cell = [radius](const Point3& p) {
    return std::pair{static_cast<long long>(std::floor(p.x / radius)), static_cast<long long>(std::floor(p.y / radius))};
  };
  for (std::uint32_t k = 0; k < loose.size(); ++k) grid[cell(points[loose[k]])].push_back(k);
  for (std::uint32_t k = 0; k < loose.size(); ++k) {
    const Point3& p = points[loose[k]];
    const auto [cx, cy] = cell(p);
    for (long long dx = -1; dx <= 1; ++dx)
      for (long long dy = -1; dy <= 1; ++dy) {
        const auto it = grid.find({cx + dx, cy + dy});
        if (it == grid.end()) continue;
        for (std::uint32_t j : it->second) {
          if (j <= k) continue;
          const Point3& q = points[loose[j]];
          if (std::hypot(p.x - q.x, p.y - q.y) <= radius && std::fabs(p.z - q.z) <= height)
            linked.join_to_smaller(k, j);
        }
      }
  }
  // Each root is its group's smallest member.
  std::map<std::size_t, std::vector<std::uint32_t>> groups;
  for (std::uint32_t k = 0; k < loose.size(); ++k) groups[linked.find(k)].push_back(loose[k]);
  std::vector<std::vector<std::uint32_t>> out;
  out.reserve(groups.size());
  for (auto& [first, members] : groups) out.push_back(std::move(members));
  return out;
}

}  // namespace

std::vector<PlanarSegment> left_out_levels(const std::vector<Point3>& points,
                                           const std::vector<PlanarSegment>& segments,
                                           const std::vector<bool>& unexplained, double spacing,
                                           std::size_t min_points, const RebuildParams& params) {
  std::vector<PlanarSegment> levels;
  const std::vector<std::uint32_t> loose = loose_points(points.size(), segments, unexplained);
  const double radius = params.level_link_spacings * spacing;
  if (loose.size() < min_points || !(radius > 0)) return levels;
  for (std::vector<std::uint32_t>& members : linked_groups(points, loose, radius, params.level_link_height)) {
    if (members.size() < min_points) continue;
    std::vector<double> z;
    z.reserve(members.size());
    for (std::uint32_t i : members) z.push_back(points[i].z);
    std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(z.size() / 2), z.end());
    const double height = z[z.size() / 2];
    PlanarSegment level;
    level.plane = {0.0, 0.0, 1.0, -height};
    level.kind = PlanarSegment::Kind::roof;
    double squares = 0.0;
    for (std::uint32_t i : members) squares += (points[i].z - height) * (points[i].z - height);
    level.rms = std::sqrt(squares / static_cast<double>(members.size()));
    level.points = std::move(members);
    levels.push_back(std::move(level));
  }
  return levels;
}

std::vector<PlanarSegment> left_out_planes(const std::vector<Point3>& points,
                                           const std::vector<PlanarSegment>& segments,
                                           const std::vector<bool>& unexplained, double spacing,
                                           std::size_t min_points, const PlaneParams& plane_params,
                                           const RebuildParams& params) {
  std::vector<PlanarSegment> planes;
  const std::vector<std::uint32_t> loose = loose_points(points.size(), segments, unexplained);
  const double radius = params.level_link_spacings * spacing;
  min_points = std::max<std::size_t>(min_points, params.left_out_plane_min_points);
  if (loose.size() < min_points || !(radius > 0)) return planes;
  const double any_height = std::numeric_limits<double>::infinity();
  for (const std::vector<std::uint32_t>& members : linked_groups(points, loose, radius, any_height)) {
    if (members.size() < min_points || members.size() > params.max_left_out_plane_points) continue;
    std::vector<Point3> group;
    group.reserve(members.size());
    for (std::uint32_t i : members) group.push_back(points[i]);
    // A plane of at least half the group (and 4 points): the group is mostly that plane, or it is left
    // to its level (rebuild.left_out_plane_divisor, left_out_plane_min_points).
    const std::size_t divisor = params.left_out_plane_divisor;
    const std::size_t least =
        std::max<std::size_t>(params.left_out_plane_min_points, (members.size() + divisor - 1) / divisor);
    for (PlanarSegment& s :
         detect_planes_of_few_points(group, plane_params, least, params.max_left_out_plane_points)) {
      if (s.kind != PlanarSegment::Kind::roof) continue;
      for (std::uint32_t& i : s.points) i = members[i];  // members ascending: the order stays
      planes.push_back(std::move(s));
    }
  }
  return planes;
}

std::vector<Segment2> left_out_plane_lines(const std::vector<Point3>& points, const std::vector<PlanarSegment>& roofs,
                                           const std::vector<bool>& unexplained, const std::vector<Polygon2>& outline,
                                           const RebuildParams& params) {
  std::vector<Point2> directions;  // unit, one per outline edge
  const auto add_directions = [&directions](const Ring2& ring) {
    for (std::size_t k = 0; k < ring.size(); ++k) {
      const Point2 &a = ring[k], &b = ring[(k + 1) % ring.size()];
      const double length = std::hypot(b.x - a.x, b.y - a.y);
      if (length > 0) directions.push_back({(b.x - a.x) / length, (b.y - a.y) / length});
    }
  };
  for (const Polygon2& polygon : outline) {
    add_directions(polygon.outer);
    for (const Ring2& hole : polygon.holes) add_directions(hole);
  }
  std::vector<Segment2> lines;
  if (directions.empty()) return lines;
  for (const PlanarSegment& roof : roofs) {
    std::vector<Point2> left;
    for (std::uint32_t i : roof.points)
      if (unexplained[i]) left.push_back({points[i].x, points[i].y});
    if (left.size() < 3 || static_cast<double>(left.size()) <
                               params.left_out_cell_share * static_cast<double>(roof.points.size()))
      continue;
    double best = std::numeric_limits<double>::infinity();
    std::array<Point2, 4> corners{};
    for (const Point2& u : directions) {
      // Extents along u and along its left normal v = (-u.y, u.x).
      double u0 = std::numeric_limits<double>::infinity(), u1 = -u0, v0 = u0, v1 = -u0;
      for (const Point2& p : left) {
        const double pu = p.x * u.x + p.y * u.y, pv = -p.x * u.y + p.y * u.x;
        u0 = std::min(u0, pu), u1 = std::max(u1, pu), v0 = std::min(v0, pv), v1 = std::max(v1, pv);
      }
      const double area = (u1 - u0) * (v1 - v0);
      if (std::min(u1 - u0, v1 - v0) < params.min_left_out_width || !(area < best)) continue;
      best = area;
      const auto at = [&u](double pu, double pv) { return Point2{pu * u.x - pv * u.y, pu * u.y + pv * u.x}; };
      corners = {at(u0, v0), at(u1, v0), at(u1, v1), at(u0, v1)};
    }
    if (!std::isfinite(best)) continue;
    for (std::size_t k = 0; k < 4; ++k) lines.push_back({corners[k], corners[(k + 1) % 4]});
  }
  return lines;
}

}  // namespace city3d::detail
