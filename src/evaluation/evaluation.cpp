// Model evaluation: point-to-surface RMSE (CGAL AABB tree over an ear-clipped triangulation) and
// validity checks (topology by directed-edge counting, geometry by Newell planes, CGAL
// self-intersection test on the triangulated surface).
#include "city3d/evaluation.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <sstream>
#include <unordered_map>
#include <vector>

#include "city3d/error.hpp"
#include "core/mesh_faces.hpp"
#include "core/vec.hpp"

namespace city3d {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Triangle = std::array<std::uint32_t, 3>;

using detail::cross;
using detail::dot;
using detail::sub;
using detail::Vec;

bool indices_valid(const PolygonMesh& mesh, const std::vector<std::uint32_t>& face) {
  return face.size() >= 3 && detail::indices_in_range(face, mesh.vertices);
}

/// Ear clipping of one face in 2D: drop the dominant axis of the Newell normal, keep the polygon
/// counter-clockwise, clip strictly convex corners whose triangle holds no other remaining vertex
/// (a vertex on the triangle's boundary also blocks it, so no T-junction is created).
void triangulate_face(const PolygonMesh& mesh, const std::vector<std::uint32_t>& face,
                      std::vector<Triangle>& out) {
  if (!indices_valid(mesh, face)) return;
  const std::size_t n = face.size();
  if (n == 3) {
    out.push_back({face[0], face[1], face[2]});
    return;
  }
  const Vec normal = detail::newell_normal(mesh.vertices, face);
  const double ax = std::fabs(normal.x), ay = std::fabs(normal.y), az = std::fabs(normal.z);
  // 2D coordinates (u, v) such that the polygon is counter-clockwise when the normal points at us.
  std::vector<double> u(n), v(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Point3& p = mesh.vertices[face[i]];
    if (az >= ax && az >= ay) {
      u[i] = p.x;
      v[i] = normal.z >= 0 ? p.y : -p.y;
    } else if (ax >= ay) {
      u[i] = p.y;
      v[i] = normal.x >= 0 ? p.z : -p.z;
    } else {
      u[i] = p.z;
      v[i] = normal.y >= 0 ? p.x : -p.x;
    }
  }
  double scale = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    scale = std::max({scale, std::fabs(u[i] - u[0]), std::fabs(v[i] - v[0])});
  const double eps = 1e-12 * std::max(scale * scale, 1e-300);
  const auto orient = [&](std::size_t a, std::size_t b, std::size_t c) {
    return (u[b] - u[a]) * (v[c] - v[a]) - (v[b] - v[a]) * (u[c] - u[a]);
  };

  std::vector<std::size_t> ring(n);
  std::iota(ring.begin(), ring.end(), 0);
  while (ring.size() > 3) {
    const std::size_t m = ring.size();
    bool clipped = false;
    for (std::size_t k = 0; k < m && !clipped; ++k) {
      const std::size_t a = ring[(k + m - 1) % m], b = ring[k], c = ring[(k + 1) % m];
      if (orient(a, b, c) <= eps) continue;  // reflex or collinear corner
      bool empty = true;
      for (std::size_t q : ring) {
        if (q == a || q == b || q == c) continue;
        if ((u[q] == u[a] && v[q] == v[a]) || (u[q] == u[b] && v[q] == v[b]) ||
            (u[q] == u[c] && v[q] == v[c]))
          continue;  // a repeated position (e.g. a slit) does not block
        if (orient(a, b, q) >= -eps && orient(b, c, q) >= -eps && orient(c, a, q) >= -eps) {
          empty = false;
          break;
        }
      }
      if (!empty) continue;
      out.push_back({face[a], face[b], face[c]});
      ring.erase(ring.begin() + static_cast<std::ptrdiff_t>(k));
      clipped = true;
    }
    if (!clipped) {
      // No ear: the polygon self-intersects or is degenerate. Fan the rest so that every face still
      // contributes surface; validity reports such faces through planarity/self-intersection.
      for (std::size_t k = 1; k + 1 < ring.size(); ++k)
        out.push_back({face[ring[0]], face[ring[k]], face[ring[k + 1]]});
      return;
    }
  }
  out.push_back({face[ring[0]], face[ring[1]], face[ring[2]]});
}

Kernel::Point_3 to_cgal(const Point3& p) { return {p.x, p.y, p.z}; }

void append(std::string& problems, const std::string& problem) {
  if (!problems.empty()) problems += "; ";
  problems += problem;
}

}  // namespace

std::vector<Triangle> triangulate(const PolygonMesh& mesh) {
  std::vector<Triangle> triangles;
  for (const auto& face : mesh.faces) triangulate_face(mesh, face, triangles);
  return triangles;
}

