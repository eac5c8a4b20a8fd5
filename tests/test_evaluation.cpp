// Tests of model evaluation: RMSE against known distances, validity of good and deliberately broken
// meshes, triangulation of non-convex faces.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/evaluation.hpp"
#include "city3d/model_io.hpp"
#include "city3d/surface_support.hpp"

namespace city3d {
namespace {

/// An axis-aligned box [0, sx] x [0, sy] x [0, sz], faces counter-clockwise seen from outside.
PolygonMesh box(double sx, double sy, double sz) {
  PolygonMesh m;
  m.vertices = {{0, 0, 0},  {sx, 0, 0},  {sx, sy, 0},  {0, sy, 0},
                {0, 0, sz}, {sx, 0, sz}, {sx, sy, sz}, {0, sy, sz}};
  m.faces = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  return m;
}

/// Points on the surface of box(sx, sy, sz), pushed `offset` metres outward along the face normal.
std::vector<Point3> box_surface_points(double sx, double sy, double sz, double offset, int per_face) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> t(0.05, 0.95);  // away from edges, where offsets are exact
  std::vector<Point3> points;
  for (int i = 0; i < per_face; ++i) {
    const double a = t(rng), b = t(rng);
    points.push_back({a * sx, b * sy, -offset});
    points.push_back({a * sx, b * sy, sz + offset});
    points.push_back({a * sx, -offset, b * sz});
    points.push_back({a * sx, sy + offset, b * sz});
    points.push_back({-offset, a * sy, b * sz});
    points.push_back({sx + offset, a * sy, b * sz});
  }
  return points;
}

double triangle_area(const PolygonMesh& m, const std::array<std::uint32_t, 3>& t) {
  const auto& a = m.vertices[t[0]];
  const auto& b = m.vertices[t[1]];
  const auto& c = m.vertices[t[2]];
  const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z, vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
  const double cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
  return 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
}

TEST(Evaluation, rmse_of_points_on_a_box_surface_is_zero) {
  EXPECT_NEAR(rmse(box(10, 8, 6), box_surface_points(10, 8, 6, 0.0, 200)), 0.0, 1e-12);
}

TEST(Evaluation, rmse_of_points_offset_outward_by_a_decimetre_is_a_decimetre) {
  EXPECT_NEAR(rmse(box(10, 8, 6), box_surface_points(10, 8, 6, 0.1, 200)), 0.1, 1e-9);
}

TEST(Evaluation, rmse_mixes_distances_as_a_root_mean_square) {
  // One point on the top, one 0.3 m above it: sqrt((0 + 0.09) / 2).
  EXPECT_NEAR(rmse(box(10, 8, 6), {{5, 4, 6}, {5, 4, 6.3}}), std::sqrt(0.045), 1e-12);
}

TEST(Evaluation, rmse_rejects_an_empty_point_set) {
  EXPECT_THROW(rmse(box(1, 1, 1), {}), ReconstructionError);
}

TEST(Evaluation, box_is_a_valid_solid_with_exact_volume) {
  const auto v = check_validity(box(10, 8, 6));
  EXPECT_TRUE(v.closed);
  EXPECT_TRUE(v.manifold);
  EXPECT_TRUE(v.outward);
  EXPECT_TRUE(v.planar);
  EXPECT_TRUE(v.self_intersecting_checked);
  EXPECT_FALSE(v.self_intersects);
  EXPECT_TRUE(v.valid()) << v.problem;
  EXPECT_TRUE(v.problem.empty()) << v.problem;
  EXPECT_NEAR(v.volume, 480.0, 1e-9);
  EXPECT_EQ(v.faces, 6u);
  EXPECT_EQ(v.vertices, 8u);
  EXPECT_NEAR(v.max_planarity_error, 0.0, 1e-12);
}

TEST(Evaluation, box_far_from_the_origin_keeps_its_volume) {
  auto m = box(10, 8, 6);
  for (auto& p : m.vertices) p = {p.x + 85000.0, p.y + 447000.0, p.z};
  EXPECT_NEAR(check_validity(m).volume, 480.0, 1e-6);
}

TEST(Evaluation, inverted_box_is_not_outward) {
  auto m = box(2, 3, 4);
  for (auto& f : m.faces) std::reverse(f.begin(), f.end());
  const auto v = check_validity(m);
  EXPECT_TRUE(v.closed);
  EXPECT_TRUE(v.manifold);
  EXPECT_FALSE(v.outward);
  EXPECT_NEAR(v.volume, -24.0, 1e-9);
  EXPECT_FALSE(v.valid());
  EXPECT_NE(v.problem.find("outward"), std::string::npos) << v.problem;
}

TEST(Evaluation, box_with_a_missing_face_is_not_closed) {
  auto m = box(2, 3, 4);
  m.faces.pop_back();
  const auto v = check_validity(m);
  EXPECT_FALSE(v.closed);
  EXPECT_FALSE(v.self_intersecting_checked);
  EXPECT_FALSE(v.valid());
  EXPECT_NE(v.problem.find("not closed: 4"), std::string::npos) << v.problem;
}

TEST(Evaluation, three_faces_on_one_edge_are_not_manifold) {
  // The box plus a fin: a square hanging from the top edge 4-5, so edge 4-5 has three faces.
  auto m = box(2, 2, 2);
  m.vertices.push_back({2, -2, 2});
  m.vertices.push_back({0, -2, 2});
  m.faces.push_back({5, 4, 9, 8});
  const auto v = check_validity(m);
  EXPECT_FALSE(v.manifold);
  EXPECT_FALSE(v.closed);
  EXPECT_NE(v.problem.find("more than two faces"), std::string::npos) << v.problem;
}

TEST(Evaluation, two_boxes_touching_at_one_vertex_are_not_manifold) {
  // Closed (every edge has its opposite), but vertex 6 of the first box is shared by the second:
  // its faces form two fans.
  auto m = box(1, 1, 1);
  const auto second = box(1, 1, 1);
  for (const auto& p : second.vertices) m.vertices.push_back({p.x + 1, p.y + 1, p.z + 1});
  for (auto f : second.faces) {
    for (auto& i : f) i = i == 0 ? 6 : i + 8;  // second box's vertex 0 is the first box's vertex 6
    m.faces.push_back(f);
  }
  const auto v = check_validity(m);
  EXPECT_TRUE(v.closed);
  EXPECT_FALSE(v.manifold);
  EXPECT_NE(v.problem.find("more than one fan"), std::string::npos) << v.problem;
}

TEST(Evaluation, non_planar_quad_is_reported_with_its_deviation) {
  auto m = box(2, 2, 2);
  m.vertices[6].z =
      2.2;  // lifts one top corner: the top is no longer planar (the walls through it stay planar)
  const auto v = check_validity(m, 0.01);
  EXPECT_TRUE(v.closed);
  EXPECT_FALSE(v.planar);
  // Top face (0,0,2) (2,0,2) (2,2,2.2) (0,2,2): Newell normal (-0.05, -0.05, 1) (cross product of
  // the diagonals), plane through the centroid (1, 1, 2.05); every vertex is 0.05 / |n| from it.
  EXPECT_NEAR(v.max_planarity_error, 0.05 / std::sqrt(1.0 + 2 * 0.0025), 1e-9);
  EXPECT_TRUE(check_validity(m, 0.1).planar);
}

TEST(Evaluation, self_intersecting_closed_mesh_is_detected) {
  // Two boxes that overlap in space, as one closed manifold mesh of two shells.
  auto m = box(2, 2, 2);
  const auto second = box(2, 2, 2);
  for (const auto& p : second.vertices) m.vertices.push_back({p.x + 1, p.y + 1, p.z + 1});
  for (auto f : second.faces) {
    for (auto& i : f) i += 8;
    m.faces.push_back(f);
  }
  const auto v = check_validity(m);
  EXPECT_TRUE(v.closed);
  EXPECT_TRUE(v.manifold);
  EXPECT_TRUE(v.self_intersecting_checked);
  EXPECT_TRUE(v.self_intersects);
  EXPECT_FALSE(v.valid());
}

/// An L-shaped prism: the footprint (0,0) (4,0) (4,2) (2,2) (2,4) (0,4) extruded to height 3. The roof
/// is a non-convex hexagon.
PolygonMesh l_prism() {
  PolygonMesh m;
  const double xy[6][2] = {{0, 0}, {4, 0}, {4, 2}, {2, 2}, {2, 4}, {0, 4}};
  for (const auto& p : xy) m.vertices.push_back({p[0], p[1], 0});
  for (const auto& p : xy) m.vertices.push_back({p[0], p[1], 3});
  m.faces.push_back({5, 4, 3, 2, 1, 0});    // floor, seen from below
  m.faces.push_back({6, 7, 8, 9, 10, 11});  // roof
  for (std::uint32_t i = 0; i < 6; ++i) m.faces.push_back({i, (i + 1) % 6, (i + 1) % 6 + 6, i + 6});
  return m;
}

TEST(Evaluation, l_shaped_roof_is_triangulated_without_covering_the_notch) {
  const auto m = l_prism();
  PolygonMesh roof_only = m;
  roof_only.faces = {m.faces[1]};
  const auto triangles = triangulate(roof_only);
  ASSERT_EQ(triangles.size(), 4u);
  double area = 0.0;
  for (const auto& t : triangles) {
    area += triangle_area(roof_only, t);
    // Same orientation as the face: normal up.
    const auto& a = m.vertices[t[0]];
    const auto& b = m.vertices[t[1]];
    const auto& c = m.vertices[t[2]];
    EXPECT_GT((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x), 0.0);
  }
  EXPECT_NEAR(area, 12.0, 1e-12);
  // A point above the notch (3, 3) is nearest to the roof's notch edges, 1 m away in plan: a
  // triangulation covering the notch would give 0.5 instead.
  EXPECT_NEAR(rmse(roof_only, {{3, 3, 3.5}}), std::sqrt(1.0 + 0.25), 1e-12);
  // Inside the notch at mid height: the roof edge is sqrt(1 + 1.5^2) away, the wall x = 2 only 1 m.
  EXPECT_NEAR(rmse(roof_only, {{3, 3, 1.5}}), std::sqrt(1.0 + 2.25), 1e-12);
  EXPECT_NEAR(rmse(m, {{3, 3, 1.5}}), 1.0, 1e-12);
}

/// The distance from p to triangle abc, the plain way: to the plane where p projects inside the
/// triangle, else to the nearest of its three edges.
double triangle_distance(const Point3& p, const Point3& a, const Point3& b, const Point3& c) {
  const auto sub = [](const Point3& u, const Point3& v) { return Point3{u.x - v.x, u.y - v.y, u.z - v.z}; };
  const auto dot = [](const Point3& u, const Point3& v) { return u.x * v.x + u.y * v.y + u.z * v.z; };
  const auto cross = [](const Point3& u, const Point3& v) {
    return Point3{u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
  };
  const auto segment = [&](const Point3& s, const Point3& e) {
    const Point3 d = sub(e, s);
    const double t = std::clamp(dot(sub(p, s), d) / dot(d, d), 0.0, 1.0);
    const Point3 q{s.x + t * d.x, s.y + t * d.y, s.z + t * d.z};
    return std::sqrt(dot(sub(p, q), sub(p, q)));
  };
  const Point3 n = cross(sub(b, a), sub(c, a));
  const bool inside = dot(cross(sub(b, a), sub(p, a)), n) >= 0 && dot(cross(sub(c, b), sub(p, b)), n) >= 0 &&
                      dot(cross(sub(a, c), sub(p, c)), n) >= 0;
  if (inside) return std::abs(dot(sub(p, a), n)) / std::sqrt(dot(n, n));
  return std::min({segment(a, b), segment(b, c), segment(c, a)});
}

/// point_distances(m, points) against the nearest of every triangle of m, the plain way.
void expect_distances_of_every_triangle(const PolygonMesh& m, const std::vector<Point3>& points) {
  const auto triangles = triangulate(m);
  const std::vector<double> d = point_distances(m, points);
  ASSERT_EQ(d.size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    double best = 1e300;
    for (const auto& t : triangles)
      best =
          std::min(best, triangle_distance(points[i], m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]));
    ASSERT_NEAR(d[i], best, 1e-9) << "point " << i << " (" << points[i].x << ", " << points[i].y << ", "
                                  << points[i].z << ")";
  }
}

// The tree search skips a triangle whose bounding box is farther than the closest point so far: the
// distances must be those of trying every triangle, for points on, near, inside and far from a tilted
// L-shaped prism (boxes that are not flat), in an order that makes each search's start a poor one.
TEST(Evaluation, point_distances_are_those_of_trying_every_triangle) {
  PolygonMesh m = l_prism();
  const double a = 0.4, b = 0.3;  // rotations about z and about x
  for (Point3& v : m.vertices) {
    const Point3 r{std::cos(a) * v.x - std::sin(a) * v.y, std::sin(a) * v.x + std::cos(a) * v.y, v.z};
    v = {r.x + 100.0, std::cos(b) * r.y - std::sin(b) * r.z + 200.0, std::sin(b) * r.y + std::cos(b) * r.z};
  }
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-3.0, 7.0), pick(0.0, 1.0);
  std::vector<Point3> points;
  const auto triangles = triangulate(m);
  for (int i = 0; i < 3000; ++i) {
    if (i % 3 == 0) {  // on a triangle, or a hair off it
      const auto& t = triangles[rng() % triangles.size()];
      double s = pick(rng), w = pick(rng);
      if (s + w > 1) s = 1 - s, w = 1 - w;
      const Point3 &p0 = m.vertices[t[0]], &p1 = m.vertices[t[1]], &p2 = m.vertices[t[2]];
      const double off = (i % 2) * 1e-7;
      points.push_back({p0.x + s * (p1.x - p0.x) + w * (p2.x - p0.x) + off,
                        p0.y + s * (p1.y - p0.y) + w * (p2.y - p0.y),
                        p0.z + s * (p1.z - p0.z) + w * (p2.z - p0.z)});
    } else {
      const double scale = i % 3 == 1 ? 1.0 : 8.0;  // around it, or far away
      points.push_back({100.0 + scale * u(rng), 200.0 + scale * u(rng), scale * u(rng)});
    }
  }
  expect_distances_of_every_triangle(m, points);
}

