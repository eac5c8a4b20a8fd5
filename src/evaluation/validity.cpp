// Validity of solids under ISO 19107 as val3dity 2.6 checks it (the validator 3DBAG reports with): the
// same error numbers, the same default tolerances and the same order (rings and polygons, then shells,
// then the solid). Rings are tested in the 2D projection on their polygon's least-squares plane with
// exact predicates; polygons are triangulated by a constrained Delaunay triangulation of that
// projection (as val3dity does) for the normals test and the shell self-intersection test.
#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/intersection.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <unordered_map>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/evaluation.hpp"
#include "core/mesh_faces.hpp"
#include "core/vec.hpp"
#include "evaluation/validity_shared.hpp"

namespace city3d {
namespace detail {

// Merges vertices closer than `tolerance` (val3dity's snap_tol) into the first of them, in index
// order, through a hash grid of cells the size of the tolerance.
std::vector<std::uint32_t> snap_vertices(const std::vector<Point3>& vertices, double tolerance) {
  std::vector<std::uint32_t> to(vertices.size());
  std::iota(to.begin(), to.end(), 0u);
  if (!(tolerance > 0.0)) return to;
  using Cell = std::array<long long, 3>;
  std::map<Cell, std::vector<std::uint32_t>> grid;
  const auto cell_of = [&](const Point3& p) {
    return Cell{static_cast<long long>(std::floor(p.x / tolerance)), static_cast<long long>(std::floor(p.y / tolerance)),
                static_cast<long long>(std::floor(p.z / tolerance))};
  };
  for (std::uint32_t i = 0; i < vertices.size(); ++i) {
    const Cell c = cell_of(vertices[i]);
    bool merged = false;
    for (long long dx = -1; dx <= 1 && !merged; ++dx)
      for (long long dy = -1; dy <= 1 && !merged; ++dy)
        for (long long dz = -1; dz <= 1 && !merged; ++dz) {
          const auto it = grid.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == grid.end()) continue;
          for (std::uint32_t j : it->second)
            if (norm(sub(vertices[i], vertices[j])) < tolerance) {
              to[i] = j;
              merged = true;
              break;
            }
        }
    if (!merged) grid[c].push_back(i);
  }
  return to;
}

}  // namespace detail

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using P2 = Kernel::Point_2;
using P3 = Kernel::Point_3;
using Ring = std::vector<std::uint32_t>;
using Triangle = std::array<std::uint32_t, 3>;


using namespace detail;  // the helpers of validity_shared.hpp and core/vec.hpp

// The least-squares plane of a polygon's vertices: centroid, unit normal (oriented like the Newell
// normal of the exterior ring) and two in-plane axes.
struct Frame {
  Point3 centroid;
  Vec normal{0, 0, 1}, u{1, 0, 0}, v{0, 1, 0};
  double max_distance = 0.0;
  bool ok = false;
};