namespace {

using DistanceTriangle = Kernel::Triangle_3;
using DistancePrimitive =
    CGAL::AABB_triangle_primitive<Kernel, std::vector<DistanceTriangle>::const_iterator>;

// CGAL's AABB traits with two shortcuts in doubles, each taken only where CGAL's exact answer is certain,
// so the closest points, and so the distances, are the same bits as without them.
// - The closest-point step first bounds the triangle's distance by its bounding box. The tree prunes
//   by the boxes of its nodes, but a leaf projects each of its triangles onto the query point; a
//   triangle whose box is farther than the closest point so far cannot be closer. The test skips only
//   triangles farther by a margin (1e-6 relative, 1e-6 m) many orders above the rounding of the
//   projection, where CGAL's own exact comparison would keep the closest point so far too.
// - The node test (does the node's box come within that distance) is decided in doubles where the
//   answer is clear by a relative 1e-10; CGAL's filtered exact test decides the rest.
struct BoxFilteredTraits : CGAL::AABB_traits<Kernel, DistancePrimitive> {
  using Base = CGAL::AABB_traits<Kernel, DistancePrimitive>;
  class Closest_point {
   public:
    explicit Closest_point(const BoxFilteredTraits& traits) : base_(traits) {}
    Kernel::Point_3 operator()(const Kernel::Point_3& p, const DistancePrimitive& primitive,
                               const Kernel::Point_3& bound) const {
      const DistanceTriangle& t = primitive.datum();
      double box = 0.0;
      for (int axis = 0; axis < 3; ++axis) {
        const double a = t[0][axis], b = t[1][axis], c = t[2][axis];
        const double lo = std::min({a, b, c}), hi = std::max({a, b, c});
        const double outside = p[axis] < lo ? lo - p[axis] : p[axis] > hi ? p[axis] - hi : 0.0;
        box += outside * outside;
      }
      const double dx = bound.x() - p.x(), dy = bound.y() - p.y(), dz = bound.z() - p.z();
      const double best = dx * dx + dy * dy + dz * dz;
      if (box > best * (1.0 + 1e-6) + 1e-12) return bound;
      return base_(p, primitive, bound);
    }

   private:
    Base::Closest_point base_;
  };
  Closest_point closest_point_object() const { return Closest_point(*this); }

  // Whether a node's box comes within the distance of the closest point so far (SMALLER) or not
  // (LARGER): the box's squared distance and the bound's each carry a few roundings, far below 1e-10.
  class Compare_distance : public Base::Compare_distance {
   public:
    using Base::Compare_distance::operator();
    CGAL::Comparison_result operator()(const Kernel::Point_3& p, const CGAL::Bbox_3& box,
                                       const Kernel::Point_3& bound) const {
      const double dx = bound.x() - p.x(), dy = bound.y() - p.y(), dz = bound.z() - p.z();
      const double radius = dx * dx + dy * dy + dz * dz;
      double outside = 0.0;
      for (int axis = 0; axis < 3; ++axis) {
        const double d = p[axis] < box.min(axis) ? box.min(axis) - p[axis]
                         : p[axis] > box.max(axis) ? p[axis] - box.max(axis)
                                                   : 0.0;
        outside += d * d;
      }
      if (outside < radius * (1.0 - 1e-10)) return CGAL::SMALLER;
      if (outside > radius * (1.0 + 1e-10) && outside > 1e-200) return CGAL::LARGER;
      return Base::Compare_distance::operator()(p, box, bound);
    }
  };
  Compare_distance compare_distance_object() const { return Compare_distance(); }
};

// Whether the triangle's edge vectors have a cross product that is certainly not zero: a component
// larger than the rounding of its computation (a bound well above the few roundings involved). Most
// triangles pass; the rest go to CGAL's exact collinearity test, whose interval filter fails (and
// throws) on the triangles of collinear face vertices.
bool certainly_not_flat(const DistanceTriangle& t) {
  const double ux = t[1].x() - t[0].x(), uy = t[1].y() - t[0].y(), uz = t[1].z() - t[0].z();
  const double vx = t[2].x() - t[0].x(), vy = t[2].y() - t[0].y(), vz = t[2].z() - t[0].z();
  const auto clear = [](double p, double q) { return std::abs(p - q) > 1e-14 * (std::abs(p) + std::abs(q)); };
  return clear(uy * vz, uz * vy) || clear(uz * vx, ux * vz) || clear(ux * vy, uy * vx);
}

}  // namespace

