// Tests of the val3dity-equivalent validity check: a hand-made invalid solid for every error code
// the check implements, each caught with its number, and valid solids that pass.
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>
#include <string>
#include <vector>

#include "city3d/evaluation.hpp"
#include "city3d/repair.hpp"
#include "evaluation/validity_shared.hpp"

namespace city3d {
namespace {

using Rings = SolidPolygon;

/// Box [x0, x0 + s] x [y0, y0 + s] x [z0, z0 + s] as 8 vertices appended to `v`; faces outward.
std::vector<SolidPolygon> box_shell(std::vector<Point3>& v, double x0, double y0, double z0, double s,
                                    bool inward = false) {
  const auto b = static_cast<std::uint32_t>(v.size());
  for (double z : {z0, z0 + s})
    for (auto [x, y] : {std::pair{x0, y0}, {x0 + s, y0}, {x0 + s, y0 + s}, {x0, y0 + s}}) v.push_back({x, y, z});
  std::vector<std::vector<std::uint32_t>> faces = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                                   {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  std::vector<SolidPolygon> shell;
  for (auto f : faces) {
    for (auto& i : f) i += b;
    if (inward) std::reverse(f.begin(), f.end());
    shell.push_back({f});
  }
  return shell;
}

SolidGeometry box_solid(double s = 10.0) {
  SolidGeometry solid;
  solid.shells.push_back(box_shell(solid.vertices, 0, 0, 0, s));
  return solid;
}

std::vector<int> codes(const SolidGeometry& solid) {
  std::vector<int> c;
  for (const ValidityError& e : validate_solid(solid)) c.push_back(e.code);
  return c;
}

bool has(const std::vector<int>& c, int code) { return std::find(c.begin(), c.end(), code) != c.end(); }

std::string all_text(const SolidGeometry& solid) {
  std::string s;
  for (const ValidityError& e : validate_solid(solid)) s += e.text() + "; ";
  return s;
}

// The top face (index 1, vertices 4 5 6 7 at z = 10) with extra rings.
void set_top(SolidGeometry& solid, Rings rings) { solid.shells[0][1] = std::move(rings); }

std::uint32_t add(SolidGeometry& solid, Point3 p) {
  solid.vertices.push_back(p);
  return static_cast<std::uint32_t>(solid.vertices.size() - 1);
}

TEST(Validity, box_is_valid) { EXPECT_TRUE(validate_solid(box_solid()).empty()) << all_text(box_solid()); }

TEST(Validity, box_with_a_hole_through_its_top_and_a_cavity_is_valid) {
  SolidGeometry s = box_solid();
  const auto a = add(s, {4, 4, 10}), b = add(s, {4, 6, 10}), c = add(s, {6, 6, 10}), d = add(s, {6, 4, 10});
  set_top(s, {{4, 5, 6, 7}, {a, b, c, d}});  // the hole is clockwise seen from above
  // The hole in the top alone leaves the shell open; close it with a well going down to z = 5.
  const auto e = add(s, {4, 4, 5}), f = add(s, {4, 6, 5}), g = add(s, {6, 6, 5}), h = add(s, {6, 4, 5});
  s.shells[0].push_back({{a, e, f, b}});
  s.shells[0].push_back({{b, f, g, c}});
  s.shells[0].push_back({{c, g, h, d}});
  s.shells[0].push_back({{d, h, e, a}});
  s.shells[0].push_back({{e, h, g, f}});
  s.shells.push_back(box_shell(s.vertices, 1, 1, 1, 2, true));  // a cavity, oriented inward
  EXPECT_TRUE(validate_solid(s).empty()) << all_text(s);
}

TEST(Validity, catches_101_too_few_points) {
  SolidGeometry s = box_solid();
  s.shells[0][1] = {{4, 5}};
  EXPECT_TRUE(has(codes(s), 101)) << all_text(s);
}

// A ring naming a vertex the solid does not have is reported (101, with the index) and nothing else is
// checked: every later check would read past the vertices.
TEST(Validity, vertex_index_out_of_range_is_101_alone) {
  SolidGeometry s = box_solid();
  s.shells[0][1] = {{4, 5, 6, 70}};
  const auto errors = validate_solid(s);
  ASSERT_EQ(errors.size(), 1u) << all_text(s);
  EXPECT_EQ(errors.front().code, 101);
  EXPECT_NE(errors.front().text().find("vertex index 70 of 8"), std::string::npos) << errors.front().text();
}

TEST(Validity, catches_102_consecutive_points_same_after_snapping) {
  SolidGeometry s = box_solid();
  const auto near5 = add(s, {10.0004, 0, 10});  // within val3dity's 1 mm snap tolerance of vertex 5
  set_top(s, {{4, 5, near5, 6, 7}});
  const auto c = codes(s);
  ASSERT_FALSE(c.empty());
  EXPECT_EQ(c.front(), 102) << all_text(s);
  EXPECT_NE(all_text(s).find("102 CONSECUTIVE_POINTS_SAME"), std::string::npos);
}

TEST(Validity, catches_104_bowtie) {
  SolidGeometry s = box_solid();
  set_top(s, {{4, 5, 7, 6}});
  EXPECT_TRUE(has(codes(s), 104)) << all_text(s);
}

TEST(Validity, catches_104_zero_width_spike) {
  // The case: a face carrying a spike 0.8 m long and of no width (out to a point and back
  // along the same line to the start).
  SolidGeometry s = box_solid();
  const auto tip = add(s, {10.8, 0, 10});
  const auto back = add(s, {10.0, 0, 10});  // the same place as vertex 5, not consecutive with it
  set_top(s, {{4, 5, tip, back, 6, 7}});
  EXPECT_TRUE(has(codes(s), 104)) << all_text(s);
  // A spike folding back onto its own edge (tip, then a point between the base and the tip).
  SolidGeometry t = box_solid();
  const auto tip2 = add(t, {10.8, 0, 10}), mid = add(t, {10.4, 0, 10});
  set_top(t, {{4, 5, tip2, mid, 6, 7}});
  EXPECT_TRUE(has(codes(t), 104)) << all_text(t);
}

TEST(Validity, catches_201_intersecting_rings) {
  SolidGeometry s = box_solid();
  const auto a = add(s, {8, 4, 10}), b = add(s, {8, 6, 10}), c = add(s, {12, 6, 10}), d = add(s, {12, 4, 10});
  set_top(s, {{4, 5, 6, 7}, {a, b, c, d}});
  EXPECT_TRUE(has(codes(s), 201)) << all_text(s);
}

TEST(Validity, catches_202_duplicated_rings) {
  SolidGeometry s = box_solid();
  set_top(s, {{4, 5, 6, 7}, {4, 7, 6, 5}});
  EXPECT_TRUE(has(codes(s), 202)) << all_text(s);
}

TEST(Validity, catches_203_non_planar_polygon_distance) {
  SolidGeometry s = box_solid();
  s.vertices[6].z = 10.1;
  const auto c = codes(s);
  EXPECT_TRUE(has(c, 203)) << all_text(s);
  EXPECT_FALSE(has(c, 204));  // 204 is only tested on polygons that pass 203
}

TEST(Validity, catches_204_normals_deviation_of_a_folded_sliver) {
  // A strip 10 m long and 2 mm wide with one corner 4 mm up: within 1 cm of planar (no 203), but
  // whichever diagonal splits it, one triangle leans 63 degrees from the other (the rounding case
  // of the issue: nearly collinear vertices moved by a millimetre).
  SolidGeometry s;
  s.vertices = {{0, 0, 10}, {10, 0, 10}, {10, 0.002, 10.004}, {0, 0.002, 10}};
  s.shells = {{{{0, 1, 2, 3}}}};
  const auto c = codes(s);
  EXPECT_TRUE(has(c, 204)) << all_text(s);
  EXPECT_FALSE(has(c, 203));
  EXPECT_NE(all_text(s).find("204 NON_PLANAR_POLYGON_NORMALS_DEVIATION"), std::string::npos);
}

TEST(Validity, catches_205_interior_disconnected) {
  // A hole touching the exterior ring at two points splits the face in two.
  SolidGeometry s = box_solid();
  const auto a = add(s, {0, 5, 10}), b = add(s, {5, 10, 10}), c = add(s, {4, 4, 10});
  set_top(s, {{4, 5, 6, 7}, {a, b, c}});
  EXPECT_TRUE(has(codes(s), 205)) << all_text(s);
}

TEST(Validity, catches_206_inner_ring_outside) {
  SolidGeometry s = box_solid();
  const auto a = add(s, {12, 4, 10}), b = add(s, {12, 6, 10}), c = add(s, {14, 6, 10}), d = add(s, {14, 4, 10});
  set_top(s, {{4, 5, 6, 7}, {a, b, c, d}});
  EXPECT_TRUE(has(codes(s), 206)) << all_text(s);
}

TEST(Validity, catches_207_inner_rings_nested) {
  SolidGeometry s = box_solid();
  const auto a = add(s, {2, 2, 10}), b = add(s, {2, 8, 10}), c = add(s, {8, 8, 10}), d = add(s, {8, 2, 10});
  const auto e = add(s, {4, 4, 10}), f = add(s, {4, 6, 10}), g = add(s, {6, 6, 10}), h = add(s, {6, 4, 10});
  set_top(s, {{4, 5, 6, 7}, {a, b, c, d}, {e, f, g, h}});
  EXPECT_TRUE(has(codes(s), 207)) << all_text(s);
}

TEST(Validity, catches_208_rings_with_the_same_orientation) {
  SolidGeometry s = box_solid();
  const auto a = add(s, {4, 4, 10}), b = add(s, {6, 4, 10}), c = add(s, {6, 6, 10}), d = add(s, {4, 6, 10});
  set_top(s, {{4, 5, 6, 7}, {a, b, c, d}});  // counter-clockwise like the exterior
  EXPECT_TRUE(has(codes(s), 208)) << all_text(s);
}

TEST(Validity, catches_301_too_few_polygons) {
  SolidGeometry s;
  s.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  s.shells = {{{{0, 2, 1}}, {{0, 1, 3}}, {{1, 2, 3}}}};
  EXPECT_TRUE(has(codes(s), 301)) << all_text(s);
}

TEST(Validity, catches_302_shell_not_closed) {
  SolidGeometry s = box_solid();
  s.shells[0].erase(s.shells[0].begin() + 1);
  EXPECT_TRUE(has(codes(s), 302)) << all_text(s);
}

TEST(Validity, catches_303_non_manifold_vertex) {
  // Two boxes touching at one corner, in one shell.
  SolidGeometry s = box_solid();
  std::vector<SolidPolygon> second = box_shell(s.vertices, 10, 10, 10, 5);
  // Weld the second box's first corner onto the first box's vertex 6 (10, 10, 10).
  for (auto& p : second)
    for (auto& r : p)
      for (auto& i : r)
        if (i == 8) i = 6;
  s.shells[0].insert(s.shells[0].end(), second.begin(), second.end());
  s.vertices.erase(s.vertices.begin() + 8);  // drop the duplicate corner, shift the rest
  for (auto& p : s.shells[0])
    for (auto& r : p)
      for (auto& i : r)
        if (i > 8) --i;
  EXPECT_TRUE(has(codes(s), 303)) << all_text(s);
}

TEST(Validity, catches_304_non_manifold_edge) {
  // Two boxes sharing one edge: four polygons meet there.
  SolidGeometry s = box_solid();
  const auto n = static_cast<std::uint32_t>(s.vertices.size());
  std::vector<SolidPolygon> second = box_shell(s.vertices, 10, 10, 0, 10);
  // The second box's corner (10, 10, z) are vertices n + 0 and n + 4; the first box's are 2 and 6.
  for (auto& p : second)
    for (auto& r : p)
      for (auto& i : r) i = i == n ? 2 : i == n + 4 ? 6 : i;
  s.shells[0].insert(s.shells[0].end(), second.begin(), second.end());
  // The two welded-away vertices stay listed but unused: 309 as well.
  const auto c = codes(s);
  EXPECT_TRUE(has(c, 304)) << all_text(s);
  EXPECT_TRUE(has(c, 309)) << all_text(s);
}

TEST(Validity, catches_305_multiple_connected_components) {
  SolidGeometry s = box_solid();
  std::vector<SolidPolygon> second = box_shell(s.vertices, 20, 0, 0, 5);
  s.shells[0].insert(s.shells[0].end(), second.begin(), second.end());
  EXPECT_TRUE(has(codes(s), 305)) << all_text(s);
}

TEST(Validity, catches_306_shell_self_intersection) {
  // A box whose top is a pyramid of four triangles pushed down through the floor.
  SolidGeometry s = box_solid();
  const auto apex = add(s, {5, 5, -2});
  s.shells[0][1] = {{4, 5, apex}};
  s.shells[0].push_back({{5, 6, apex}});
  s.shells[0].push_back({{6, 7, apex}});
  s.shells[0].push_back({{7, 4, apex}});
  EXPECT_TRUE(has(codes(s), 306)) << all_text(s);
}

TEST(Validity, catches_307_polygon_wrong_orientation) {
  SolidGeometry s = box_solid();
  std::reverse(s.shells[0][3][0].begin(), s.shells[0][3][0].end());
  EXPECT_TRUE(has(codes(s), 307)) << all_text(s);
}

TEST(Validity, shell_errors_name_the_first_polygon_and_count_the_edges) {
  // Which polygon each shell error names, and its counts, as the sorted edges give them: the
  // rewrite of check_shell without maps kept them (960 mutated Delft models, city3d evaluate).
  SolidGeometry flipped = box_solid();
  std::reverse(flipped.shells[0][3][0].begin(), flipped.shells[0][3][0].end());
  std::reverse(flipped.shells[0][5][0].begin(), flipped.shells[0][5][0].end());
  EXPECT_EQ(all_text(flipped),
            "307 POLYGON_WRONG_ORIENTATION (shell 0, face 5: 8 edges used twice in the same direction); ");
  SolidGeometry open = box_solid();
  open.shells[0].erase(open.shells[0].begin() + 2);
  open.shells[0].push_back(open.shells[0][0]);
  EXPECT_EQ(all_text(open),
            "302 SHELL_NOT_CLOSED (shell 0, face 4: 3 edges used by one polygon only); "
            "304 NON_MANIFOLD_EDGE (shell 0, face 0: 3 edges used by more than two polygons); "
            "307 POLYGON_WRONG_ORIENTATION (shell 0, face 5: 1 edges used twice in the same direction); ");
  SolidGeometry apart = box_solid();
  apart.shells[0].push_back(box_shell(apart.vertices, 30, 0, 0, 5, false)[4]);
  EXPECT_EQ(all_text(apart),
            "309 VERTICES_NOT_USED (4 vertices used by no polygon); "
            "302 SHELL_NOT_CLOSED (shell 0, face 6: 4 edges used by one polygon only); "
            "305 MULTIPLE_CONNECTED_COMPONENTS (shell 0: 2 parts joined by no edge); ");
}

// The shell check's own test of a triangle soup against CGAL's is_polygon_soup_a_polygon_mesh, which it
// replaces before the self-intersection test: the same answer on closed surfaces and on soups broken
// the ways a model can be (a triangle flipped, dropped or doubled, two vertices welded, a component
// added that touches the first at a vertex or along an edge, a triangle of random vertices).
TEST(Validity, triangle_soups_form_a_surface_exactly_when_cgal_says_so) {
  using Tri = std::array<std::uint32_t, 3>;
  // An octahedron (vertices 0..5) and a triangulated cube (vertices 0..7), both closed and outward.
  const std::vector<Tri> octahedron = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                                       {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  const std::vector<Tri> cube = {{0, 3, 2}, {0, 2, 1}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                 {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  const auto shifted = [](std::vector<Tri> t, std::uint32_t by) {
    for (Tri& x : t)
      for (std::uint32_t& i : x) i += by;
    return t;
  };
  const auto cgal_says = [](const std::vector<Tri>& t) {
    return CGAL::Polygon_mesh_processing::is_polygon_soup_a_polygon_mesh(t);
  };
  std::mt19937 rng(2611);
  std::size_t surfaces = 0, soups = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    std::vector<Tri> t = trial % 2 ? cube : octahedron;
    const std::uint32_t n = trial % 2 ? 8 : 6;
    const int mutations = static_cast<int>(rng() % 3);
    for (int m = 0; m < mutations && !t.empty(); ++m) {
      const std::size_t k = rng() % t.size();
      switch (rng() % 7) {
        case 0:
          std::swap(t[k][0], t[k][1]);
          break;  // flipped
        case 1:
          t.erase(t.begin() + static_cast<std::ptrdiff_t>(k));
          break;
        case 2:
          t.push_back(t[k]);
          break;   // doubled
        case 3: {  // two vertices welded
          const std::uint32_t a = rng() % n, b = rng() % n;
          for (Tri& x : t)
            for (std::uint32_t& i : x)
              if (i == a) i = b;
          break;
        }
        case 4: {  // a second octahedron sharing one vertex (a pinch) or an edge with the first
          std::vector<Tri> other = shifted(octahedron, 100);
          const bool edge = rng() % 2;
          for (Tri& x : other)
            for (std::uint32_t& i : x) {
              if (i == 100) i = 0;
              if (edge && i == 102) i = 2;
            }
          t.insert(t.end(), other.begin(), other.end());
          break;
        }
        case 5: {  // a second, separate cube: still a surface
          const std::vector<Tri> other = shifted(cube, 200);
          t.insert(t.end(), other.begin(), other.end());
          break;
        }
        default:
          t.push_back({static_cast<std::uint32_t>(rng() % n), static_cast<std::uint32_t>(rng() % n),
                       static_cast<std::uint32_t>(rng() % n)});
      }
    }
    const bool expected = cgal_says(t);
    ASSERT_EQ(detail::triangles_form_a_surface(t), expected) << "trial " << trial;
    (expected ? surfaces : soups) += 1;
  }
  // Both answers are exercised, often.
  EXPECT_GT(surfaces, 1000u);
  EXPECT_GT(soups, 1000u);
  EXPECT_TRUE(detail::triangles_form_a_surface({}));
  // A triangle with a vertex twice, alone (its edges and corners alone would pass), and two triangles
  // back to back (a closed surface of two faces).
  for (const std::vector<Tri>& t : {std::vector<Tri>{{0, 0, 1}}, std::vector<Tri>{{0, 1, 2}, {0, 2, 1}}})
    EXPECT_EQ(detail::triangles_form_a_surface(t), cgal_says(t));
  EXPECT_FALSE(detail::triangles_form_a_surface({{0, 0, 1}}));
}

TEST(Validity, catches_309_vertices_not_used) {
  SolidGeometry s = box_solid();
  add(s, {50, 50, 50});
  const auto c = codes(s);
  ASSERT_EQ(c.size(), 1u) << all_text(s);
  EXPECT_EQ(c.front(), 309);
}

TEST(Validity, catches_401_intersecting_shells) {
  SolidGeometry s = box_solid();
  s.shells.push_back(box_shell(s.vertices, 8, 8, 8, 4, true));
  EXPECT_TRUE(has(codes(s), 401)) << all_text(s);
}

TEST(Validity, catches_402_duplicated_shells) {
  SolidGeometry s = box_solid();
  std::vector<SolidPolygon> copy = s.shells[0];
  for (auto& p : copy) std::reverse(p[0].begin(), p[0].end());
  s.shells.push_back(copy);
  EXPECT_TRUE(has(codes(s), 402)) << all_text(s);
}

TEST(Validity, catches_403_inner_shell_outside) {
  SolidGeometry s = box_solid();
  s.shells.push_back(box_shell(s.vertices, 20, 20, 20, 2, true));
  EXPECT_TRUE(has(codes(s), 403)) << all_text(s);
}

TEST(Validity, catches_405_wrong_orientation_shell) {
  SolidGeometry s;
  s.shells.push_back(box_shell(s.vertices, 0, 0, 0, 10, true));  // every polygon inward
  EXPECT_TRUE(has(codes(s), 405)) << all_text(s);
  SolidGeometry t = box_solid();
  t.shells.push_back(box_shell(t.vertices, 2, 2, 2, 2, false));  // a cavity oriented outward
  EXPECT_TRUE(has(codes(t), 405)) << all_text(t);
}

TEST(Validity, validate_model_checks_each_part_as_a_solid) {
  // Two separate boxes in one mesh: two valid parts (as the CityJSON writer writes them).
  PolygonMesh m;
  for (double x0 : {0.0, 20.0}) {
    const auto b = static_cast<std::uint32_t>(m.vertices.size());
    for (double z : {0.0, 5.0})
      for (auto [x, y] : {std::pair{x0, 0.0}, {x0 + 5, 0.0}, {x0 + 5, 5.0}, {x0, 5.0}}) m.vertices.push_back({x, y, z});
    for (auto f : std::vector<std::vector<std::uint32_t>>{{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}}) {
      for (auto& i : f) i += b;
      m.faces.push_back(f);
    }
  }
  EXPECT_EQ(mesh_parts(m).size(), 2u);
  EXPECT_TRUE(validate_model(m).empty());
  // As one solid (an OBJ object), the same mesh is 305.
  EXPECT_EQ(validity_codes(check_validity(m).errors), "305");
  std::reverse(m.faces[7].begin(), m.faces[7].end());
  const auto errors = validate_model(m);
  ASSERT_FALSE(errors.empty());
  EXPECT_EQ(errors.front().code, 307);
  EXPECT_EQ(errors.front().shell, 1);  // the second part
}

}  // namespace
}  // namespace city3d

namespace city3d {
namespace {

// The 104 case: a face carrying a zero-width spike (out to a tip 0.8 m away and back along
// the same line) on a closed, 2-manifold box, which a check of edges alone calls valid.
BuildingModel box_with_spike() {
  BuildingModel m;
  m.id = "spike";
  m.origin = {85000, 447000, 0};
  m.mesh.vertices = {{0, 0, 0}, {10, 0, 0}, {10, 10, 0}, {0, 10, 0}, {0, 0, 10}, {10, 0, 10}, {10, 10, 10}, {0, 10, 10},
                     {10, 5, 10}, {10.8, 5, 10}};
  m.mesh.faces = {{0, 3, 2, 1}, {4, 5, 8, 9, 8, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 8, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  return m;
}

TEST(ValidAsWritten, a_zero_width_spike_is_caught_as_104_and_cut) {
  BuildingModel m = box_with_spike();
  const WrittenValidity v = validate_as_written(m, 0.0001);
  ASSERT_FALSE(v.found.empty());
  EXPECT_EQ(validity_codes(v.found), "104");
  EXPECT_TRUE(v.remaining.empty()) << validity_codes(v.remaining);
  EXPECT_NE(v.repairs.find("cut 1 zero-width spike"), std::string::npos) << v.repairs;
  EXPECT_TRUE(validate_model(m.mesh).empty());
  EXPECT_EQ(m.mesh.vertices.size(), 9u);  // the tip is gone
}

TEST(ValidAsWritten, rounding_to_the_grid_is_what_is_checked) {
  // A strip roof vertex 0.04 mm off its plane: within tolerance as computed, but the rounding to the
  // 0.1 mm grid is what the writers write, so the model is checked (and stays valid) as rounded.
  BuildingModel m;
  m.origin = {85000, 447000, 0};
  m.mesh.vertices = {{0, 0, 0}, {10, 0, 0}, {10, 10, 0}, {0, 10, 0}, {0, 0, 10}, {10, 0, 10}, {10, 10, 10}, {0, 10, 10.00004}};
  m.mesh.faces = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  const WrittenValidity v = validate_as_written(m, 0.0001);
  EXPECT_TRUE(v.found.empty());
  EXPECT_DOUBLE_EQ(m.mesh.vertices[7].z, 10.0);  // rounded to the grid
}

}  // namespace
}  // namespace city3d