Frame fit_plane(const std::vector<Point3>& vertices, const SolidPolygon& polygon) {
  Frame f;
  std::vector<std::uint32_t> all;
  for (const Ring& r : polygon) all.insert(all.end(), r.begin(), r.end());
  if (all.size() < 3) return f;
  Point3 c{0, 0, 0};
  for (auto i : all) c = {c.x + vertices[i].x, c.y + vertices[i].y, c.z + vertices[i].z};
  c = {c.x / all.size(), c.y / all.size(), c.z / all.size()};
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (auto i : all) {
    const Eigen::Vector3d d(vertices[i].x - c.x, vertices[i].y - c.y, vertices[i].z - c.z);
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
  const Eigen::Vector3d n = solver.eigenvectors().col(0);  // smallest eigenvalue
  f.normal = {n.x(), n.y(), n.z()};
  const Vec newell = detail::newell_normal(vertices, polygon.front());
  if (dot(newell, f.normal) < 0) f.normal = {-f.normal.x, -f.normal.y, -f.normal.z};
  // u, v: a right-handed basis with the normal, so the exterior ring comes out counter-clockwise.
  const Vec helper = std::fabs(f.normal.z) < 0.9 ? Vec{0, 0, 1} : Vec{1, 0, 0};
  f.u = cross(helper, f.normal);
  const double lu = norm(f.u);
  f.u = {f.u.x / lu, f.u.y / lu, f.u.z / lu};
  f.v = cross(f.normal, f.u);
  f.centroid = c;
  for (auto i : all) f.max_distance = std::max(f.max_distance, std::fabs(dot(sub(vertices[i], c), f.normal)));
  f.ok = std::isfinite(f.max_distance);
  return f;
}

P2 project(const Frame& f, const Point3& p) {
  const Vec d = sub(p, f.centroid);
  return {dot(d, f.u), dot(d, f.v)};
}

bool on_segment(const P2& a, const P2& b, const P2& c) {  // c on the closed segment ab, given collinear
  return std::min(a.x(), b.x()) <= c.x() && c.x() <= std::max(a.x(), b.x()) && std::min(a.y(), b.y()) <= c.y() &&
         c.y() <= std::max(a.y(), b.y());
}

bool segments_touch(const P2& p, const P2& q, const P2& r, const P2& s) {
  const auto o1 = CGAL::orientation(p, q, r), o2 = CGAL::orientation(p, q, s);
  const auto o3 = CGAL::orientation(r, s, p), o4 = CGAL::orientation(r, s, q);
  if (o1 != o2 && o3 != o4 && o1 != CGAL::COLLINEAR && o2 != CGAL::COLLINEAR && o3 != CGAL::COLLINEAR &&
      o4 != CGAL::COLLINEAR)
    return true;
  return (o1 == CGAL::COLLINEAR && on_segment(p, q, r)) || (o2 == CGAL::COLLINEAR && on_segment(p, q, s)) ||
         (o3 == CGAL::COLLINEAR && on_segment(r, s, p)) || (o4 == CGAL::COLLINEAR && on_segment(r, s, q));
}

// A ring is simple in 2D: no repeated point, no spike (two consecutive edges folding back over each
// other), no two non-consecutive edges touching.
bool ring_is_simple(const std::vector<P2>& r) {
  const std::size_t n = r.size();
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j)
      if (r[i] == r[j]) return false;
  for (std::size_t i = 0; i < n; ++i) {
    const P2 &a = r[(i + n - 1) % n], &b = r[i], &c = r[(i + 1) % n];
    if (CGAL::orientation(a, b, c) == CGAL::COLLINEAR && (a - b) * (c - b) > 0) return false;  // a spike
  }
  if (n == 3 && CGAL::orientation(r[0], r[1], r[2]) == CGAL::COLLINEAR) return false;  // collapsed to a line
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // consecutive through the closing edge
      if (segments_touch(r[i], r[(i + 1) % n], r[j], r[(j + 1) % n])) return false;
    }
  return true;
}

double signed_area(const std::vector<P2>& r) {
  double a = 0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    const P2 &p = r[i], &q = r[(i + 1) % r.size()];
    a += p.x() * q.y() - q.x() * p.y();
  }
  return a / 2;
}

// Point strictly inside / on the boundary / outside a simple ring: +1 / 0 / -1.
int locate(const std::vector<P2>& ring, const P2& p) {
  bool inside = false;
  for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) {
    const P2 &a = ring[i], &b = ring[j];
    if (CGAL::orientation(a, b, p) == CGAL::COLLINEAR && on_segment(a, b, p)) return 0;
    if ((a.y() > p.y()) != (b.y() > p.y())) {
      const double x = a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
      if (p.x() < x) inside = !inside;
    }
  }
  return inside ? 1 : -1;
}

// How two simple rings meet: number of distinct touching points, or -1 when they cross or overlap
// along more than a point.
int ring_contacts(const std::vector<P2>& r, const std::vector<P2>& s) {
  std::set<std::pair<double, double>> touches;
  for (std::size_t i = 0; i < r.size(); ++i)
    for (std::size_t j = 0; j < s.size(); ++j) {
      const P2 &a = r[i], &b = r[(i + 1) % r.size()], &c = s[j], &d = s[(j + 1) % s.size()];
      if (!segments_touch(a, b, c, d)) continue;
      const auto o1 = CGAL::orientation(a, b, c), o2 = CGAL::orientation(a, b, d);
      if (o1 == CGAL::COLLINEAR && o2 == CGAL::COLLINEAR) {
        // Collinear: a shared point is fine only when the overlap is a single point.
        int shared = 0;
        P2 at = a;
        for (const P2& p : {a, b})
          if (on_segment(c, d, p)) ++shared, at = p;
        for (const P2& p : {c, d})
          if (on_segment(a, b, p) && p != a && p != b) ++shared, at = p;
        if (shared > 1) return -1;
        touches.insert({at.x(), at.y()});
        continue;
      }
      // A touching point must be a vertex of one of the two edges; otherwise they cross.
      const P2* at = nullptr;
      for (const P2* p : {&a, &b})
        if (CGAL::orientation(c, d, *p) == CGAL::COLLINEAR && on_segment(c, d, *p)) at = p;
      for (const P2* p : {&c, &d})
        if (CGAL::orientation(a, b, *p) == CGAL::COLLINEAR && on_segment(a, b, *p)) at = p;
      if (!at) return -1;
      touches.insert({at->x(), at->y()});
    }
  // Touching points where the rings cross each other (one ring passes from inside to outside the
  // other) are crossings: test the midpoints of r's edges against s on both sides of each contact.
  bool in = false, out = false;
  for (std::size_t i = 0; i < r.size(); ++i) {
    const P2 m = CGAL::midpoint(r[i], r[(i + 1) % r.size()]);
    const int l = locate(s, m);
    in = in || l > 0;
    out = out || l < 0;
  }
  if (in && out) return -1;
  return static_cast<int>(touches.size());
}