std::vector<double> point_distances(const PolygonMesh& mesh, const std::vector<Point3>& points) {
  using Tri = DistanceTriangle;
  using Tree = CGAL::AABB_tree<BoxFilteredTraits>;
  if (points.empty()) throw ReconstructionError(ReconstructionStage::evaluation, "rmse needs at least one point");
  std::vector<Tri> triangles;
  for (const auto& t : triangulate(mesh)) {
    Tri tri(to_cgal(mesh.vertices[t[0]]), to_cgal(mesh.vertices[t[1]]), to_cgal(mesh.vertices[t[2]]));
    // AABB distance queries need real triangles.
    if (certainly_not_flat(tri) || !tri.is_degenerate()) triangles.push_back(tri);
  }
  if (triangles.empty())
    throw ReconstructionError(ReconstructionStage::evaluation, "rmse of a mesh without area (" +
                              std::to_string(mesh.faces.size()) + " faces)");
  Tree tree(triangles.begin(), triangles.end());
  std::vector<double> distances;
  distances.reserve(points.size());
  // The closest point of the previous point is the hint of the next: consecutive points of a scan are
  // neighbours, so each search starts with a tight bound (faster than CGAL's accelerated queries,
  // whose kd-tree of sample points costs more to build than it saves here).
  Kernel::Point_3 hint = triangles.front().vertex(0);
  for (const auto& p : points) {
    const Kernel::Point_3 q = to_cgal(p);
    hint = tree.closest_point(q, hint);
    distances.push_back(std::sqrt(CGAL::to_double(CGAL::squared_distance(q, hint))));
  }
  return distances;
}

double rmse(const PolygonMesh& mesh, const std::vector<Point3>& points) {
  double sum = 0.0;
  for (const double d : point_distances(mesh, points)) sum += d * d;
  return std::sqrt(sum / static_cast<double>(points.size()));
}

