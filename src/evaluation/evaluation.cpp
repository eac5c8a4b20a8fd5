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
#include <limits>
#include <numeric>
#include <optional>
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
using detail::norm;
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

// The triangle nearest to a point, found by columns, when it is certain. The triangles are listed
// per column of a grid in xy (every column their projection may overlap); a query measures the
// triangles of the columns around the point, ring by ring, until the next ring lies farther than the
// nearest triangle found, each distance in doubles (Ericson's closest point on a triangle). The
// answer is given only when every other triangle is farther by far more than the rounding of those
// distances (and no sliver, whose distance rounds worse, is within reach): the CGAL projection onto it is
// then the closest point the AABB tree's search would give, the same bits. Ties (a point nearest to an
// edge or a corner two triangles share) are left to the tree. On a building's model a point meets a
// few triangles of its own column (its roof, the floor, walls beside it) where the tree tests about a
// hundred nodes and projects a dozen triangles.
class ColumnIndex {
 public:
  // `queries`: how many points will be asked about (a column per four of them, 64 to 2,048).
  ColumnIndex(const std::vector<DistanceTriangle>& triangles, std::size_t queries) {
    double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
    for (const DistanceTriangle& t : triangles) {
      Facet tri;
      for (int v = 0; v < 3; ++v) {
        tri.v[v] = {t[v].x(), t[v].y(), t[v].z()};
        x0 = std::min(x0, tri.v[v].x), x1 = std::max(x1, tri.v[v].x);
        y0 = std::min(y0, tri.v[v].y), y1 = std::max(y1, tri.v[v].y);
      }
      const Vec ab = sub(tri.v[1], tri.v[0]), ac = sub(tri.v[2], tri.v[0]), bc = sub(tri.v[2], tri.v[1]);
      const double longest = std::max({dot(ab, ab), dot(ac, ac), dot(bc, bc)});
      const double doubled_area = norm(cross(ab, ac));
      tri.sliver = !(doubled_area * doubled_area > kSliver * longest * longest);
      if (!tri.sliver) {
        const Vec n = cross(ab, ac);
        tri.normal = {n.x / doubled_area, n.y / doubled_area, n.z / doubled_area};
      } else {
        // Its longest edge first: every point of it is within the third corner's distance of that edge.
        const int e = longest == dot(ab, ab) ? 0 : longest == dot(bc, bc) ? 1 : 2;
        std::rotate(tri.v, tri.v + e, tri.v + 3);
        tri.width = segment_distance(tri.v[2], tri.v[0], tri.v[1]);
      }
      facets_.push_back(tri);
    }
    // Square columns over the model's extent, none narrower than half a metre: building them costs
    // what a few queries cost, and more columns hold fewer triangles each.
    const double wanted = std::clamp(static_cast<double>(queries) / 4.0, 64.0, 2048.0);
    const double w = x1 - x0, h = y1 - y0;
    size_ = std::max(0.5, std::sqrt(std::max(w * h, w * w / 64 + h * h / 64) / wanted));
    x0_ = x0, y0_ = y0;
    nx_ = static_cast<long>(w / size_) + 1, ny_ = static_cast<long>(h / size_) + 1;
    // (column, triangle) pairs, then the triangles sorted by column (counting), each column's in order.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    for (std::uint32_t k = 0; k < facets_.size(); ++k) {
      const Facet& t = facets_[k];
      const auto [i0, i1] = std::minmax({column_x(t.v[0].x), column_x(t.v[1].x), column_x(t.v[2].x)});
      const auto [j0, j1] = std::minmax({column_y(t.v[0].y), column_y(t.v[1].y), column_y(t.v[2].y)});
      for (long j = j0; j <= j1; ++j)
        for (long i = i0; i <= i1; ++i)
          if (may_overlap(t, i, j)) pairs.emplace_back(static_cast<std::uint32_t>(j * nx_ + i), k);
    }
    first_.assign(static_cast<std::size_t>(nx_ * ny_) + 1, 0);
    for (const auto& [c, k] : pairs) ++first_[c + 1];
    for (std::size_t c = 1; c < first_.size(); ++c) first_[c] += first_[c - 1];
    items_.resize(pairs.size());
    std::vector<std::uint32_t> next(first_.begin(), first_.end() - 1);
    for (const auto& [c, k] : pairs) items_[next[c]++] = k;
    seen_.assign(facets_.size(), 0);
  }

  // The index of the triangle nearest to p when it is certain, or -1.
  long nearest(const Point3& p) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return -1;
    if (++query_ == 0) std::fill(seen_.begin(), seen_.end(), 0), query_ = 1;
    const long ci = std::clamp(column_x(p.x), 0L, nx_ - 1), cj = std::clamp(column_y(p.y), 0L, ny_ - 1);
    const long rings = std::max({ci, nx_ - 1 - ci, cj, ny_ - 1 - cj});
    // Squared distances: the nearest, the next nearest, the nearest a sliver may be (its box), and
    // the reach (the nearest's distance and the tie margin) within which every triangle is measured.
    double best = std::numeric_limits<double>::infinity(), second = best, sliver = best, reach = best;
    double reach_distance = best;
    long winner = -1;
    // How far p is inside its own column: ring r >= 1 lies that far and r - 1 columns more away.
    const double border = std::max(0.0, std::min({p.x - (x0_ + static_cast<double>(ci) * size_),
                                                  x0_ + static_cast<double>(ci + 1) * size_ - p.x,
                                                  p.y - (y0_ + static_cast<double>(cj) * size_),
                                                  y0_ + static_cast<double>(cj + 1) * size_ - p.y}) -
                                            1e-9 * size_);
    for (long r = 0; r <= rings; ++r) {
      if (r > 0) {
        const double away = border + static_cast<double>(r - 1) * size_;
        if (away * away > reach) break;
      }
      bool any = false;  // a column of this ring within reach
      for (long j = cj - r; j <= cj + r; ++j) {
        if (j < 0 || j >= ny_) continue;
        const bool edge_row = j == cj - r || j == cj + r;
        for (long i = ci - r; i <= ci + r; i += edge_row ? 1 : 2 * r) {
          if (i >= 0 && i < nx_ && squared_column_distance(p, i, j) <= reach) {
            any = true;
            const auto c = static_cast<std::size_t>(j * nx_ + i);
            for (std::uint32_t n = first_[c]; n < first_[c + 1]; ++n) {
              const std::uint32_t k = items_[n];
              if (seen_[k] == query_) continue;
              seen_[k] = query_;
              const Facet& t = facets_[k];
              if (t.sliver) {
                const double low =
                    std::max(0.0, segment_distance(p, t.v[0], t.v[1]) - t.width - kPlaneMargin);
                sliver = std::min(sliver, low * low);
                continue;
              }
              // Its plane is no farther than the triangle.
              if (std::abs(dot(t.normal, sub(p, t.v[0]))) > reach_distance + kPlaneMargin) continue;
              const double d = squared_distance(t, p);
              if (d < best) {
                second = best, best = d, winner = k;
                reach_distance = std::sqrt(best) + kTie;
                reach = reach_distance * reach_distance;
              } else if (d < second) {
                second = d;
              }
            }
          }
          if (r == 0) break;
        }
      }
      if (!any && r > 0) break;
    }
    if (winner < 0 || !(second > reach) || !(sliver > reach)) return -1;
    return winner;
  }

 private:
  // Triangles whose doubled area is below this share of their longest edge squared are slivers: their
  // normal and Ericson's distance round too coarsely to be trusted, so a sliver is only bounded (by its
  // longest edge and its width), and one within reach leaves the point to the tree.
  static constexpr double kSliver = 1e-8;
  // Distances that differ by less than this are a tie: far above the rounding of the distances of the
  // other triangles (a ten-thousandth of their longest edge or more across), about 1e-10 m here.
  static constexpr double kTie = 1e-6;
  // The rounding of a distance to a plane of such a triangle, and far more.
  static constexpr double kPlaneMargin = 1e-7;

  struct Facet {
    Point3 v[3];  // a sliver's longest edge is v[0] v[1]
    bool sliver = false;
    Vec normal{0.0, 0.0, 0.0};  // the unit normal of its plane (not for a sliver)
    double width = 0.0;         // a sliver's: how far its third corner is from its longest edge
  };

  // The distance from p to segment ab.
  static double segment_distance(const Point3& p, const Point3& a, const Point3& b) {
    const Vec ab = sub(b, a), ap = sub(p, a);
    const double length2 = dot(ab, ab);
    const double t = length2 > 0.0 ? std::clamp(dot(ab, ap) / length2, 0.0, 1.0) : 0.0;
    return norm({ap.x - t * ab.x, ap.y - t * ab.y, ap.z - t * ab.z});
  }

  long column_x(double x) const { return static_cast<long>(std::floor((x - x0_) / size_)); }
  long column_y(double y) const { return static_cast<long>(std::floor((y - y0_) / size_)); }

  // The squared distance in xy from p to column (i, j), a lower bound of the 3D distance to what it
  // holds; the column is taken a hair wider than it is, so the bound never exceeds the truth.
  double squared_column_distance(const Point3& p, long i, long j) const {
    const double margin = 1e-9 * size_;
    const double xa = x0_ + static_cast<double>(i) * size_ - margin, xb = xa + size_ + 2 * margin;
    const double ya = y0_ + static_cast<double>(j) * size_ - margin, yb = ya + size_ + 2 * margin;
    const double dx = p.x < xa ? xa - p.x : p.x > xb ? p.x - xb : 0.0;
    const double dy = p.y < ya ? ya - p.y : p.y > yb ? p.y - yb : 0.0;
    return dx * dx + dy * dy;
  }

  // Whether the triangle's projection may overlap column (i, j): no edge of the projection separates
  // them (the separating-axis test, with a margin, so an overlap is never missed).
  bool may_overlap(const Facet& t, long i, long j) const {
    const double margin = 1e-9 * size_;
    const double xa = x0_ + static_cast<double>(i) * size_ - margin, xb = xa + size_ + 2 * margin;
    const double ya = y0_ + static_cast<double>(j) * size_ - margin, yb = ya + size_ + 2 * margin;
    for (int e = 0; e < 3; ++e) {
      const Point3& a = t.v[e];
      const Point3& b = t.v[(e + 1) % 3];
      const double nx = a.y - b.y, ny = b.x - a.x;  // a normal of the edge in xy
      if (nx == 0.0 && ny == 0.0) continue;
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (const Point3& v : t.v)
        lo = std::min(lo, nx * v.x + ny * v.y), hi = std::max(hi, nx * v.x + ny * v.y);
      double box_lo = std::numeric_limits<double>::infinity(), box_hi = -box_lo;
      for (const double x : {xa, xb})
        for (const double y : {ya, yb})
          box_lo = std::min(box_lo, nx * x + ny * y), box_hi = std::max(box_hi, nx * x + ny * y);
      const double slack = 1e-9 * (std::abs(nx) + std::abs(ny)) * (size_ + std::abs(xa) + std::abs(ya));
      if (box_hi < lo - slack || box_lo > hi + slack) return false;
    }
    return true;
  }

  // The squared distance from p to the triangle (Ericson, Real-Time Collision Detection, 5.1.5).
  static double squared_distance(const Facet& t, const Point3& p) {
    const Point3 &a = t.v[0], &b = t.v[1], &c = t.v[2];
    const Vec ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
    const auto length2 = [](const Vec& v) { return dot(v, v); };
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return length2(ap);
    const Vec bp = sub(p, b);
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return length2(bp);
    const double vc = d1 * d4 - d3 * d2;
    const auto off = [&](const Point3& o, const Vec& u, double s, const Vec& v, double w) {
      return length2({p.x - (o.x + s * u.x + w * v.x), p.y - (o.y + s * u.y + w * v.y),
                      p.z - (o.z + s * u.z + w * v.z)});
    };
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return off(a, ab, d1 / (d1 - d3), ac, 0.0);
    const Vec cp = sub(p, c);
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return length2(cp);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return off(a, ab, 0.0, ac, d2 / (d2 - d6));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0)
      return off(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)), ab, 0.0);
    const double denominator = 1.0 / (va + vb + vc);
    return off(a, ab, vb * denominator, ac, vc * denominator);
  }

  std::vector<Facet> facets_;
  double x0_ = 0.0, y0_ = 0.0, size_ = 1.0;
  long nx_ = 1, ny_ = 1;
  std::vector<std::uint32_t> first_, items_;  // the triangles of column c: items_[first_[c] .. first_[c + 1])
  std::vector<std::uint32_t> seen_;           // the query that last measured each triangle
  std::uint32_t query_ = 0;
};

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
  std::optional<Tree> tree;  // built at its first query
  std::vector<double> distances;
  distances.reserve(points.size());
  // Where the column index is certain of the nearest triangle, the closest point is CGAL's projection
  // onto it, as the tree's search would find it; the rest (ties, slivers) search the tree. The closest
  // point of the previous point is the hint of the next: consecutive points of a scan are neighbours,
  // so each tree search starts with a tight bound (faster than CGAL's accelerated queries, whose
  // kd-tree of sample points costs more to build than it saves here).
  Kernel::Point_3 hint = triangles.front().vertex(0);
  ColumnIndex columns(triangles, points.size());
  const Kernel::Construct_projected_point_3 project;
  const Kernel::Compare_distance_3 compare;
  for (const auto& p : points) {
    const Kernel::Point_3 q = to_cgal(p);
    const long nearest = columns.nearest(p);
    if (nearest >= 0) {
      // The tree's search starts from the hint and keeps it against a projection that is farther
      // (by a rounding: the hint lies on the model, a closest point of the point before).
      const Kernel::Point_3 projected = project(triangles[static_cast<std::size_t>(nearest)], q);
      if (compare(q, projected, hint) != CGAL::LARGER) hint = projected;
    } else {
      if (!tree) tree.emplace(triangles.begin(), triangles.end());
      hint = tree->closest_point(q, hint);
    }
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