using CdtVb = CGAL::Triangulation_vertex_base_with_info_2<std::uint32_t, Kernel>;
// Each face's info: its nesting depth (triangulate_polygon).
using CdtFb = CGAL::Triangulation_face_base_with_info_2<int, Kernel,
                                                        CGAL::Constrained_triangulation_face_base_2<Kernel>>;
using CdtTds = CGAL::Triangulation_data_structure_2<CdtVb, CdtFb>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<Kernel, CdtTds, CGAL::Exact_predicates_tag>;

// Triangles of a valid polygon (simple rings, holes inside): a constrained Delaunay triangulation of
// its projection, faces inside an odd number of rings kept, each oriented like the exterior ring.
std::vector<Triangle> triangulate_polygon(const std::vector<Point3>& vertices, const SolidPolygon& polygon,
                                          const Frame& frame) {
  Cdt cdt;
  for (const Ring& ring : polygon) {
    std::vector<Cdt::Vertex_handle> handles;
    for (std::uint32_t i : ring) {
      auto h = cdt.insert(project(frame, vertices[i]));
      h->info() = i;
      handles.push_back(h);
    }
    for (std::size_t k = 0; k < handles.size(); ++k)
      if (handles[k] != handles[(k + 1) % handles.size()]) cdt.insert_constraint(handles[k], handles[(k + 1) % handles.size()]);
  }
  // Nesting depth by flooding from the infinite face across edges; constrained edges add one. The
  // depths live in the faces (-1: not reached yet); `reached` lists every face once.
  for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->info() = -1;
  std::vector<Cdt::Face_handle> reached{cdt.infinite_face()};
  cdt.infinite_face()->info() = 0;
  for (std::size_t k = 0; k < reached.size(); ++k) {
    const Cdt::Face_handle f = reached[k];
    for (int e = 0; e < 3; ++e) {
      const Cdt::Face_handle g = f->neighbor(e);
      if (g->info() >= 0) continue;
      g->info() = f->info() + (cdt.is_constrained({f, e}) ? 1 : 0);
      reached.push_back(g);
    }
  }
  // Depth by plain flooding over-counts where constrained regions are reached the long way round;
  // relax until stable (a few rounds for a polygon with holes). The relaxed depths are the fewest
  // constrained edges crossed from the infinite face, whatever the order of the faces.
  for (bool changed = true; changed;) {
    changed = false;
    for (const Cdt::Face_handle& f : reached)
      for (int e = 0; e < 3; ++e) {
        const int there = f->neighbor(e)->info();
        if (there < 0) continue;
        const int via = there + (cdt.is_constrained({f, e}) ? 1 : 0);
        if (via < f->info()) f->info() = via, changed = true;
      }
  }
  std::vector<Triangle> out;
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    if (f->info() % 2 == 0) continue;
    out.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});  // CDT faces are CCW
  }
  return out;
}

Vec triangle_normal(const std::vector<Point3>& v, const Triangle& t) {
  return cross(sub(v[t[1]], v[t[0]]), sub(v[t[2]], v[t[0]]));
}

using Mesh = CGAL::Surface_mesh<P3>;

}  // namespace

namespace detail {

bool triangles_form_a_surface(const std::vector<std::array<std::uint32_t, 3>>& triangles) {
  // No triangle with a vertex twice, and no directed edge twice (then no edge has more than two
  // triangles either: one in each direction).
  std::vector<std::uint64_t> directed;
  directed.reserve(3 * triangles.size());
  for (const Triangle& t : triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) return false;
    for (std::size_t k = 0; k < 3; ++k) directed.push_back(std::uint64_t{t[k]} << 32 | t[(k + 1) % 3]);
  }
  std::sort(directed.begin(), directed.end());
  if (std::adjacent_find(directed.begin(), directed.end()) != directed.end()) return false;
  // One umbrella per vertex: its corners (vertex, previous, next) joined where one's next is
  // another's previous (the edge they share) form one part.
  std::vector<std::array<std::uint32_t, 3>> corners;
  corners.reserve(3 * triangles.size());
  for (const Triangle& t : triangles)
    for (std::size_t k = 0; k < 3; ++k) corners.push_back({t[k], t[(k + 2) % 3], t[(k + 1) % 3]});
  std::sort(corners.begin(), corners.end());  // by vertex, then by previous: unique (previous, vertex) edges
  UnionFind fans;
  for (std::size_t i = 0; i < corners.size();) {
    std::size_t j = i;
    while (j < corners.size() && corners[j][0] == corners[i][0]) ++j;
    fans.reset(j - i);
    for (std::size_t c = i; c < j; ++c) {
      const auto after = std::lower_bound(corners.begin() + static_cast<std::ptrdiff_t>(i),
                                          corners.begin() + static_cast<std::ptrdiff_t>(j),
                                          std::array<std::uint32_t, 3>{corners[c][0], corners[c][2], 0});
      if (after != corners.begin() + static_cast<std::ptrdiff_t>(j) && (*after)[1] == corners[c][2])
        fans.join(c - i, static_cast<std::size_t>(after - corners.begin()) - i);
    }
    std::size_t parts = 0;
    for (std::size_t c = 0; c < j - i; ++c) parts += fans.find(c) == c;
    if (parts > 1) return false;
    i = j;
  }
  return true;
}

}  // namespace detail