// A prism over a 48-cornered star with a sloped roof (its floor and roof are fans of long triangles over
// many columns of the search grid) and two slivers: the distances of points inside, on its corners,
// edges and triangles (ties between triangles), under the floor, beside the walls and far outside the
// grid must be those of trying every triangle.
TEST(Evaluation, point_distances_find_the_nearest_of_many_triangles_wherever_the_point_is) {
  PolygonMesh m;
  const int corners = 48;
  const auto roof_z = [](double x, double y) { return 6.0 + 0.15 * x - 0.05 * y; };
  for (int k = 0; k < corners; ++k) {
    const double angle = 2.0 * M_PI * k / corners;
    const double r = k % 2 == 0 ? 12.0 : 7.0;  // every other corner in: a star
    const double x = r * std::cos(angle) + 300.0, y = r * std::sin(angle) - 150.0;
    m.vertices.push_back({x, y, 0.0});
    m.vertices.push_back({x, y, roof_z(x - 300.0, y + 150.0)});
  }
  std::vector<std::uint32_t> floor, roof;
  for (int k = 0; k < corners; ++k) {
    const auto a = static_cast<std::uint32_t>(2 * k), b = static_cast<std::uint32_t>(2 * ((k + 1) % corners));
    floor.insert(floor.begin(), a);
    roof.push_back(a + 1);
    m.faces.push_back({a, b, b + 1, a + 1});
  }
  m.faces.push_back(floor);
  m.faces.push_back(roof);
  // Two slivers, 3 m long and 0.2 mm wide, one flat above the roof, one steep beside a wall.
  const auto add = [&m](const Point3& a, const Point3& b, const Point3& c) {
    const auto n = static_cast<std::uint32_t>(m.vertices.size());
    m.vertices.insert(m.vertices.end(), {a, b, c});
    m.faces.push_back({n, n + 1, n + 2});
  };
  add({300.0, -150.0, 9.0}, {303.0, -150.0, 9.0}, {301.5, -150.0 + 2e-4, 9.0});
  add({312.5, -151.0, 1.0}, {312.5, -151.0 + 2e-4, 2.5}, {312.5, -151.0, 4.0});
  const auto triangles = triangulate(m);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0), pick(0.0, 1.0);
  std::vector<Point3> points;
  for (int i = 0; i < 6000; ++i) {
    const int kind = i % 6;
    if (kind == 0) {  // on a corner, an edge or a triangle (a sliver too), or a hair above one
      const auto& t = triangles[rng() % triangles.size()];
      const Point3 &p0 = m.vertices[t[0]], &p1 = m.vertices[t[1]], &p2 = m.vertices[t[2]];
      const double s = (i / 6) % 3 == 0 ? 0.0 : pick(rng) / 2, w = (i / 6) % 3 == 2 ? pick(rng) / 2 : 0.0;
      points.push_back({p0.x + s * (p1.x - p0.x) + w * (p2.x - p0.x),
                        p0.y + s * (p1.y - p0.y) + w * (p2.y - p0.y),
                        p0.z + s * (p1.z - p0.z) + w * (p2.z - p0.z) + (i % 4) * 1e-8});
    } else if (kind == 1) {  // near the roof, inside or beyond the walls
      const double x = 14.0 * u(rng), y = 14.0 * u(rng);
      points.push_back({x + 300.0, y - 150.0, roof_z(x, y) + 0.3 * u(rng)});
    } else if (kind == 2) {  // inside, at any height, and under the floor
      points.push_back({300.0 + 10.0 * u(rng), -150.0 + 10.0 * u(rng), 4.0 + 6.0 * u(rng)});
    } else if (kind == 3) {  // far outside the grid
      points.push_back({300.0 + 200.0 * u(rng), -150.0 + 200.0 * u(rng), 50.0 * u(rng)});
    } else {  // the same point again, or one a hair from the one before (the search starts there)
      const Point3 before = points.back();
      points.push_back(kind == 4 ? before : Point3{before.x + 1e-9, before.y, before.z - 1e-9});
    }
  }
  expect_distances_of_every_triangle(m, points);
}

