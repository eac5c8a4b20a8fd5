// Face hypothesis, step 5: the selection problem over the candidate faces (paper section 3.3 and
// its appendix): the support of every face (the data term), the edges of the faces' union with their
// sharp pairs (the complexity term and the 0-or-2 constraint), the floors forced on, the face prior
// of every roof segment, and the vertically overlapping roof faces (single-layer roof).
//
// Support: the number of points within support_distance of the face's plane whose projection falls
// inside the face polygon. For a roof face only the points of its own planar segment count (as in
// PolyFit); for walls and the floor every point counts.
//
// Unsupported area (E_u of selection.hpp): the area of the face more than surface_support.tolerance
// above the highest point within surface_support.radius of it in plan (surface_support.hpp); 0 for the
// floor. The face prior of a segment is its best-supported face among those whose data term outweighs
// their unsupported-area term: the prior must not force a blade on.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

#include "hypothesis/steps.hpp"

namespace city3d::detail {

void build_selection_problem(const std::vector<Point3>& points, const std::vector<PlanarSegment>& roofs,
                             const PlainArrangement& arr, double floor_z,
                             const std::vector<std::vector<std::uint32_t>>& edge_faces, const LocalTopRaster& local_top,
                             const HypothesisParams& params, const SelectionParams& energy, CandidateFaces& out) {
  const std::size_t R = roofs.size();
  const std::size_t cell_count = arr.cells.size();
  SelectionProblem& prob = out.problem;
  const std::size_t nf = out.faces.size();
  prob.face_count = nf;
  prob.point_count = points.size();
  prob.support.assign(nf, 0.0);
  prob.centroid_z.resize(nf);
  prob.is_roof.resize(nf);
  if (!points.empty()) {
    prob.z_min = std::numeric_limits<double>::infinity();
    prob.z_max = -prob.z_min;
    for (const auto& p : points) {
      prob.z_min = std::min(prob.z_min, p.z);
      prob.z_max = std::max(prob.z_max, p.z);
    }
    if (!(prob.z_max > prob.z_min)) prob.z_max = prob.z_min + 1.0;
  }
  std::vector<int> segment_of(points.size(), -1);
  for (std::size_t r = 0; r < R; ++r)
    for (auto k : roofs[r].points) segment_of[k] = static_cast<int>(r);
  const double eps = params.support_distance;
  // Roof and floor faces: the points over their cell.
  const PointGrid point_grid(points.size(), [&](std::size_t k) { return Point2{points[k].x, points[k].y}; });
  std::vector<std::vector<std::uint32_t>> cell_points(cell_count);
  for (std::size_t c = 0; c < cell_count; ++c) {
    Box2 box;
    for (const auto& p : arr.cells[c].polygon) box.add(p);
    point_grid.for_each_in(box.min.x, box.min.y, box.max.x, box.max.y, [&](std::uint32_t k) {
      const auto& p = points[k];
      if (p.x < box.min.x || p.x > box.max.x || p.y < box.min.y || p.y > box.max.y) return;
      if (inside_polygon(arr.cells[c].polygon, p.x, p.y)) cell_points[c].push_back(k);
    });
    std::sort(cell_points[c].begin(), cell_points[c].end());
  }
  for (std::size_t i = 0; i < nf; ++i) {
    const auto& f = out.faces[i];
    const auto& poly = out.polygons[i];
    prob.centroid_z[i] = centroid(poly).z;
    prob.is_roof[i] = f.kind == FaceKind::roof;
    double support = 0.0;
    if (f.kind == FaceKind::roof) {
      const Plane3& pl = roofs[static_cast<std::size_t>(f.source)].plane;
      for (auto k : cell_points[f.cell_or_edge])
        if (segment_of[k] == f.source && std::abs(pl.signed_distance(points[k])) <= eps) support += 1.0;
    } else if (f.kind == FaceKind::floor) {
      for (auto k : cell_points[f.cell_or_edge])
        if (std::abs(points[k].z - floor_z) <= eps) support += 1.0;
    } else {
      const auto& edge = arr.edges[f.cell_or_edge];
      const Point2 a = arr.vertices[edge.u], b = arr.vertices[edge.w];
      const double len = std::hypot(b.x - a.x, b.y - a.y);
      const double dx = (b.x - a.x) / len, dy = (b.y - a.y) / len;
      std::vector<Point2> tz;  // the face in (along the edge, z)
      double zlo = std::numeric_limits<double>::infinity(), zhi = -zlo;
      for (const auto& p : poly) {
        tz.push_back({(p.x - a.x) * dx + (p.y - a.y) * dy, p.z});
        zlo = std::min(zlo, p.z);
        zhi = std::max(zhi, p.z);
      }
      point_grid.for_each_in(std::min(a.x, b.x) - eps, std::min(a.y, b.y) - eps, std::max(a.x, b.x) + eps,
                             std::max(a.y, b.y) + eps, [&](std::uint32_t k) {
        const auto& p = points[k];
        if (p.z < zlo || p.z > zhi) return;
        const double across = -(p.x - a.x) * dy + (p.y - a.y) * dx;
        if (std::abs(across) > eps) return;
        const double along = (p.x - a.x) * dx + (p.y - a.y) * dy;
        if (along < 0.0 || along > len) return;
        if (inside_polygon(tz, along, p.z)) support += 1.0;
      });
    }
    prob.support[i] = support;
  }
  prob.plan_area = 0.0;
  for (const auto& cell : arr.cells) prob.plan_area += cell.area;
  prob.unsupported.assign(nf, 0.0);
  const SurfaceSupportParams& sp = params.surface_support;
  for (std::size_t i = 0; i < nf; ++i) {
    if (out.faces[i].kind == FaceKind::floor) continue;
    prob.unsupported[i] = local_top.unsupported_area(out.polygons[i], sp);
  }

  for (const auto& list : edge_faces) {
    SelectionProblem::Edge edge;
    edge.faces = list;
    for (std::size_t i = 0; i < edge.faces.size(); ++i)
      for (std::size_t j = i + 1; j < edge.faces.size(); ++j)
        if (out.faces[edge.faces[i]].plane_id != out.faces[edge.faces[j]].plane_id)
          edge.sharp_pairs.emplace_back(edge.faces[i], edge.faces[j]);
    prob.edges.push_back(std::move(edge));
  }

  std::vector<std::vector<std::uint32_t>> roofs_over_cell(cell_count);
  std::vector<long> prior(R, -1);
  for (std::uint32_t i = 0; i < nf; ++i) {
    const auto& f = out.faces[i];
    if (f.kind == FaceKind::floor) prob.forced_on.push_back(i);
    if (f.kind != FaceKind::roof) continue;
    roofs_over_cell[f.cell_or_edge].push_back(i);
    auto& best = prior[static_cast<std::size_t>(f.source)];
    const bool pays = prob.plan_area > 0.0 && prob.point_count > 0 &&
                      energy.lambda_data * prob.support[i] / static_cast<double>(prob.point_count) >
                          energy.lambda_unsupported * prob.unsupported[i] / prob.plan_area;
    if (prob.support[i] > 0.0 && f.area >= params.min_face_area && pays &&
        (best < 0 || prob.support[i] > prob.support[static_cast<std::size_t>(best)]))
      best = i;
  }
  // A cell's floor is always on, so closing the solid over it takes exactly one of its roof faces.
  for (const auto& list : roofs_over_cell) {
    for (std::size_t i = 0; i < list.size(); ++i)
      for (std::size_t j = i + 1; j < list.size(); ++j) prob.vertical_overlaps.emplace_back(list[i], list[j]);
    if (!list.empty()) prob.exactly_one.push_back(list);
  }
  for (long p : prior)
    if (p >= 0) prob.face_prior.push_back(static_cast<std::uint32_t>(p));
  std::sort(prob.face_prior.begin(), prob.face_prior.end());
}

}  // namespace city3d::detail