namespace {

// A triangle soup as a CGAL mesh, or false when it is not a valid polygon mesh (the conditions of
// CGAL's is_polygon_soup_a_polygon_mesh, checked by triangles_form_a_surface on sorted vectors).
bool to_surface_mesh(const std::vector<Point3>& vertices, const std::vector<Triangle>& triangles, Mesh& mesh) {
  if (!detail::triangles_form_a_surface(triangles)) return false;
  // The soup's points in the order the triangles first use them (the mesh's vertex order).
  constexpr std::size_t kUnused = std::numeric_limits<std::size_t>::max();
  std::vector<P3> points;
  std::vector<std::size_t> local(vertices.size(), kUnused);
  std::vector<std::array<std::size_t, 3>> faces;
  faces.reserve(triangles.size());
  for (const Triangle& t : triangles) {
    std::array<std::size_t, 3>& f = faces.emplace_back();
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t i = t[k];
      if (local[i] == kUnused) {
        local[i] = points.size();
        points.push_back({vertices[i].x, vertices[i].y, vertices[i].z});
      }
      f[k] = local[i];
    }
  }
  CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(points, faces, mesh);
  return true;
}

double signed_volume(const std::vector<Point3>& v, const std::vector<Triangle>& triangles) {
  if (triangles.empty()) return 0.0;
  const Point3& o = v[triangles.front()[0]];
  double six = 0.0;
  for (const Triangle& t : triangles) six += dot(sub(v[t[0]], o), cross(sub(v[t[1]], o), sub(v[t[2]], o)));
  return six / 6.0;
}

struct ShellResult {
  bool valid = false;
  std::vector<Triangle> triangles;
};