MeshValidity check_validity(const PolygonMesh& mesh, double planarity_tolerance) {
  MeshValidity result;
  result.faces = mesh.faces.size();
  result.vertices = mesh.vertices.size();
  {
    // val3dity's rules on the mesh as one solid with one exterior shell (as val3dity reads an OBJ).
    SolidGeometry solid;
    solid.vertices = mesh.vertices;
    solid.shells.emplace_back();
    for (const auto& face : mesh.faces) solid.shells[0].push_back({face});
    ValidityParams params;
    params.planarity_distance = planarity_tolerance;
    result.errors = validate_solid(solid, params);
    for (const ValidityError& e : result.errors) append(result.problem, e.text());
  }

  std::size_t bad_faces = 0;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& face = mesh.faces[f];
    std::vector<std::uint32_t> sorted = face;
    std::sort(sorted.begin(), sorted.end());
    if (!indices_valid(mesh, face) || std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) {
      if (bad_faces++ == 0)
        append(result.problem, "face " + std::to_string(f) +
                                   " has fewer than 3 vertices, a repeated vertex or an index out of range");
    }
  }
  if (bad_faces > 0) {
    append(result.problem, std::to_string(bad_faces) + " degenerate faces; topology not checked");
    return result;
  }
  if (mesh.faces.empty()) {
    append(result.problem, "no faces");
    return result;
  }

  // Topology. A directed edge key packs (from, to) into 64 bits.
  const auto key = [](std::uint32_t a, std::uint32_t b) { return (std::uint64_t{a} << 32) | b; };
  std::unordered_map<std::uint64_t, int> directed;
  for (const auto& face : mesh.faces)
    for (std::size_t i = 0; i < face.size(); ++i) ++directed[key(face[i], face[(i + 1) % face.size()])];
  std::size_t boundary = 0, overused = 0;
  for (const auto& [k, count] : directed) {
    const auto a = static_cast<std::uint32_t>(k >> 32), b = static_cast<std::uint32_t>(k);
    const auto opposite = directed.find(key(b, a));
    const int opposite_count = opposite == directed.end() ? 0 : opposite->second;
    if (count != 1 || opposite_count != 1) ++boundary;
    if (a < b && count + opposite_count > 2) ++overused;
    if (a > b && opposite_count == 0 && count > 2) ++overused;
  }
  // Vertex fans: the corners of the faces around a vertex, joined when consecutive around the
  // vertex (sharing an edge through it), must form one connected fan.
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> corners(mesh.vertices.size());
  for (const auto& face : mesh.faces)
    for (std::size_t i = 0; i < face.size(); ++i)
      corners[face[i]].emplace_back(face[(i + face.size() - 1) % face.size()], face[(i + 1) % face.size()]);
  std::size_t pinched = 0;
  for (const auto& around : corners)
    if (around.size() >= 2) pinched += detail::fans_around(around) > 1;
  result.closed = boundary == 0;
  result.manifold = overused == 0 && pinched == 0;
  if (!result.closed)
    append(result.problem,
           "not closed: " + std::to_string(boundary) + " directed edges without exactly one opposite");
  if (overused > 0)
    append(result.problem, "not manifold: " + std::to_string(overused) + " edges in more than two faces");
  if (pinched > 0)
    append(result.problem, "not manifold: " + std::to_string(pinched) + " vertices with more than one fan");

  // Volume by the divergence theorem over fan triangles (exact for any simple planar polygon, as the
  // signed contributions of a fan cancel outside it), relative to the bounding-box centre to keep
  // the products small.
  Box3 box;
  for (const auto& p : mesh.vertices) box.add(p);
  const Point3 centre{0.5 * (box.min.x + box.max.x), 0.5 * (box.min.y + box.max.y),
                      0.5 * (box.min.z + box.max.z)};
  double six_volume = 0.0;
  for (const auto& face : mesh.faces) {
    const Vec a = sub(mesh.vertices[face[0]], centre);
    for (std::size_t i = 1; i + 1 < face.size(); ++i)
      six_volume +=
          dot(a, cross(sub(mesh.vertices[face[i]], centre), sub(mesh.vertices[face[i + 1]], centre)));
  }
  result.volume = six_volume / 6.0;
  result.outward = result.volume > 0.0;
  if (result.closed && !result.outward)
    append(result.problem, "not outward: signed volume " + std::to_string(result.volume));

  // Planarity: distance of each vertex to the plane through the face centroid with Newell's normal.
  std::size_t degenerate = 0;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& face = mesh.faces[f];
    const Vec normal = detail::newell_normal(mesh.vertices, face);
    const double length = std::sqrt(dot(normal, normal));
    if (!(length > 0.0)) {
      ++degenerate;
      continue;
    }
    Point3 c{0, 0, 0};
    for (auto v : face) c = {c.x + mesh.vertices[v].x, c.y + mesh.vertices[v].y, c.z + mesh.vertices[v].z};
    c = {c.x / face.size(), c.y / face.size(), c.z / face.size()};
    for (auto v : face)
      result.max_planarity_error =
          std::max(result.max_planarity_error, std::fabs(dot(sub(mesh.vertices[v], c), normal)) / length);
  }
  result.planar = degenerate == 0 && result.max_planarity_error <= planarity_tolerance;
  if (degenerate > 0) append(result.problem, std::to_string(degenerate) + " faces without area");
  if (result.max_planarity_error > planarity_tolerance) {
    std::ostringstream s;
    s << "not planar: a vertex " << result.max_planarity_error << " m from its face's plane (tolerance "
      << planarity_tolerance << " m)";
    append(result.problem, s.str());
  }

  // Self-intersection. When val3dity's rules found nothing, their test has run on each polygon's
  // constrained triangulation (exact predicates) and decides; a 306 "polygons intersect" decides too.
  // Otherwise (they stopped at an earlier error) the ear-clipped surface is tested; PMP's test wants a
  // valid triangle mesh, which closed + manifold guarantees here. (Ear clipping can fall back to a fan
  // on a polygon with collinear runs, and a fan may overlap itself where the polygon does not.)
  const bool solid_intersects = std::any_of(result.errors.begin(), result.errors.end(), [](const ValidityError& e) {
    return e.code == 306 && e.info.find("polygons intersect") != std::string::npos;
  });
  if (result.errors.empty() || solid_intersects) {
    result.self_intersecting_checked = true;
    result.self_intersects = solid_intersects;
    if (solid_intersects) append(result.problem, "self-intersecting");
  } else if (result.closed && result.manifold) {
    using Mesh = CGAL::Surface_mesh<Kernel::Point_3>;
    std::vector<Kernel::Point_3> points;
    points.reserve(mesh.vertices.size());
    for (const auto& p : mesh.vertices) points.push_back(to_cgal(p));
    std::vector<std::vector<std::size_t>> triangles;
    for (const auto& t : triangulate(mesh)) triangles.push_back({t[0], t[1], t[2]});
    namespace PMP = CGAL::Polygon_mesh_processing;
    if (PMP::is_polygon_soup_a_polygon_mesh(triangles)) {
      Mesh surface;
      PMP::polygon_soup_to_polygon_mesh(points, triangles, surface);
      result.self_intersecting_checked = true;
      result.self_intersects = PMP::does_self_intersect(surface);
      if (result.self_intersects) append(result.problem, "self-intersecting");
    } else {
      append(result.problem,
             "triangulated surface is not a valid triangle mesh; self-intersection not checked");
    }
  }
  return result;
}

}  // namespace city3d