TEST(Evaluation, l_shaped_prism_is_a_valid_solid) {
  const auto v = check_validity(l_prism());
  EXPECT_TRUE(v.valid()) << v.problem;
  EXPECT_NEAR(v.volume, 36.0, 1e-9);
  EXPECT_EQ(triangulate(l_prism()).size(), 4u + 4u + 6u * 2u);
}

TEST(Evaluation, face_with_an_index_out_of_range_is_reported_not_crashed_on) {
  auto m = box(1, 1, 1);
  m.faces[0][0] = 99;
  const auto v = check_validity(m);
  EXPECT_FALSE(v.closed);
  EXPECT_FALSE(v.valid());
  EXPECT_NE(v.problem.find("out of range"), std::string::npos) << v.problem;
}

}  // namespace
}  // namespace city3d

// A Delft LoD2.2 model (b31bbff5e) whose faces have runs of collinear vertices: ear clipping finds no
// ear in one of them and fans it, and the fan overlapped itself. The solid is valid under val3dity's
// rules (each polygon triangulated by constraints, exact predicates), and the check says so.
TEST(Evaluation, collinear_runs_are_not_taken_for_a_self_intersection) {
  const city3d::BuildingModel model =
      city3d::read_obj_model(std::string(CITY3D_TEST_DATA) + "/model/delft_b31bbff5e_collinear_runs.obj");
  const city3d::MeshValidity v = city3d::check_validity(model.mesh);
  EXPECT_TRUE(v.errors.empty()) << v.problem;
  EXPECT_TRUE(v.self_intersecting_checked);
  EXPECT_FALSE(v.self_intersects) << v.problem;
  EXPECT_TRUE(v.valid()) << v.problem;
}