// Shell rules 301-307 for one shell whose polygons are valid.
ShellResult check_shell(const std::vector<Point3>& v, const std::vector<SolidPolygon>& shell,
                        const std::vector<std::vector<Triangle>>& polygon_triangles, int shell_index, bool inner,
                        std::vector<ValidityError>& errors) {
  ShellResult result;
  const std::size_t before = errors.size();
  const auto report = [&](int code, int face, const std::string& info) { errors.push_back({code, shell_index, face, info}); };
  if (shell.size() < 4) report(301, -1, std::to_string(shell.size()) + " polygons");

  // Directed edges of every ring with their polygon, sorted by edge; stable, so that an edge's polygons
  // stay in the order of the polygons. Each edge's entries are one run of `directed`.
  struct DirectedEdge {
    std::uint32_t a, b;
    std::size_t face;
  };
  std::vector<DirectedEdge> directed;
  for (std::size_t f = 0; f < shell.size(); ++f)
    for (const Ring& r : shell[f])
      for (std::size_t k = 0; k < r.size(); ++k) directed.push_back({r[k], r[(k + 1) % r.size()], f});
  const auto edge_less = [](const DirectedEdge& x, const DirectedEdge& y) {
    return x.a != y.a ? x.a < y.a : x.b < y.b;
  };
  std::stable_sort(directed.begin(), directed.end(), edge_less);
  std::vector<std::size_t> run_start;  // where each edge's run begins, then the end
  for (std::size_t i = 0; i < directed.size(); ++i)
    if (i == 0 || edge_less(directed[i - 1], directed[i])) run_start.push_back(i);
  run_start.push_back(directed.size());
  // The run of edge (a, b): [first, last), empty when no polygon has it.
  const auto run_of = [&](std::uint32_t a, std::uint32_t b) {
    const DirectedEdge key{a, b, 0};
    const auto range = std::equal_range(directed.begin(), directed.end(), key, edge_less);
    return std::make_pair(static_cast<std::size_t>(range.first - directed.begin()),
                          static_cast<std::size_t>(range.second - directed.begin()));
  };
  std::size_t boundary = 0, overused = 0, same_direction = 0;
  int first_boundary_face = -1, first_overused_face = -1, first_flipped_face = -1;
  UnionFind parts(shell.size());  // connected components over shared edges (either direction)
  for (std::size_t g = 0; g + 1 < run_start.size(); ++g) {
    const std::size_t first = run_start[g], last = run_start[g + 1];
    const DirectedEdge& e = directed[first];
    const auto [opposite_first, opposite_last] = run_of(e.b, e.a);
    for (std::size_t i = first + 1; i < last; ++i) parts.join(directed[i].face, e.face);
    if (opposite_first != opposite_last) parts.join(e.face, directed[opposite_first].face);
    const std::size_t here = last - first, there = opposite_last - opposite_first;
    if (e.a > e.b && there > 0) continue;  // each undirected edge once
    if (here + there == 1) {
      ++boundary;
      if (first_boundary_face < 0) first_boundary_face = static_cast<int>(e.face);
    } else if (here + there > 2) {
      ++overused;
      if (first_overused_face < 0) first_overused_face = static_cast<int>(e.face);
    } else if (here == 2 || there == 2) {
      ++same_direction;
      if (first_flipped_face < 0)
        first_flipped_face =
            static_cast<int>(here == 2 ? directed[first + 1].face : directed[opposite_first + 1].face);
    }
  }
  if (boundary) report(302, first_boundary_face, std::to_string(boundary) + " edges used by one polygon only");
  if (overused)
    report(304, first_overused_face, std::to_string(overused) + " edges used by more than two polygons");
  std::size_t components = 0;
  for (std::size_t f = 0; f < shell.size(); ++f) components += parts.find(f) == f;
  if (components > 1) report(305, -1, std::to_string(components) + " parts joined by no edge");

  // Vertex manifoldness: the polygons around a vertex must form one umbrella (connected through
  // edges at that vertex). Each corner is (vertex, previous, next), sorted by vertex, stable.
  if (!boundary && !overused) {
    std::vector<std::array<std::uint32_t, 3>> corners;
    for (const SolidPolygon& p : shell)
      for (const Ring& r : p)
        for (std::size_t k = 0; k < r.size(); ++k)
          corners.push_back({r[k], r[(k + r.size() - 1) % r.size()], r[(k + 1) % r.size()]});
    std::stable_sort(corners.begin(), corners.end(),
                     [](const auto& x, const auto& y) { return x[0] < y[0]; });
    std::size_t pinched = 0;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> around;
    for (std::size_t i = 0; i < corners.size();) {
      around.clear();
      std::size_t j = i;
      for (; j < corners.size() && corners[j][0] == corners[i][0]; ++j)
        around.push_back({corners[j][1], corners[j][2]});
      pinched += detail::fans_around(around) > 1;
      i = j;
    }
    if (pinched) report(303, -1, std::to_string(pinched) + " vertices whose polygons form more than one umbrella");
  }
  if (same_direction) report(307, first_flipped_face, std::to_string(same_direction) + " edges used twice in the same direction");
  if (errors.size() != before) return result;

  std::vector<Triangle> triangles;
  for (const auto& t : polygon_triangles) triangles.insert(triangles.end(), t.begin(), t.end());
  Mesh mesh;
  if (!to_surface_mesh(v, triangles, mesh)) {
    report(306, -1, "the triangulated polygons do not form a surface");
    return result;
  }
  if (CGAL::Polygon_mesh_processing::does_self_intersect(mesh)) {
    report(306, -1, "polygons intersect");
    return result;
  }
  const double volume = signed_volume(v, triangles);
  if (inner ? volume > 0 : volume < 0)
    errors.push_back({405, shell_index, -1,
                      std::string(inner ? "interior shell oriented outward" : "exterior shell oriented inward") +
                          " (volume " + format(volume, 3) + " m3)"});
  if (errors.size() != before) return result;
  result.valid = true;
  result.triangles = std::move(triangles);
  return result;
}

}  // namespace

void ValidityParams::validate() const {
  std::string problems;
  const auto add = [&](const std::string& p) { problems += (problems.empty() ? "" : "; ") + p; };
  if (!(snap_tolerance >= 0.0) || !std::isfinite(snap_tolerance)) add("snap_tolerance must be >= 0 (metres)");
  if (!(planarity_distance > 0.0) || !std::isfinite(planarity_distance)) add("planarity_distance must be > 0 (metres)");
  if (!(planarity_normals > 0.0 && planarity_normals <= 180.0)) add("planarity_normals must be in (0, 180] degrees");
  if (!problems.empty()) throw ConfigError("validity: " + problems);
}

const char* validity_error_name(int code) {
  switch (code) {
    case 101: return "TOO_FEW_POINTS";
    case 102: return "CONSECUTIVE_POINTS_SAME";
    case 103: return "RING_NOT_CLOSED";
    case 104: return "RING_SELF_INTERSECTION";
    case 201: return "INTERSECTION_RINGS";
    case 202: return "DUPLICATED_RINGS";
    case 203: return "NON_PLANAR_POLYGON_DISTANCE_PLANE";
    case 204: return "NON_PLANAR_POLYGON_NORMALS_DEVIATION";
    case 205: return "POLYGON_INTERIOR_DISCONNECTED";
    case 206: return "INNER_RING_OUTSIDE";
    case 207: return "INNER_RINGS_NESTED";
    case 208: return "ORIENTATION_RINGS_SAME";
    case 301: return "TOO_FEW_POLYGONS";
    case 302: return "SHELL_NOT_CLOSED";
    case 303: return "NON_MANIFOLD_VERTEX";
    case 304: return "NON_MANIFOLD_EDGE";
    case 305: return "MULTIPLE_CONNECTED_COMPONENTS";
    case 306: return "SHELL_SELF_INTERSECTION";
    case 307: return "POLYGON_WRONG_ORIENTATION";
    case 309: return "VERTICES_NOT_USED";
    case 401: return "INTERSECTION_SHELLS";
    case 402: return "DUPLICATED_SHELLS";
    case 403: return "INNER_SHELL_OUTSIDE";
    case 405: return "WRONG_ORIENTATION_SHELL";
  }
  return "UNKNOWN_ERROR";
}

std::string ValidityError::text() const {
  std::string s = std::to_string(code) + " " + validity_error_name(code);
  std::string where;
  if (shell >= 0) where = "shell " + std::to_string(shell);
  if (face >= 0) where += (where.empty() ? "" : ", ") + std::string("face ") + std::to_string(face);
  if (!where.empty() || !info.empty())
    s += " (" + where + (where.empty() || info.empty() ? "" : ": ") + info + ")";
  return s;
}

std::string validity_codes(const std::vector<ValidityError>& errors) {
  std::set<int> codes;
  for (const ValidityError& e : errors) codes.insert(e.code);
  std::string s;
  for (int c : codes) s += (s.empty() ? "" : ",") + std::to_string(c);
  return s;
}

std::vector<ValidityError> validate_solid(const SolidGeometry& solid, const ValidityParams& params) {
  // The snap map depends on the vertices alone; validate_snapped_solid reports an index out of range (101).
  return detail::validate_snapped_solid(solid.vertices, solid.shells,
                                        snap_vertices(solid.vertices, params.snap_tolerance), params);
}