// ---------------------------------------------------------------------------------------------
// Surface support (issue 23): the model measured against its points the other way.
namespace city3d {
namespace {

TEST(SurfaceSupport, local_top_is_the_highest_point_within_the_radius_as_brute_force_finds_it) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> xy(-20.0, 20.0), z(0.0, 15.0);
  std::vector<Point3> points(3000);
  for (auto& p : points) p = {xy(rng), xy(rng), z(rng)};
  const LocalTop top(points, 1.5);
  std::uniform_real_distribution<double> q(-25.0, 25.0);
  for (int k = 0; k < 2000; ++k) {
    const double x = q(rng), y = q(rng);
    double best = -1.0;
    for (const auto& p : points)
      if ((p.x - x) * (p.x - x) + (p.y - y) * (p.y - y) <= 1.5 * 1.5) best = std::max(best, p.z);
    const double got = top.at(x, y);
    if (best < 0.0)
      EXPECT_TRUE(std::isnan(got)) << x << " " << y;
    else
      EXPECT_EQ(got, best) << x << " " << y;
  }
}

TEST(SurfaceSupport, the_raster_says_a_height_is_above_the_local_top_as_its_top_does) {
  // above() skips the search where the lower bound already answers; its answer must be at()'s.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> xy(-20.0, 20.0), z(0.0, 15.0);
  std::vector<Point3> points(2500);
  for (auto& p : points) p = {xy(rng), xy(rng), z(rng)};
  points.push_back({0.3, 0.3, 6.0});
  const LocalTop top(points, 1.5);
  Box2 region;
  region.add({-22.0, -22.0});
  region.add({22.0, 22.0});
  const LocalTopRaster asked(top, region, 0.25), searched(top, region, 0.25);
  std::uniform_real_distribution<double> q(-24.0, 24.0), h(-1.0, 17.0);
  std::size_t above = 0, below = 0;
  for (int k = 0; k < 20000; ++k) {
    const double x = q(rng), y = q(rng), height = h(rng);
    const double t = searched.at(x, y);
    const bool expected = !std::isnan(t) && height - t > 0.5;
    EXPECT_EQ(asked.above(x, y, height, 0.5), expected) << x << " " << y << " " << height;
    (expected ? above : below) += 1;
  }
  EXPECT_GT(above, 1000u);
  EXPECT_GT(below, 1000u);
  // Exactly at the tolerance above the top is not above it.
  const double t = searched.at(0.3, 0.3);
  EXPECT_FALSE(asked.above(0.3, 0.3, t + 0.5, 0.5));
  EXPECT_TRUE(asked.above(0.3, 0.3, t + 0.5 + 1e-9, 0.5));
}

TEST(SurfaceSupport, local_top_counts_a_point_exactly_on_the_radius_and_none_beyond) {
  const LocalTop top({{0.0, 0.0, 3.0}, {10.0, 0.0, 7.0}}, 1.5);
  EXPECT_EQ(top.at(1.5, 0.0), 3.0);
  EXPECT_TRUE(std::isnan(top.at(1.5001, 0.0)));
  EXPECT_EQ(top.at(8.5, 0.0), 7.0);
  EXPECT_TRUE(std::isnan(LocalTop({}, 1.5).at(0.0, 0.0)));
}

TEST(SurfaceSupport, a_face_of_square_kilometres_is_sampled_coarser_to_at_most_four_million_samples) {
  // A roof of 12 x 8 km (a cloud in millimetres read as metres): 1.5 billion samples at 0.25 m were
  // 24 GB; the run was killed.
  const std::vector<Point3> roof{{0, 0, 10}, {12000, 0, 10}, {12000, 8000, 10}, {0, 8000, 10}};
  std::vector<Point3> samples;
  const double piece = sample_polygon(roof, 0.25, samples);
  EXPECT_LE(samples.size(), 4000000u);
  EXPECT_GT(samples.size(), 3900000u);
  EXPECT_NEAR(piece * static_cast<double>(samples.size()), 12000.0 * 8000.0, 1e-3);
  // A face of 250,000 m2 or less keeps the spacing asked for.
  const std::vector<Point3> hall{{0, 0, 10}, {500, 0, 10}, {500, 400, 10}, {0, 400, 10}};
  EXPECT_DOUBLE_EQ(sample_polygon(hall, 0.25, samples), 0.0625);
}

TEST(SurfaceSupport, samples_of_a_nonconvex_face_cover_its_area_inside_it_and_no_farther_apart_than_the_spacing) {
  // An L in the tilted plane z = 0.5 x: 6 x 6 minus its 3 x 3 upper right quarter.
  std::vector<Point3> l;
  for (const auto& [x, y] : std::vector<std::pair<double, double>>{{0, 0}, {6, 0}, {6, 3}, {3, 3}, {3, 6}, {0, 6}})
    l.push_back({x, y, 0.5 * x});
  std::vector<Point3> samples;
  const double area = sample_polygon(l, 0.25, samples) * static_cast<double>(samples.size());
  const double expected = 27.0 * std::sqrt(1.25);  // plan area / cos(slope)
  EXPECT_NEAR(area, expected, 1e-9);
  for (const auto& p : samples) {
    EXPECT_NEAR(p.z, 0.5 * p.x, 1e-9);
    EXPECT_FALSE(p.x > 3.0 && p.y > 3.0) << p.x << " " << p.y;  // not in the notch
  }
  // Every sample has a neighbour within the spacing, and there are about one per spacing squared.
  for (std::size_t i = 0; i < samples.size(); i += 37) {
    double nearest = 1e9;
    for (std::size_t j = 0; j < samples.size(); ++j)
      if (j != i)
        nearest = std::min(nearest, std::hypot(samples[i].x - samples[j].x, samples[i].y - samples[j].y,
                                               samples[i].z - samples[j].z));
    EXPECT_LE(nearest, 0.25);
  }
  EXPECT_GT(static_cast<double>(samples.size()), 0.9 * expected / (0.25 * 0.25));
  EXPECT_LT(static_cast<double>(samples.size()), 1.1 * expected / (0.25 * 0.25));
}

// A 10 x 10 m house whose points all lie on a flat roof at 5 m (a 0.5 m grid), modelled either as the flat
// box or with its east half under a blade: a plane rising from 5 m at x = 5 to 15 m at x = 10.
struct BladeHouse {
  std::vector<Point3> points;
  PolygonMesh flat = box(10, 10, 5);
  PolygonMesh blade;
  BladeHouse() {
    for (int i = 0; i <= 20; ++i)
      for (int j = 0; j <= 20; ++j) points.push_back({0.5 * i, 0.5 * j, 5.0});
    blade.vertices = {{0, 0, 0}, {10, 0, 0}, {10, 10, 0}, {0, 10, 0}, {0, 0, 5},
                      {5, 0, 5}, {10, 0, 15}, {10, 10, 15}, {5, 10, 5}, {0, 10, 5}};
    blade.faces = {{0, 3, 2, 1},     // ground
                   {4, 5, 8, 9},     // flat roof, x <= 5
                   {5, 6, 7, 8},     // the blade
                   {0, 1, 6, 5, 4},  // south wall, up to the blade
                   {1, 2, 7, 6},     // east wall, 15 m high
                   {2, 3, 9, 8, 7},  // north wall
                   {3, 0, 4, 9}};    // west wall
  }
};

TEST(SurfaceSupport, a_blade_above_the_roof_is_measured_and_the_flat_roof_is_not) {
  const BladeHouse house;
  const LocalTop top(house.points, 1.5);
  ASSERT_TRUE(check_validity(house.blade).valid()) << check_validity(house.blade).problem;
  const SurfaceSupport flat = surface_support(house.flat, surface_types_unoriented(house.flat), top);
  EXPECT_EQ(flat.unsupported_area, 0.0);
  EXPECT_LE(flat.height_excess, 1e-9);
  EXPECT_EQ(flat.unpointed_roof_area, 0.0);
  const SurfaceSupport blade = surface_support(house.blade, surface_types_unoriented(house.blade), top);
  // Above 6 m (the local top, 5 m, plus 1 m): the blade beyond x = 5.5 (4.5 m x sqrt(5) x 10 m), the
  // two side walls' triangles above 6 m (2 x 20.25 m2) and the east wall above 6 m (9 m x 10 m).
  const double expected = 4.5 * std::sqrt(5.0) * 10.0 + 2 * 20.25 + 90.0;
  EXPECT_NEAR(blade.unsupported_area, expected, 0.03 * expected);
  EXPECT_GT(blade.height_excess, 9.5);
  EXPECT_LE(blade.height_excess, 10.0);
  EXPECT_EQ(blade.face_unsupported_area[0], 0.0);  // the ground is not sampled
  EXPECT_EQ(blade.face_unsupported_area[1], 0.0);  // the flat roof is supported
  EXPECT_NEAR(blade.face_unsupported_area[2], 4.5 * std::sqrt(5.0) * 10.0, 1.5);
  // The points beneath it: those within 1.5 m in plan of its unsupported part (x > 5.5 - 1.5).
  const std::vector<bool> beneath = points_beneath_unsupported(blade, house.points);
  for (std::size_t i = 0; i < house.points.size(); ++i)
    EXPECT_EQ(beneath[i], house.points[i].x > 4.1) << house.points[i].x;
}

// ModelFit, both ways: the points to the model (how many lie farther than 1 m, their squared distances)
// and the model to the points (its unsupported surface), and the two in one figure.
TEST(SurfaceSupport, a_models_fit_counts_far_points_one_way_and_unsupported_surface_the_other) {
  BladeHouse house;
  house.points.push_back({5.0, 5.0, 7.5});  // 2.5 m above the flat roof: far from the flat model
  const LocalTop top(house.points, 1.5);
  std::vector<double> distances;
  const ModelFit flat = fit_both_ways(house.flat, surface_types_unoriented(house.flat), house.points, top, {},
                                      &distances);
  EXPECT_EQ(flat.far, 1u);
  EXPECT_NEAR(flat.squares, 2.5 * 2.5, 1e-9);
  ASSERT_EQ(distances.size(), house.points.size());
  EXPECT_NEAR(distances.back(), 2.5, 1e-9);
  // The lone high point lifts the local top around it: the flat roof stays supported.
  EXPECT_EQ(flat.support.unsupported_area, 0.0);
  const ModelFit blade = fit_both_ways(house.blade, surface_types_unoriented(house.blade), house.points, top, {});
  EXPECT_GT(blade.support.unsupported_area, 100.0);
  // One way only: the same distances, no support measured.
  const ModelFit one_way = fit_of_points(house.flat, house.points);
  EXPECT_EQ(one_way.far, flat.far);
  EXPECT_EQ(one_way.squares, flat.squares);
  EXPECT_EQ(one_way.support.unsupported_area, 0.0);
  // Both ways in one figure, at 4 points per m2: a square metre unsupported weighs 4 points left out.
  EXPECT_DOUBLE_EQ(blade.unfaithful(4.0), static_cast<double>(blade.far) + 4.0 * blade.support.unsupported_area);
  EXPECT_DOUBLE_EQ(flat.squares_both_ways(4.0), flat.squares);
  EXPECT_LT(flat.unfaithful(4.0), blade.unfaithful(4.0));
}

TEST(SurfaceSupport, a_sliver_thinner_than_the_spacing_is_still_sampled_along_its_length) {
  // 20 m long, 5 cm wide, vertical: a sample every 0.25 m along it.
  const std::vector<Point3> sliver = {{0, 0, 0}, {20, 0, 0}, {20, 0, 0.05}, {0, 0, 0.05}};
  std::vector<Point3> samples;
  const double piece = sample_polygon(sliver, 0.25, samples);
  const std::size_t count = samples.size();
  const double area = piece * static_cast<double>(count);
  double lo = 1e9, hi = -1e9;
  for (const Point3& p : samples) lo = std::min(lo, p.x), hi = std::max(hi, p.x);
  EXPECT_NEAR(area, 1.0, 1e-12);
  EXPECT_EQ(count, 80u);
  EXPECT_LT(lo, 0.25);
  EXPECT_GT(hi, 19.75);
}

TEST(SurfaceSupport, roof_with_no_point_near_it_is_unpointed_not_unsupported) {
  // Points only over the west 3 m of the flat box: the roof beyond 4.5 m has no local top.
  std::vector<Point3> points;
  for (int i = 0; i <= 6; ++i)
    for (int j = 0; j <= 20; ++j) points.push_back({0.5 * i, 0.5 * j, 5.0});
  const PolygonMesh house = box(10, 10, 5);
  const SurfaceSupport s = surface_support(house, surface_types_unoriented(house), LocalTop(points, 1.5));
  EXPECT_EQ(s.unsupported_area, 0.0);
  EXPECT_NEAR(s.unpointed_roof_area, 10.0 * (10.0 - 4.5), 1.0);
}

TEST(SurfaceSupport, ground_is_found_whatever_the_orientation_of_the_faces) {
  PolygonMesh m = box(4, 4, 3);
  for (auto& f : m.faces) std::reverse(f.begin(), f.end());  // inward, as some tools write them
  const std::vector<SurfaceType> types = surface_types_unoriented(m);
  EXPECT_EQ(types[0], SurfaceType::ground);
  EXPECT_EQ(types[1], SurfaceType::roof);
  for (std::size_t f = 2; f < 6; ++f) EXPECT_EQ(types[f], SurfaceType::wall);
}

}  // namespace
// A gap in the points narrower than the sample spacing, next to a wall, counts for its own width (Delft
// b112715ef: one 0.25 m column over such a gap was 1.1 of the 1.4 m2 it was measured with). A flat box
// 10 x 10 x 5 m; its roof points run in a row 1.4 m from the south wall (y = 0) and fill the roof beyond
// 2 m; the row has a gap that leaves the wall's foot without a roof point within 1.5 m for 0.16 m around
// x = 5.125, the centre of a 0.25 m column, where one point at 1 m is the local top. The wall is
// unsupported there from 2 m to 5 m: 0.16 x 3 = 0.48 m2 (the column alone would say 0.25 x 3 = 0.75).
TEST(SurfaceSupport, a_gap_narrower_than_the_spacing_counts_for_its_own_width) {
  const double reach = std::sqrt(1.5 * 1.5 - 1.4 * 1.4);  // how far along the row a point of it reaches
  std::vector<Point3> points;
  for (int i = 0; i <= 10000; ++i) {
    const double x = 0.001 * i;
    if (std::abs(x - 5.125) > reach + 0.08) points.push_back({x, 1.4, 5.0});
  }
  for (int i = 0; i <= 20; ++i)
    for (int j = 4; j <= 20; ++j) points.push_back({0.5 * i, 0.5 * j, 5.0});
  points.push_back({5.125, 0.2, 1.0});
  const PolygonMesh house = box(10, 10, 5);
  const SurfaceSupport s = surface_support(house, surface_types_unoriented(house), LocalTop(points, 1.5));
  EXPECT_NEAR(s.unsupported_area, 0.48, 0.05);
  EXPECT_NEAR(s.height_excess, 4.0, 1e-9);
  EXPECT_EQ(s.unsupported_roof_area, 0.0);
}

}  // namespace city3d