std::vector<ValidityError> detail::validate_snapped_solid(
    const std::vector<Point3>& v, const std::vector<std::vector<SolidPolygon>>& solid_shells,
    const std::vector<std::uint32_t>& to, const ValidityParams& params) {
  std::vector<ValidityError> errors;
  for (const auto& shell : solid_shells)
    for (const auto& polygon : shell)
      for (const auto& ring : polygon)
        for (std::uint32_t i : ring)
          if (i >= v.size()) {
            errors.push_back({101, -1, -1, "vertex index " + std::to_string(i) + " of " + std::to_string(v.size())});
            return errors;
          }

  // 309: every listed vertex must be used.
  std::vector<bool> used(v.size(), false);
  for (const auto& shell : solid_shells)
    for (const auto& polygon : shell)
      for (const auto& ring : polygon)
        for (std::uint32_t i : ring) used[i] = true;
  const std::size_t unused = static_cast<std::size_t>(std::count(used.begin(), used.end(), false));

  // Snapped, then rings and polygons.
  std::vector<std::vector<SolidPolygon>> shells = solid_shells;
  for (auto& shell : shells)
    for (auto& polygon : shell)
      for (auto& ring : polygon)
        for (std::uint32_t& i : ring) i = to[i];

  const double max_angle = params.planarity_normals * kPi / 180.0;
  std::vector<std::vector<std::vector<Triangle>>> triangles(shells.size());
  bool polygons_valid = true;
  for (std::size_t s = 0; s < shells.size(); ++s) {
    triangles[s].resize(shells[s].size());
    for (std::size_t f = 0; f < shells[s].size(); ++f) {
      const SolidPolygon& polygon = shells[s][f];
      const auto report = [&](int code, const std::string& info) {
        errors.push_back({code, static_cast<int>(s), static_cast<int>(f), info});
        polygons_valid = false;
      };
      bool rings_ok = !polygon.empty();
      if (polygon.empty()) report(101, "polygon without rings");
      for (std::size_t r = 0; r < polygon.size(); ++r) {
        const Ring& ring = polygon[r];
        const std::string which = r == 0 ? "exterior ring" : "interior ring " + std::to_string(r - 1);
        if (ring.size() < 3) {
          report(101, which + ": " + std::to_string(ring.size()) + " points");
          rings_ok = false;
          continue;
        }
        for (std::size_t k = 0; k < ring.size(); ++k)
          if (ring[k] == ring[(k + 1) % ring.size()]) {
            report(102, which + ": points " + std::to_string(k) + " and " + std::to_string((k + 1) % ring.size()));
            rings_ok = false;
            break;
          }
      }
      if (!rings_ok) continue;
      const Frame frame = fit_plane(v, polygon);
      std::vector<std::vector<P2>> rings2;
      for (const Ring& ring : polygon) {
        rings2.emplace_back();
        for (std::uint32_t i : ring) rings2.back().push_back(project(frame, v[i]));
      }
      bool simple = true;
      for (std::size_t r = 0; r < rings2.size(); ++r)
        if (!ring_is_simple(rings2[r])) {
          report(104, r == 0 ? "exterior ring" : "interior ring " + std::to_string(r - 1));
          simple = false;
        }
      if (!simple) continue;
      if (!frame.ok || frame.max_distance > params.planarity_distance) {
        report(203, format(frame.max_distance, 4) + " m from the fitted plane");
        continue;
      }
      // Interior rings: 201 (crossing), 202 (duplicated), 205 (touching into a cycle), 206 (outside),
      // 207 (nested), 208 (same orientation as the exterior).
      bool rings_valid = true;
      if (rings2.size() > 1) {
        const bool outer_ccw = signed_area(rings2[0]) > 0;
        std::vector<std::size_t> up(rings2.size());
        std::iota(up.begin(), up.end(), std::size_t{0});
        const auto root = [&up](std::size_t i) {
          while (up[i] != i) i = up[i] = up[up[i]];
          return i;
        };
        bool cycle = false;
        for (std::size_t a = 0; a < rings2.size(); ++a)
          for (std::size_t b = a + 1; b < rings2.size(); ++b) {
            std::vector<std::uint32_t> sa = polygon[a], sb = polygon[b];
            std::sort(sa.begin(), sa.end());
            std::sort(sb.begin(), sb.end());
            if (sa == sb) {
              report(202, "rings " + std::to_string(a) + " and " + std::to_string(b));
              rings_valid = false;
              continue;
            }
            const int contacts = ring_contacts(rings2[a], rings2[b]);
            if (contacts < 0) {
              report(201, "rings " + std::to_string(a) + " and " + std::to_string(b));
              rings_valid = false;
            } else if (contacts > 0) {
              if (contacts > 1 || root(a) == root(b)) cycle = true;
              up[root(a)] = root(b);
            }
          }
        if (rings_valid && cycle) {
          report(205, "rings touch so that the interior is split");
          rings_valid = false;
        }
        if (rings_valid) {
          // A ring vertex not on the other ring's boundary tells inside from outside.
          const auto probe = [&](const std::vector<P2>& ring, const std::vector<P2>& other) {
            for (const P2& p : ring) {
              const int l = locate(other, p);
              if (l != 0) return l;
            }
            return 0;
          };
          for (std::size_t h = 1; h < rings2.size(); ++h) {
            if (probe(rings2[h], rings2[0]) < 0) {
              report(206, "interior ring " + std::to_string(h - 1));
              rings_valid = false;
            }
            for (std::size_t k = 1; k < rings2.size(); ++k)
              if (k != h && probe(rings2[h], rings2[k]) > 0) {
                report(207, "interior ring " + std::to_string(h - 1) + " inside interior ring " + std::to_string(k - 1));
                rings_valid = false;
              }
            if ((signed_area(rings2[h]) > 0) == outer_ccw) {
              report(208, "interior ring " + std::to_string(h - 1));
              rings_valid = false;
            }
          }
        }
      }
      if (!rings_valid) continue;
      // 204: triangles of the polygon whose normals deviate by more than the tolerance. Every pair is
      // compared (val3dity compares against one of them), so a polygon passing here passes there.
      triangles[s][f] = triangulate_polygon(v, polygon, frame);
      std::vector<Vec> normals;
      for (const Triangle& t : triangles[s][f]) {
        const Vec n = triangle_normal(v, t);
        const double l = norm(n);
        if (l > 0) normals.push_back({n.x / l, n.y / l, n.z / l});
      }
      // First the test of every normal against the first one: when none is more than half the
      // tolerance (less a margin far above rounding) away from it, no two are more than the tolerance
      // apart, and the pairs need not be compared: a floor of many vertices has thousands of triangles.
      const double half = 0.5 * max_angle - 1e-9;
      const bool near_first = std::all_of(normals.begin(), normals.end(), [&](const Vec& n) {
        return std::acos(std::clamp(dot(normals.front(), n), -1.0, 1.0)) <= half;
      });
      double worst = 0.0;
      if (!near_first)
        for (std::size_t a = 0; a < normals.size(); ++a)
          for (std::size_t b = a + 1; b < normals.size(); ++b)
            worst = std::max(worst, std::acos(std::clamp(dot(normals[a], normals[b]), -1.0, 1.0)));
      if (worst > max_angle) report(204, format(worst * 180.0 / kPi, 1) + " degrees between two triangles");
    }
  }
  if (unused) errors.push_back({309, -1, -1, std::to_string(unused) + " vertices used by no polygon"});
  if (!polygons_valid) return errors;

  // Shells.
  std::vector<ShellResult> shell_results;
  bool shells_valid = true;
  for (std::size_t s = 0; s < shells.size(); ++s) {
    shell_results.push_back(check_shell(v, shells[s], triangles[s], static_cast<int>(s), s > 0, errors));
    shells_valid = shells_valid && shell_results.back().valid;
  }
  if (!shells_valid || shells.size() < 2) return errors;

  // The solid: interior shells against the exterior and each other.
  std::vector<Mesh> meshes(shells.size());
  for (std::size_t s = 0; s < shells.size(); ++s) to_surface_mesh(v, shell_results[s].triangles, meshes[s]);
  for (std::size_t a = 0; a < shells.size(); ++a)
    for (std::size_t b = a + 1; b < shells.size(); ++b) {
      std::set<std::uint32_t> va, vb;
      for (const auto& p : shells[a])
        for (const auto& r : p) va.insert(r.begin(), r.end());
      for (const auto& p : shells[b])
        for (const auto& r : p) vb.insert(r.begin(), r.end());
      if (va == vb) {
        errors.push_back({402, -1, -1, "shells " + std::to_string(a) + " and " + std::to_string(b)});
        continue;
      }
      if (CGAL::Polygon_mesh_processing::do_intersect(meshes[a], meshes[b])) {
        errors.push_back({401, -1, -1, "shells " + std::to_string(a) + " and " + std::to_string(b)});
        continue;
      }
      // Disjoint surfaces: one inside the other, or apart.
      const P3 pb = meshes[b].point(*meshes[b].vertices().begin());
      const P3 pa = meshes[a].point(*meshes[a].vertices().begin());
      const bool b_in_a = CGAL::Side_of_triangle_mesh<Mesh, Kernel>(meshes[a])(pb) == CGAL::ON_BOUNDED_SIDE;
      const bool a_in_b = CGAL::Side_of_triangle_mesh<Mesh, Kernel>(meshes[b])(pa) == CGAL::ON_BOUNDED_SIDE;
      if (a == 0 && !b_in_a) errors.push_back({403, static_cast<int>(b), -1, "interior shell outside the exterior shell"});
      if (a > 0 && (b_in_a || a_in_b))
        errors.push_back({401, -1, -1, "interior shells " + std::to_string(a) + " and " + std::to_string(b) + " nested"});
    }
  return errors;
}

std::vector<PolygonMesh> mesh_parts(const PolygonMesh& mesh) {
  const std::vector<std::size_t> part_of = detail::edge_connected_parts(mesh.faces);
  std::vector<PolygonMesh> parts;
  std::vector<std::map<std::uint32_t, std::uint32_t>> local;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    if (part_of[f] == parts.size()) {  // the part's first face
      parts.emplace_back();
      local.emplace_back();
    }
    PolygonMesh& part = parts[part_of[f]];
    std::vector<std::uint32_t> face;
    for (std::uint32_t i : mesh.faces[f]) {
      if (i >= mesh.vertices.size()) {
        face.push_back(i);  // left for the validator to report
        continue;
      }
      const auto [vit, vfresh] = local[part_of[f]].emplace(i, static_cast<std::uint32_t>(part.vertices.size()));
      if (vfresh) part.vertices.push_back(mesh.vertices[i]);
      face.push_back(vit->second);
    }
    part.faces.push_back(std::move(face));
  }
  return parts;
}

std::vector<ValidityError> validate_model(const PolygonMesh& mesh, const ValidityParams& params) {
  std::vector<ValidityError> errors;
  const std::vector<PolygonMesh> parts = mesh_parts(mesh);
  if (parts.empty()) errors.push_back({301, 0, -1, "no polygons"});
  for (std::size_t p = 0; p < parts.size(); ++p) {
    SolidGeometry solid;
    solid.vertices = parts[p].vertices;
    solid.shells.emplace_back();
    for (const auto& face : parts[p].faces) solid.shells[0].push_back({face});
    for (ValidityError e : validate_solid(solid, params)) {
      e.shell = static_cast<int>(p);
      errors.push_back(std::move(e));
    }
  }
  return errors;
}

}  // namespace city3d
