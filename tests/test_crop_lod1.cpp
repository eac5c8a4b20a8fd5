// Tests of cropping (points and ground per footprint), the LoD1 block model and the mesh checks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <set>
#include <string>

#include "city3d/crop.hpp"
#include "city3d/error.hpp"
#include "city3d/evaluation.hpp"
#include "city3d/lod1.hpp"
#include "city3d/mesh_check.hpp"
#include "city3d/point_cloud_io.hpp"
#ifndef CITY3D_NO_IO
#include "city3d/footprint_io.hpp"
#endif

namespace city3d {
namespace {

// World coordinates at RD New magnitudes, so that the local frame matters.
constexpr double kX = 85000.0;
constexpr double kY = 447000.0;

Ring2 rectangle(double x0, double y0, double x1, double y1) {
  return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};  // counter-clockwise
}

Ring2 reversed(Ring2 ring) {
  std::reverse(ring.begin(), ring.end());
  return ring;
}

Footprint footprint(const std::string& id, std::vector<Polygon2> polygons) {
  Footprint f;
  f.id = id;
  f.polygons = std::move(polygons);
  return f;
}

/// An L: 10 x 10 square without its top-right 5 x 5 quarter.
Ring2 l_shape(double x, double y) {
  return {{x, y}, {x + 10, y}, {x + 10, y + 5}, {x + 5, y + 5}, {x + 5, y + 10}, {x, y + 10}};
}

PointCloud cloud(const std::vector<Point3>& points, const std::vector<std::uint8_t>& classes = {}) {
  PointCloud c;
  c.points = points;
  c.classification = classes;
  return c;
}

std::vector<BuildingInput> crop(std::vector<Footprint> footprints, const PointCloud& points,
                                CropParams params = {}) {
  Cropper cropper(std::move(footprints), std::move(params));
  cropper.add(points);
  return cropper.finish();
}

bool holds(const BuildingInput& b, double world_x, double world_y) {
  return std::any_of(b.points.begin(), b.points.end(), [&](const Point3& p) {
    return p.x + b.origin.x == world_x && p.y + b.origin.y == world_y;
  });
}

double ring_area(const Ring2& r) {
  double a = 0.0;
  for (std::size_t k = 0; k < r.size(); ++k)
    a += r[k].x * r[(k + 1) % r.size()].y - r[(k + 1) % r.size()].x * r[k].y;
  return 0.5 * a;
}

// ---------------------------------------------------------------- coverage (issue 24 item 2)

Box3 box3(double x0, double y0, double x1, double y1) {
  Box3 b;
  b.add({x0, y0, 0});
  b.add({x1, y1, 10});
  return b;
}

// A building input for coverage: the footprint cropped from a cloud of `points` (any class).
BuildingInput covered(const std::vector<Polygon2>& polygons, const std::vector<Point3>& points) {
  std::vector<std::uint8_t> classes(points.size(), 1);  // unclassified: presence only, no building point
  return crop({footprint("f", polygons)}, cloud(points, classes)).front();
}

std::vector<Box2> local(const std::vector<Box3>& tiles, const std::vector<std::uint64_t>& counts, const Point3& origin) {
  std::vector<Box2> out;
  for (std::size_t t = 0; t < tiles.size(); ++t) {
    const Box2 e = tile_extent(tiles[t], counts[t]);
    Box2 l;
    l.add({e.min.x - origin.x, e.min.y - origin.y});
    l.add({e.max.x - origin.x, e.max.y - origin.y});
    out.push_back(l);
  }
  return out;
}

TEST(Coverage, a_tile_extent_is_its_header_box_grown_by_half_its_point_spacing) {
  // 100 x 100 m with 40,000 points: 0.5 m apart.
  EXPECT_DOUBLE_EQ(point_spacing(box3(0, 0, 100, 100), 40000), 0.5);
  const Box2 e = tile_extent(box3(0, 0, 100, 100), 40000);
  EXPECT_DOUBLE_EQ(e.min.x, -0.25);
  EXPECT_DOUBLE_EQ(e.max.y, 100.25);
  EXPECT_TRUE(tile_extent(box3(0, 0, 100, 100), 0).empty());
  EXPECT_TRUE(tile_extent(Box3{}, 10).empty());
  // Cells of three spacings, at least 1 m, a multiple of the presence lattice.
  EXPECT_DOUBLE_EQ(coverage_cell_size(0.26, 0.25), 1.0);
  EXPECT_DOUBLE_EQ(coverage_cell_size(0.5, 0.25), 1.5);
  EXPECT_DOUBLE_EQ(coverage_cell_size(0.5, 1.0), 2.0);
}

TEST(Coverage, the_area_share_is_the_part_of_the_footprint_inside_the_tiles_extents) {
  // A 10 x 10 m footprint across x = kX + 5, with points everywhere in it at 0.25 m.
  std::vector<Point3> points;
  for (double x = kX + 0.1; x < kX + 10; x += 0.25)
    for (double y = kY + 0.1; y < kY + 10; y += 0.25) points.push_back({x, y, 5});
  const BuildingInput in = covered({{rectangle(kX, kY, kX + 10, kY + 10), {}}}, points);
  // The left tile alone (grown by a negligible spacing): 7 of 10 m.
  const Box3 left = box3(kX - 50, kY - 50, kX + 7, kY + 50);
  FootprintCoverage c = footprint_coverage(in, local({left}, {1000000000}, in.origin), 0.25);
  EXPECT_NEAR(c.area, 0.7, 1e-3);
  EXPECT_DOUBLE_EQ(c.cells, 1.0);  // the points are there: only the tiles given decide
  // Both tiles, 2 mm apart (as Delft's at x = 85000): all of it.
  const Box3 right = box3(kX + 7.002, kY - 50, kX + 60, kY + 50);
  c = footprint_coverage(in, local({left, right}, {10000, 10000}, in.origin), 0.25);
  EXPECT_DOUBLE_EQ(c.area, 1.0);
  // No tile at all, and a tile elsewhere.
  EXPECT_DOUBLE_EQ(footprint_coverage(in, {}, 0.25).area, 0.0);
  EXPECT_DOUBLE_EQ(footprint_coverage(in, local({box3(kX + 100, kY, kX + 200, kY + 100)}, {100}, in.origin), 0.25).area,
                   0.0);
  // Overlapping tiles are not counted twice.
  c = footprint_coverage(in, local({left, box3(kX - 10, kY - 10, kX + 3, kY + 20)}, {1000000000, 1000000000}, in.origin),
                         0.25);
  EXPECT_NEAR(c.area, 0.7, 1e-3);
}

TEST(Coverage, a_hole_and_a_second_polygon_count_by_their_area) {
  // 20 x 10 with a 4 x 4 hole on the left half, and a 5 x 5 square apart on the right: the tile
  // covers x < kX + 10, the holed polygon's left half (100 - 16 m2) and nothing of the square.
  const Polygon2 holed{rectangle(kX, kY, kX + 20, kY + 10), {reversed(rectangle(kX + 3, kY + 3, kX + 7, kY + 7))}};
  const Polygon2 square{rectangle(kX + 30, kY, kX + 35, kY + 5), {}};
  const BuildingInput in = covered({holed, square}, {});
  const FootprintCoverage c =
      footprint_coverage(in, local({box3(kX - 100, kY - 100, kX + 10, kY + 100)}, {4000000000}, in.origin), 0.25);
  EXPECT_NEAR(c.area, (100.0 - 16.0) / (200.0 - 16.0 + 25.0), 1e-3);
  EXPECT_DOUBLE_EQ(c.cells, 0.0);  // no point at all
}

TEST(Coverage, the_cell_share_counts_cells_with_points_of_any_class) {
  // Points over the left 6 m of a 10 x 10 m footprint only: 1 m cells, 60 of 100 with points.
  std::vector<Point3> points;
  for (double x = kX + 0.1; x < kX + 6; x += 0.3)
    for (double y = kY + 0.1; y < kY + 10; y += 0.3) points.push_back({x, y, 5});
  const BuildingInput in = covered({{rectangle(kX, kY, kX + 10, kY + 10), {}}}, points);
  EXPECT_TRUE(in.points.empty());  // class 1: no building point, but data
  const FootprintCoverage c =
      footprint_coverage(in, local({box3(kX - 100, kY - 100, kX + 100, kY + 100)}, {4000000000}, in.origin), 0.25);
  EXPECT_DOUBLE_EQ(c.area, 1.0);
  EXPECT_DOUBLE_EQ(c.cells, 0.6);
  // Sparser tiles, larger cells (3 spacings of 1 m: 3 m cells aligned to multiples of 3 m).
  const FootprintCoverage coarse =
      footprint_coverage(in, local({box3(kX - 100, kY - 100, kX + 100, kY + 100)}, {40000}, in.origin), 1.0);
  EXPECT_GT(coarse.cells, 0.5);
  EXPECT_LT(coarse.cells, 1.0);
}

TEST(Coverage, the_building_share_counts_the_cells_with_points_that_hold_building_points) {
  // Points of any class over all of a 10 x 10 m footprint, at 0.3 m; those over its left 4 m building
  // points (class 6), the rest ground (class 2): 1 m cells, 40 of the 100 with points hold the building's.
  std::vector<Point3> points;
  std::vector<std::uint8_t> classes;
  for (double x = kX + 0.1; x < kX + 10; x += 0.3)
    for (double y = kY + 0.1; y < kY + 10; y += 0.3) {
      points.push_back({x, y, x < kX + 4 ? 8.0 : 0.1});
      classes.push_back(x < kX + 4 ? 6 : 2);
    }
  const BuildingInput in =
      crop({footprint("f", {{rectangle(kX, kY, kX + 10, kY + 10), {}}})}, cloud(points, classes)).front();
  ASSERT_FALSE(in.points.empty());
  const std::vector<Box2> tiles =
      local({box3(kX - 100, kY - 100, kX + 100, kY + 100)}, {4000000000}, in.origin);
  FootprintCoverage c = footprint_coverage(in, tiles, 0.25);
  EXPECT_DOUBLE_EQ(c.cells, 1.0);
  EXPECT_DOUBLE_EQ(c.building, 0.4);
  // Of the cells with points only: the right half without any point leaves the share of the rest.
  std::vector<Point3> left_only;
  std::vector<std::uint8_t> left_classes;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (points[i].x < kX + 5) left_only.push_back(points[i]), left_classes.push_back(classes[i]);
  const BuildingInput half =
      crop({footprint("f", {{rectangle(kX, kY, kX + 10, kY + 10), {}}})}, cloud(left_only, left_classes))
          .front();
  c = footprint_coverage(half, tiles, 0.25);
  EXPECT_DOUBLE_EQ(c.cells, 0.5);
  EXPECT_DOUBLE_EQ(c.building, 0.8);
  // No point at all: unknown, not 0.
  EXPECT_TRUE(std::isnan(
      footprint_coverage(covered({{rectangle(kX, kY, kX + 10, kY + 10), {}}}, {}), tiles, 0.25).building));
}

// ---------------------------------------------------------------- cropping: which points go where

TEST(Crop, assigns_points_inside_a_square_in_a_local_frame) {
  const auto inputs =
      crop({footprint("sq", {{rectangle(kX, kY, kX + 10.4, kY + 10.4), {}}})},
           cloud({{kX + 1, kY + 1, 5}, {kX + 9, kY + 2, 6}, {kX - 1, kY + 1, 7}, {kX + 11, kY + 5, 8}},
                 {6, 6, 6, 6}));
  ASSERT_EQ(inputs.size(), 1u);
  const BuildingInput& b = inputs[0];
  EXPECT_EQ(b.id, "sq");
  // Origin: bbox centre (kX + 5.2, kY + 5.2) rounded to the metre, z = 0.
  EXPECT_EQ(b.origin.x, kX + 5);
  EXPECT_EQ(b.origin.y, kY + 5);
  EXPECT_EQ(b.origin.z, 0.0);
  ASSERT_EQ(b.points.size(), 2u);
  EXPECT_DOUBLE_EQ(b.points[0].x, -4.0);
  EXPECT_DOUBLE_EQ(b.points[0].y, -4.0);
  EXPECT_DOUBLE_EQ(b.points[0].z, 5.0);
  EXPECT_DOUBLE_EQ(b.points[1].x, 4.0);
  // The footprint comes back in the same local frame.
  EXPECT_DOUBLE_EQ(b.footprint.polygons[0].outer[0].x, -5.0);
  EXPECT_EQ(b.footprint.polygons[0].outer[2].y, (kY + 10.4) - (kY + 5));  // exact: no rounding added
}

TEST(Crop, assigns_points_inside_an_l_shape_but_not_in_its_notch) {
  const auto inputs =
      crop({footprint("L", {{l_shape(kX, kY), {}}})},
           cloud({{kX + 2, kY + 2, 1}, {kX + 8, kY + 2, 1}, {kX + 2, kY + 8, 1}, {kX + 8, kY + 8, 1}}));
  ASSERT_EQ(inputs[0].points.size(), 3u);
  EXPECT_TRUE(holds(inputs[0], kX + 2, kY + 8));
  EXPECT_FALSE(holds(inputs[0], kX + 8, kY + 8));
}

TEST(Crop, does_not_assign_points_inside_a_hole) {
  Polygon2 courtyard{rectangle(kX, kY, kX + 20, kY + 20),
                     {reversed(rectangle(kX + 5, kY + 5, kX + 15, kY + 15))}};
  const auto inputs =
      crop({footprint("court", {courtyard})},
           cloud({{kX + 10, kY + 10, 1}, {kX + 2, kY + 10, 1}, {kX + 10, kY + 17, 1}}, {6, 6, 6}));
  ASSERT_EQ(inputs[0].points.size(), 2u);
  EXPECT_FALSE(holds(inputs[0], kX + 10, kY + 10));
}

TEST(Crop, holes_are_respected_whatever_the_ring_orientation) {
  // Readers normalise rings, but the even-odd rule must not rely on it.
  Polygon2 courtyard{reversed(rectangle(kX, kY, kX + 20, kY + 20)),
                     {rectangle(kX + 5, kY + 5, kX + 15, kY + 15)}};
  const auto inputs =
      crop({footprint("court", {courtyard})}, cloud({{kX + 10, kY + 10, 1}, {kX + 2, kY + 10, 1}}));
  ASSERT_EQ(inputs[0].points.size(), 1u);
  EXPECT_TRUE(holds(inputs[0], kX + 2, kY + 10));
}

TEST(Crop, a_point_beyond_a_neighbour_goes_only_to_the_footprint_containing_it) {
  // Two footprints in a row: the ray of the crossing test passes the far one, which must not matter.
  const auto inputs = crop({footprint("west", {{rectangle(kX, kY, kX + 10, kY + 10), {}}}),
                            footprint("east", {{rectangle(kX + 20, kY, kX + 30, kY + 10), {}}})},
                           cloud({{kX + 5, kY + 5, 1}, {kX + 25, kY + 5, 2}, {kX + 15, kY + 5, 3}}));
  ASSERT_EQ(inputs[0].points.size(), 1u);
  ASSERT_EQ(inputs[1].points.size(), 1u);
  EXPECT_TRUE(holds(inputs[0], kX + 5, kY + 5));
  EXPECT_TRUE(holds(inputs[1], kX + 25, kY + 5));
}

TEST(Crop, a_multipolygon_collects_points_of_all_its_parts) {
  const auto inputs = crop({footprint("multi", {{rectangle(kX, kY, kX + 10, kY + 10), {}},
                                                {rectangle(kX + 20, kY, kX + 30, kY + 10), {}}})},
                           cloud({{kX + 5, kY + 5, 1}, {kX + 25, kY + 5, 2}, {kX + 15, kY + 5, 3}}));
  EXPECT_EQ(inputs[0].points.size(), 2u);
}

TEST(Crop, a_point_on_a_shared_edge_goes_to_exactly_one_footprint) {
  // Two footprints sharing a slanted edge from (10, 0) to (13, 10); the second one's ring runs the
  // other way round. Points on (or, after rounding, next to) the edge must each land exactly once.
  const Ring2 left{{kX, kY}, {kX + 10, kY}, {kX + 13, kY + 10}, {kX, kY + 10}};
  const Ring2 right = reversed({{kX + 10, kY}, {kX + 20, kY}, {kX + 20, kY + 10}, {kX + 13, kY + 10}});
  // The top end (13, 10) is left out: it is also on the union's top boundary, which the half-open
  // rule leaves outside both.
  std::vector<Point3> points;
  for (int k = 0; k < 100; ++k) {
    const double t = k / 100.0;
    points.push_back({kX + 10 + 3 * t, kY + 10 * t, 1.0});
  }
  points.push_back({kX + 20, kY + 5, 1.0});  // on the right footprint's outer edge: inside, by the rule
  points.push_back({kX, kY + 5, 1.0});       // on the left footprint's outer edge: inside
  const auto inputs =
      crop({footprint("left", {{left, {}}}), footprint("right", {{right, {}}})}, cloud(points));
  // Every shared-edge point is assigned once; of the two outer-edge points the left-edge one goes in
  // (ray to +x crosses the far edge) and the right-edge one stays out.
  EXPECT_EQ(inputs[0].points.size() + inputs[1].points.size(), 100u + 1u);
  EXPECT_TRUE(holds(inputs[0], kX, kY + 5));
  EXPECT_FALSE(holds(inputs[1], kX + 20, kY + 5));

  // Same answer with the footprints in the other order.
  const auto swapped =
      crop({footprint("right", {{right, {}}}), footprint("left", {{left, {}}})}, cloud(points));
  EXPECT_EQ(swapped[1].points.size(), inputs[0].points.size());
  EXPECT_EQ(swapped[0].points.size(), inputs[1].points.size());
}

TEST(Crop, building_classes_select_points_and_other_classes_are_dropped) {
  CropParams params;
  params.building_classes = {6, 26};
  const auto inputs =
      crop({footprint("sq", {{rectangle(kX, kY, kX + 10, kY + 10), {}}})},
           cloud({{kX + 1, kY + 1, 1}, {kX + 2, kY + 1, 2}, {kX + 3, kY + 1, 3}, {kX + 4, kY + 1, 4}},
                 {6, 1, 26, 2}),
           params);
  ASSERT_EQ(inputs[0].points.size(), 2u);
  EXPECT_EQ(inputs[0].points[1].z, 3.0);
  EXPECT_TRUE(inputs[0].ground_heights.empty());  // the class-2 point is inside the footprint
}

TEST(Crop, without_classes_every_point_inside_is_a_building_point_and_every_point_around_a_ground_point) {
  // Inside: two points. Around, in the 3 m buffer: one, then twelve (the ground needs ten), at 0.5 m up
  // to 1.6 m (a car, a fence); 20 m away: none of them.
  std::vector<Point3> points{
      {kX + 1, kY + 1, 4}, {kX + 2, kY + 1, 9}, {kX + 12, kY + 1, 0}, {kX + 30, kY + 1, -9}};
  auto inputs = crop({footprint("sq", {{rectangle(kX, kY, kX + 10, kY + 10), {}}})}, cloud(points));
  EXPECT_EQ(inputs[0].points.size(), 2u);
  EXPECT_EQ(inputs[0].ground_heights, std::vector<double>{0.0});  // too few to use, still counted
  EXPECT_EQ(inputs[0].ground_method, "lowest building point");
  EXPECT_EQ(inputs[0].ground_z, 4.0);
  EXPECT_TRUE(inputs[0].footprint.note.find("no ground point near it") != std::string::npos)
      << inputs[0].footprint.note;
  for (int k = 0; k < 11; ++k) points.push_back({kX + k, kY - 1, 0.5 + 0.1 * k});
  CropParams ignore;
  ignore.use_classes = ClassUse::never;  // --ignore-classes: the classes given are not read
  inputs = crop({footprint("sq", {{rectangle(kX, kY, kX + 10, kY + 10), {}}})},
                cloud(points, std::vector<std::uint8_t>(points.size(), 6)), ignore);
  EXPECT_EQ(inputs[0].points.size(), 2u);
  EXPECT_EQ(inputs[0].ground_heights.size(), 12u);
  EXPECT_EQ(inputs[0].ground_method, "ground percentile");
  EXPECT_NEAR(inputs[0].ground_z, 0.51, 1e-12);  // rank 0.1 * 11 = 1.1 between 0.5 and 0.6
  EXPECT_TRUE(inputs[0].footprint.note.empty()) << inputs[0].footprint.note;
}

TEST(Crop, a_ground_above_half_of_the_building_points_is_not_taken) {
  // Ground points around at 50 m (another datum than the building's), building points at 9-12 m.
  std::vector<Point3> points;
  std::vector<std::uint8_t> classes;
  for (int k = 0; k < 12; ++k) points.push_back({kX + k * 0.5, kY - 1, 50.0}), classes.push_back(2);
  for (int k = 0; k < 4; ++k) points.push_back({kX + 1 + k, kY + 5, 9.0 + k}), classes.push_back(6);
  auto inputs = crop({footprint("sq", {{rectangle(kX, kY, kX + 10, kY + 10), {}}})}, cloud(points, classes));
  EXPECT_EQ(inputs[0].ground_method, "lowest building point");
  EXPECT_FALSE(inputs[0].ground_measured);
  EXPECT_EQ(inputs[0].ground_z, 9.0);
  EXPECT_TRUE(inputs[0].footprint.note.find("lie above half of its points (median 10.500 m)") !=
              std::string::npos)
      << inputs[0].footprint.note;
  // At 10.4 m, below the median: the ground stands (a building on a slope, its lowest points below it).
  for (std::size_t k = 0; k < 12; ++k) points[k].z = 10.4;
  inputs = crop({footprint("sq", {{rectangle(kX, kY, kX + 10, kY + 10), {}}})}, cloud(points, classes));
  EXPECT_EQ(inputs[0].ground_method, "ground percentile");
  EXPECT_DOUBLE_EQ(inputs[0].ground_z, 10.4);
  EXPECT_TRUE(inputs[0].footprint.note.empty()) << inputs[0].footprint.note;
}

TEST(Crop, the_ground_class_cannot_also_be_a_building_class) {
  CropParams params;
  params.ground_class = 6;
  EXPECT_THROW(params.validate(), ConfigError);
  params.use_classes = ClassUse::never;  // classes not read: no contradiction
  EXPECT_NO_THROW(params.validate());
}

TEST(Crop, footprints_that_overlap_are_noted_with_the_other_footprint) {
  // A 10 x 10 m building, a block polygon over it and its neighbour, and the neighbour, apart from it
  // (no ground points: each note goes on to say so).
  std::vector<Point3> points;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) {
      points.push_back({kX + 0.5 + i, kY + 0.5 + j, 8});
      points.push_back({kX + 20.5 + i, kY + 0.5 + j, 9});
    }
  const auto inputs = crop({footprint("house", {{rectangle(kX, kY, kX + 10, kY + 10), {}}}),
                            footprint("block", {{rectangle(kX - 5, kY - 5, kX + 35, kY + 15), {}}}),
                            footprint("neighbour", {{rectangle(kX + 20, kY, kX + 30, kY + 10), {}}})},
                           cloud(points, std::vector<std::uint8_t>(points.size(), 6)));
  EXPECT_EQ(inputs[0].footprint.note.rfind(
                "100 of its 100 points lie in footprint block too: the footprints overlap", 0),
            0u);
  EXPECT_EQ(inputs[1].footprint.note.rfind(
                "200 of its 200 points lie in footprint house too: the footprints overlap", 0),
            0u);
  EXPECT_EQ(inputs[2].footprint.note.rfind(
                "100 of its 100 points lie in footprint block too: the footprints overlap", 0),
            0u);
  // Footprints that only touch share no point.
  const auto apart = crop({footprint("a", {{rectangle(kX, kY, kX + 10, kY + 10), {}}}),
                           footprint("b", {{rectangle(kX + 10, kY, kX + 20, kY + 10), {}}})},
                          cloud(points, std::vector<std::uint8_t>(points.size(), 6)));
  EXPECT_EQ(apart[0].footprint.note.find("overlap"), std::string::npos) << apart[0].footprint.note;
  EXPECT_EQ(apart[1].footprint.note.find("overlap"), std::string::npos) << apart[1].footprint.note;
}

TEST(Crop, rejects_a_chunk_whose_classes_do_not_match_its_points) {
  Cropper cropper({footprint("sq", {{rectangle(kX, kY, kX + 10, kY + 10), {}}})});
  EXPECT_THROW(cropper.add(cloud({{kX + 1, kY + 1, 4}, {kX + 2, kY + 1, 9}}, {6})), Error);
}

TEST(Crop, rejects_invalid_parameters_listing_each_problem) {
  CropParams params;
  params.ground_buffer = -1;
  params.ground_percentile = 150;
  try {
    params.validate();
    FAIL() << "no exception";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("ground_buffer"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("ground_percentile"), std::string::npos);
  }
}

TEST(Crop, pins_the_default_parameters) {
  const CropParams params;
  EXPECT_EQ(params.building_classes, std::vector<std::uint8_t>{6});
  EXPECT_EQ(params.ground_class, 2);
  EXPECT_EQ(params.ground_buffer, 3.0);
  EXPECT_EQ(params.wide_buffer_factor, 4.0);
  EXPECT_EQ(params.ground_percentile, 10.0);
  EXPECT_EQ(params.min_ground_points, 10u);
  EXPECT_EQ(params.use_classes, ClassUse::automatic);
  EXPECT_EQ(Lod1Params{}.roof_percentile, 70.0);
  EXPECT_EQ(Lod1Params{}.min_height, 1.0);
}

// ---------------------------------------------------------------- cropping: ground height

TEST(Percentile, interpolates_linearly_between_closest_ranks) {
  std::vector<double> v{5, 1, 4, 2, 3};
  EXPECT_DOUBLE_EQ(percentile(v, 0), 1.0);
  EXPECT_DOUBLE_EQ(percentile(v, 100), 5.0);
  EXPECT_DOUBLE_EQ(percentile(v, 50), 3.0);
  EXPECT_DOUBLE_EQ(percentile(v, 10), 1.4);
  EXPECT_DOUBLE_EQ(percentile(v, 70), 3.8);
  std::vector<double> one{7};
  EXPECT_DOUBLE_EQ(percentile(one, 70), 7.0);
}

// The LoD1.3 clusters keep their heights sorted and take the percentile of the sorted list: it must be
// percentile()'s number, bit for bit, whatever order percentile() gets the values in.
TEST(Percentile, of_sorted_values_is_the_same_number_as_of_the_values_in_any_order) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> height(2.0, 30.0);
  for (std::size_t n : {1u, 2u, 3u, 7u, 50u, 1001u}) {
    std::vector<double> values(n);
    for (double& v : values) v = height(rng);
    for (std::size_t k = 0; k + 1 < n; k += 3) values[k + 1] = values[k];  // ties
    std::vector<double> sorted = values;
    std::sort(sorted.begin(), sorted.end());
    for (double p : {0.0, 10.0, 33.3, 50.0, 70.0, 99.9, 100.0}) {
      std::shuffle(values.begin(), values.end(), rng);
      std::vector<double> any_order = values;
      const double expected = percentile(any_order, p);
      EXPECT_EQ(sorted_percentile(sorted, p), expected) << n << " values, p = " << p;
    }
  }
  EXPECT_EQ(sorted_percentile({1, 2, 3, 4, 5}, 70), 3.8);
}

TEST(Crop, ground_height_is_the_10th_percentile_of_ground_points_in_the_buffer) {
  // 20 ground points 1 m south of the square at z = 1..20, plus ground points that must not count:
  // one inside the footprint (z = -50), one 5 m away (beyond the 3 m buffer, z = -40).
  std::vector<Point3> points;
  std::vector<std::uint8_t> classes;
  for (int k = 0; k < 20; ++k) {
    points.push_back({kX + 0.5 * k, kY - 1, 1.0 + k});
    classes.push_back(2);
  }
  points.push_back({kX + 5, kY + 5, -50});
  classes.push_back(2);
  points.push_back({kX + 5, kY - 5, -40});
  classes.push_back(2);
  points.push_back({kX + 5, kY + 5, 12});
  classes.push_back(6);
  const auto inputs =
      crop({footprint("sq", {{rectangle(kX, kY, kX + 10, kY + 10), {}}})}, cloud(points, classes));
  EXPECT_EQ(inputs[0].ground_method, "ground percentile");
  EXPECT_EQ(inputs[0].ground_heights.size(), 20u);
  EXPECT_NEAR(inputs[0].ground_z, 2.9, 1e-12);  // rank 0.1 * 19 = 1.9 between 2 and 3
}

TEST(Crop, the_ground_buffer_follows_the_polygon_not_its_bounding_box) {
  // Ground points in the notch of the L, 4 m and more from every edge, are outside the 3 m buffer.
  std::vector<Point3> points;
  for (int k = 0; k < 12; ++k) points.push_back({kX + 9.5 + 0.01 * k, kY + 9.5, -5.0});  // notch corner
  for (int k = 0; k < 12; ++k) points.push_back({kX + 2 + 0.1 * k, kY - 2, 1.0});        // 2 m south
  const auto inputs =
      crop({footprint("L", {{l_shape(kX, kY), {}}})}, cloud(points, std::vector<std::uint8_t>(24, 2)));
  EXPECT_EQ(inputs[0].ground_method, "ground percentile");
  EXPECT_EQ(inputs[0].ground_heights.size(), 12u);
  EXPECT_DOUBLE_EQ(inputs[0].ground_z, 1.0);
}

TEST(Crop, ground_falls_back_to_the_wide_buffer_when_the_buffer_has_too_few_points) {
  std::vector<Point3> points;
  for (int k = 0; k < 4; ++k) points.push_back({kX + k, kY - 1, 1.0});      // in the 3 m buffer
  for (int k = 0; k < 8; ++k) points.push_back({kX + k, kY - 8, 2.0 + k});  // 8 m away: wide buffer (12 m)
  points.push_back({kX + 5, kY - 20, -30.0});                               // beyond the wide buffer
  const auto inputs = crop({footprint("sq", {{rectangle(kX, kY, kX + 10, kY + 10), {}}})},
                           cloud(points, std::vector<std::uint8_t>(points.size(), 2)));
  EXPECT_EQ(inputs[0].ground_method, "ground percentile (wide buffer)");
  ASSERT_EQ(inputs[0].ground_heights.size(), 12u);
  // 12 heights: 1,1,1,1,2,3,...,9; rank 0.1 * 11 = 1.1 -> 1.0.
  EXPECT_DOUBLE_EQ(inputs[0].ground_z, 1.0);
}

TEST(Crop, ground_falls_back_to_the_lowest_building_point) {
  std::vector<Point3> points{
      {kX + 1, kY + 1, 7.0}, {kX + 2, kY + 2, 4.5}, {kX + 3, kY + 3, 9.0}, {kX + 1, kY - 1, 0.0}};
  const auto inputs =
      crop({footprint("sq", {{rectangle(kX, kY, kX + 10, kY + 10), {}}})}, cloud(points, {6, 6, 6, 2}));
  EXPECT_EQ(inputs[0].ground_method, "lowest building point");
  EXPECT_DOUBLE_EQ(inputs[0].ground_z, 4.5);
  EXPECT_EQ(inputs[0].ground_heights.size(), 1u);  // too few to use, still reported
}

TEST(Crop, a_footprint_without_points_gets_ground_zero_and_method_none) {
  const auto inputs = crop({footprint("empty", {{rectangle(kX, kY, kX + 10, kY + 10), {}}})},
                           cloud({{kX + 100, kY + 100, 3}}, {6}));
  EXPECT_EQ(inputs[0].ground_method, "none");
  EXPECT_EQ(inputs[0].ground_z, 0.0);
  EXPECT_TRUE(inputs[0].points.empty());
}

TEST(Crop, every_footprint_gets_an_input_even_an_unusable_one) {
  const auto inputs = crop(
      {footprint("a", {{rectangle(kX, kY, kX + 10, kY + 10), {}}}), footprint("broken", {{{{kX, kY}}, {}}}),
       footprint("b", {{rectangle(kX + 20, kY, kX + 30, kY + 10), {}}})},
      cloud({{kX + 5, kY + 5, 3}, {kX + 25, kY + 5, 3}}, {6, 6}));
  ASSERT_EQ(inputs.size(), 3u);
  EXPECT_EQ(inputs[1].id, "broken");
  EXPECT_TRUE(inputs[1].points.empty());
  EXPECT_EQ(inputs[0].points.size(), 1u);
  EXPECT_EQ(inputs[2].points.size(), 1u);
}

// ---------------------------------------------------------------- cropping: streaming

void expect_same(const std::vector<BuildingInput>& a, const std::vector<BuildingInput>& b) {
  ASSERT_EQ(a.size(), b.size());
  auto same_points = [](const std::vector<Point3>& p, const std::vector<Point3>& q) {
    if (p.size() != q.size()) return false;
    for (std::size_t k = 0; k < p.size(); ++k)
      if (p[k].x != q[k].x || p[k].y != q[k].y || p[k].z != q[k].z) return false;
    return true;
  };
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].id, b[i].id);
    EXPECT_TRUE(same_points(a[i].points, b[i].points)) << a[i].id;
    EXPECT_EQ(a[i].ground_heights, b[i].ground_heights) << a[i].id;
    EXPECT_EQ(a[i].ground_z, b[i].ground_z) << a[i].id;
    EXPECT_EQ(a[i].ground_method, b[i].ground_method) << a[i].id;
    EXPECT_EQ(a[i].presence.marked, b[i].presence.marked) << a[i].id;
  }
}

TEST(Crop, chunked_and_whole_input_give_identical_building_inputs) {
  // A block of footprints with shared edges, a hole, an L and a lonely one, and 60,000 random points
  // of classes 1, 2 and 6 over and around them (fixed seed).
  std::vector<Footprint> footprints{
      footprint("a", {{rectangle(kX, kY, kX + 10, kY + 10), {}}}),
      footprint("b", {{rectangle(kX + 10, kY, kX + 20, kY + 10), {}}}),
      footprint("court", {{rectangle(kX, kY + 10, kX + 20, kY + 30),
                           {reversed(rectangle(kX + 5, kY + 15, kX + 15, kY + 25))}}}),
      footprint("L", {{l_shape(kX + 30, kY), {}}}),
      footprint("far", {{rectangle(kX + 70, kY + 40, kX + 75, kY + 45), {}}}),
  };
  std::mt19937_64 rng(20240611);
  std::uniform_real_distribution<double> ux(kX - 20, kX + 90), uy(kY - 20, kY + 60), uz(0, 15);
  std::discrete_distribution<int> uc({1, 2, 3});
  const std::uint8_t class_of[] = {1, 2, 6};
  PointCloud all;
  for (int k = 0; k < 60000; ++k) {
    all.points.push_back({ux(rng), uy(rng), uz(rng)});
    all.classification.push_back(class_of[uc(rng)]);
  }
  const auto whole = crop(footprints, all);
  std::size_t assigned = 0;
  for (const auto& b : whole) assigned += b.points.size();
  EXPECT_GT(assigned, 1000u);
  EXPECT_EQ(whole[4].ground_method, "ground percentile");

  for (std::size_t chunk : {1u, 7u, 4096u}) {
    Cropper cropper(footprints);
    for (std::size_t first = 0; first < all.size(); first += chunk) {
      const std::size_t last = std::min(all.size(), first + chunk);
      PointCloud part;
      part.points.assign(all.points.begin() + first, all.points.begin() + last);
      part.classification.assign(all.classification.begin() + first, all.classification.begin() + last);
      cropper.add(part);
    }
    SCOPED_TRACE("chunk size " + std::to_string(chunk));
    expect_same(whole, cropper.finish());
  }
}

TEST(Crop, brute_force_agrees_with_the_grid_on_many_footprints) {
  // 400 small footprints on a jittered grid; every point's footprint is computed by hand.
  std::vector<Footprint> footprints;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) {
      const double x = kX + 12.0 * i, y = kY + 12.0 * j;
      footprints.push_back(footprint(std::to_string(i) + "_" + std::to_string(j),
                                     {{rectangle(x, y, x + 8 + (i % 3), y + 8 + (j % 2)), {}}}));
    }
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> ux(kX - 5, kX + 245), uy(kY - 5, kY + 245);
  PointCloud points;
  std::vector<int> expected(footprints.size(), 0);
  for (int k = 0; k < 20000; ++k) {
    const Point3 p{ux(rng), uy(rng), 1.0};
    points.points.push_back(p);
    for (std::size_t f = 0; f < footprints.size(); ++f) {
      const Ring2& r = footprints[f].polygons[0].outer;
      if (p.x > r[0].x && p.x < r[1].x && p.y > r[0].y && p.y < r[2].y) ++expected[f];
    }
  }
  const auto inputs = crop(footprints, points);
  for (std::size_t f = 0; f < footprints.size(); ++f)
    EXPECT_EQ(inputs[f].points.size(), static_cast<std::size_t>(expected[f])) << f;
}

TEST(Crop, brute_force_agrees_with_the_grid_on_ground_buffers_and_on_presence_from_every_class) {
  // 36 L-shaped footprints 14 m apart: their 3 m ground buffers and 12 m wide boxes overlap their
  // neighbours'. Points on a 0.5 m lattice offset by 0.25 m (none on an edge), of classes 1, 2 and 6
  // in turn, and ground points exactly 3 m below a footprint's bottom edge and just beyond that.
  std::vector<Footprint> footprints;
  std::vector<std::pair<double, double>> corners;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) {
      corners.push_back({kX + 14.0 * i, kY + 14.0 * j});
      footprints.push_back(footprint(std::to_string(i) + "_" + std::to_string(j),
                                     {{l_shape(corners.back().first, corners.back().second), {}}}));
    }
  std::vector<Point3> points;
  std::vector<std::uint8_t> classes;
  const std::uint8_t cycle[] = {1, 2, 6};
  for (double x = kX - 14.75; x < kX + 14.0 * 6 + 14; x += 0.5)
    for (double y = kY - 14.75; y < kY + 14.0 * 6 + 14; y += 0.5) {
      points.push_back({x, y, static_cast<double>(points.size())});
      classes.push_back(cycle[points.size() % 3]);
    }
  for (const auto& [x0, y0] : corners)
    for (const double below : {3.0, 3.0 + 1e-9}) {
      points.push_back({x0 + 2.25, y0 - below, static_cast<double>(points.size())});
      classes.push_back(2);
    }
  CropParams params;
  params.min_ground_points = 1000000;  // the wide boxes' ground is kept: near ones first, then wide ones
  const auto inputs = crop(footprints, cloud(points, classes), params);

  // The L of corner (x0, y0): the 10 x 10 square without its top-right 5 x 5 quarter.
  const auto inside = [](double x, double y, double x0, double y0) {
    return x > x0 && x < x0 + 10 && y > y0 && y < y0 + 10 && !(x > x0 + 5 && y > y0 + 5);
  };
  const auto distance2 = [](double x, double y, double x0, double y0) {
    const double edges[6][4] = {{x0, y0, x0 + 10, y0},
                                {x0 + 10, y0, x0 + 10, y0 + 5},
                                {x0 + 5, y0 + 5, x0 + 10, y0 + 5},
                                {x0 + 5, y0 + 5, x0 + 5, y0 + 10},
                                {x0, y0 + 10, x0 + 5, y0 + 10},
                                {x0, y0, x0, y0 + 10}};
    double best = std::numeric_limits<double>::infinity();
    for (const auto& e : edges) {  // axis-aligned: the distance along each axis outside the segment
      const double dx = std::max({e[0] - x, 0.0, x - e[2]}), dy = std::max({e[1] - y, 0.0, y - e[3]});
      best = std::min(best, dx * dx + dy * dy);
    }
    return best;
  };
  std::size_t near_total = 0, exactly_at_the_buffer = 0;
  for (std::size_t f = 0; f < footprints.size(); ++f) {
    const auto [x0, y0] = corners[f];
    std::vector<double> building, near, wide;
    std::set<std::pair<std::int64_t, std::int64_t>> cells;
    for (std::size_t k = 0; k < points.size(); ++k) {
      const Point3& p = points[k];
      if (p.x >= x0 && p.x <= x0 + 10 && p.y >= y0 && p.y <= y0 + 10)
        cells.insert({static_cast<std::int64_t>(std::floor(p.x / 0.25)),
                      static_cast<std::int64_t>(std::floor(p.y / 0.25))});
      if (classes[k] == 6 && inside(p.x, p.y, x0, y0)) building.push_back(p.z);
      if (classes[k] != 2) continue;
      if (std::any_of(corners.begin(), corners.end(),
                      [&](const auto& c) { return inside(p.x, p.y, c.first, c.second); }))
        continue;
      if (p.x < x0 - 12 || p.x > x0 + 22 || p.y < y0 - 12 || p.y > y0 + 22) continue;
      const double d2 = distance2(p.x, p.y, x0, y0);
      (d2 <= 9.0 ? near : wide).push_back(p.z);
      exactly_at_the_buffer += d2 == 9.0;
    }
    near_total += near.size();
    std::vector<double> got_building;
    for (const Point3& q : inputs[f].points) got_building.push_back(q.z + inputs[f].origin.z);
    EXPECT_EQ(got_building, building) << footprints[f].id;
    near.insert(near.end(), wide.begin(), wide.end());
    EXPECT_EQ(inputs[f].ground_heights, near) << footprints[f].id;
    const PointPresence& presence = inputs[f].presence;
    std::size_t marked = 0;
    for (bool m : presence.marked) marked += m;
    EXPECT_EQ(marked, cells.size()) << footprints[f].id;
    for (const auto& [i, j] : cells)
      EXPECT_TRUE(presence.at(i, j)) << footprints[f].id << " " << i << " " << j;
  }
  EXPECT_GT(near_total, 1000u);
  EXPECT_GE(exactly_at_the_buffer, 36u);
}

// ---------------------------------------------------------------- LoD1 blocks

BuildingInput building(std::vector<Polygon2> polygons, double ground_z, std::vector<double> heights) {
  BuildingInput b;
  b.id = "b1";
  b.origin = {kX, kY, 0};
  b.footprint = footprint("b1", std::move(polygons));
  b.ground_z = ground_z;
  for (double z : heights) b.points.push_back({0, 0, z});
  return b;
}

Point3 newell_normal(const PolygonMesh& mesh, const std::vector<std::uint32_t>& face) {
  Point3 n;
  for (std::size_t k = 0; k < face.size(); ++k) {
    const Point3& a = mesh.vertices[face[k]];
    const Point3& b = mesh.vertices[face[(k + 1) % face.size()]];
    n.x += (a.y - b.y) * (a.z + b.z);
    n.y += (a.z - b.z) * (a.x + b.x);
    n.z += (a.x - b.x) * (a.y + b.y);
  }
  return n;
}

TEST(Lod1, a_square_block_has_six_faces_and_the_exact_volume) {
  const auto model = make_lod1_block(building({{rectangle(-5, -4, 5, 4), {}}}, 1.5, {11.5}));
  const MeshCheck check = check_mesh(model.mesh);
  EXPECT_EQ(check.face_count, 6u);
  EXPECT_TRUE(check.closed);
  EXPECT_TRUE(check.manifold);
  EXPECT_TRUE(check.outward);
  EXPECT_EQ(check.degenerate_faces, 0u);
  EXPECT_EQ(check.shell_count, 1u);
  EXPECT_NEAR(check.signed_volume, 80.0 * 10.0, 1e-9);
  EXPECT_EQ(model.origin.x, kX);
  EXPECT_EQ(model.id, "b1");
}

TEST(Lod1, the_roof_is_the_70th_percentile_of_the_point_heights) {
  std::vector<double> heights;
  for (int k = 0; k <= 100; ++k) heights.push_back(100.0 - k);  // 70th percentile = 70
  const auto model = make_lod1_block(building({{rectangle(0, 0, 4, 4), {}}}, 2.0, heights));
  double low = 1e9, high = -1e9;
  for (const Point3& v : model.mesh.vertices) {
    low = std::min(low, v.z);
    high = std::max(high, v.z);
  }
  EXPECT_DOUBLE_EQ(low, 2.0);
  EXPECT_DOUBLE_EQ(high, 70.0);
  EXPECT_NEAR(check_mesh(model.mesh).signed_volume, 16.0 * 68.0, 1e-9);
}

TEST(Lod1, a_roof_too_close_to_the_ground_is_raised_to_the_minimum_height) {
  const BuildingInput b = building({{rectangle(0, 0, 4, 4), {}}}, 3.0, {3.2, 3.1, 2.0});
  const Lod1Heights h = lod1_heights(b);
  EXPECT_DOUBLE_EQ(h.roof_z, 4.0);
  EXPECT_FALSE(h.note.empty());
  EXPECT_NEAR(check_mesh(make_lod1_block(b).mesh).signed_volume, 16.0, 1e-9);
}

TEST(Lod1, rejects_a_building_without_points) {
  try {
    make_lod1_block(building({{rectangle(0, 0, 4, 4), {}}}, 0.0, {}));
    FAIL() << "no exception";
  } catch (const ReconstructionError& e) {
    EXPECT_STREQ(e.what(), "lod1: building b1 has no points");
  }
}

TEST(Lod1, an_l_shaped_block_has_eight_faces_and_keeps_its_roof_in_one_piece) {
  const auto model = make_lod1_block(building({{l_shape(-5, -5), {}}}, 0.0, {6.0}));
  const MeshCheck check = check_mesh(model.mesh);
  EXPECT_EQ(check.face_count, 8u);
  EXPECT_TRUE(check.valid());
  EXPECT_NEAR(check.signed_volume, 75.0 * 6.0, 1e-9);
  const std::size_t hexagons = std::count_if(model.mesh.faces.begin(), model.mesh.faces.end(),
                                             [](const auto& f) { return f.size() == 6; });
  EXPECT_EQ(hexagons, 2u);  // roof and floor
}

TEST(Lod1, clockwise_input_rings_still_give_an_outward_solid) {
  const auto model = make_lod1_block(building({{reversed(l_shape(0, 0)), {}}}, 0.0, {6.0}));
  const MeshCheck check = check_mesh(model.mesh);
  EXPECT_TRUE(check.valid());
  EXPECT_NEAR(check.signed_volume, 75.0 * 6.0, 1e-9);
}

TEST(Lod1, a_block_with_a_hole_is_closed_and_its_courtyard_walls_face_the_courtyard) {
  const Ring2 hole = reversed(rectangle(-3, -2, 3, 2));
  const auto model = make_lod1_block(building({{rectangle(-10, -8, 10, 8), {hole}}}, 1.0, {9.0}));
  const MeshCheck check = check_mesh(model.mesh);
  EXPECT_TRUE(check.closed);
  EXPECT_TRUE(check.manifold);
  EXPECT_TRUE(check.outward);
  EXPECT_EQ(check.degenerate_faces, 0u);
  EXPECT_EQ(check.shell_count, 1u);
  EXPECT_NEAR(check.signed_volume, (320.0 - 24.0) * 8.0, 1e-9);

  // Walls along the courtyard (vertical faces with all vertices on the hole's boundary) point to its
  // centre (0, 0).
  std::size_t courtyard_walls = 0;
  for (const auto& face : model.mesh.faces) {
    const bool on_hole = std::all_of(face.begin(), face.end(), [&](std::uint32_t v) {
      const Point3& p = model.mesh.vertices[v];
      return std::abs(p.x) <= 3 && std::abs(p.y) <= 2;
    });
    const Point3 n = newell_normal(model.mesh, face);
    if (!on_hole || n.z != 0.0) continue;
    const Point3& a = model.mesh.vertices[face[0]];
    const Point3& b = model.mesh.vertices[face[1]];
    const double to_centre = n.x * (0 - 0.5 * (a.x + b.x)) + n.y * (0 - 0.5 * (a.y + b.y));
    EXPECT_GT(to_centre, 0.0);
    ++courtyard_walls;
  }
  EXPECT_EQ(courtyard_walls, 4u);
  // 8 walls plus the roof and floor split into convex pieces (never more than the 8 triangles).
  EXPECT_GE(check.face_count, 8u + 2u * 2u);
  EXPECT_LE(check.face_count, 8u + 2u * 8u);
}

TEST(Lod1, a_block_with_several_holes_splits_its_caps_into_convex_pieces_without_t_junctions) {
  // An irregular outer ring (with a collinear vertex) and three holes, one of them an L.
  const Ring2 outer{{-20, -10}, {0, -10}, {20, -10}, {25, 0}, {20, 12}, {-5, 15}, {-22, 5}};
  const Ring2 h1 = reversed(rectangle(-15, -5, -10, 0));
  const Ring2 h2 = reversed(l_shape(-4, -6));
  const Ring2 h3 = reversed({{12, -2}, {16, 0}, {13, 5}});
  const auto model = make_lod1_block(building({{outer, {h1, h2, h3}}}, 0.0, {5.0}));
  const MeshCheck check = check_mesh(model.mesh);
  EXPECT_TRUE(check.valid());
  EXPECT_EQ(check.non_manifold_vertices, 0u);
  const double area = ring_area(outer) + ring_area(h1) + ring_area(h2) + ring_area(h3);
  EXPECT_NEAR(check.signed_volume, area * 5.0, 1e-9);
  // Every roof piece is convex (counter-clockwise, all turns left).
  for (const auto& face : model.mesh.faces) {
    if (newell_normal(model.mesh, face).z <= 0.0) continue;
    for (std::size_t k = 0; k < face.size(); ++k) {
      const Point3& a = model.mesh.vertices[face[k]];
      const Point3& b = model.mesh.vertices[face[(k + 1) % face.size()]];
      const Point3& c = model.mesh.vertices[face[(k + 2) % face.size()]];
      EXPECT_GT((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x), 0.0);
    }
  }
}

TEST(Lod1, a_multipolygon_gives_one_closed_shell_per_polygon) {
  const auto model =
      make_lod1_block(building({{rectangle(-10, -5, -2, 5), {}}, {l_shape(2, -5), {}}}, 0.0, {3.0}));
  const MeshCheck check = check_mesh(model.mesh);
  EXPECT_TRUE(check.valid());
  EXPECT_EQ(check.shell_count, 2u);
  EXPECT_EQ(check.face_count, 6u + 8u);
  EXPECT_NEAR(check.signed_volume, (80.0 + 75.0) * 3.0, 1e-9);
}

TEST(Lod1, rejects_a_ring_with_fewer_than_three_distinct_vertices) {
  EXPECT_THROW(make_lod1_block(building({{{{0, 0}, {1, 0}, {1, 0}, {0, 0}}, {}}}, 0.0, {3.0})),
               ReconstructionError);
}

// ---------------------------------------------------------------- mesh checks

PolygonMesh unit_cube() { return make_lod1_block(building({{rectangle(0, 0, 1, 1), {}}}, 0.0, {1.0})).mesh; }

TEST(MeshCheck, an_open_box_is_not_closed) {
  PolygonMesh mesh = unit_cube();
  mesh.faces.pop_back();
  const MeshCheck check = check_mesh(mesh);
  EXPECT_FALSE(check.closed);
  EXPECT_EQ(check.boundary_edges, 4u);
  EXPECT_TRUE(check.manifold);
}

TEST(MeshCheck, a_flipped_face_breaks_closure_and_an_inverted_box_is_not_outward) {
  PolygonMesh flipped = unit_cube();
  std::reverse(flipped.faces[0].begin(), flipped.faces[0].end());
  const MeshCheck one = check_mesh(flipped);
  EXPECT_FALSE(one.closed);
  EXPECT_FALSE(one.manifold);

  PolygonMesh inverted = unit_cube();
  for (auto& f : inverted.faces) std::reverse(f.begin(), f.end());
  const MeshCheck all = check_mesh(inverted);
  EXPECT_TRUE(all.closed);
  EXPECT_FALSE(all.outward);
  EXPECT_NEAR(all.signed_volume, -1.0, 1e-12);
}

TEST(MeshCheck, two_cubes_sharing_only_a_vertex_make_a_non_manifold_vertex) {
  PolygonMesh mesh = unit_cube();
  const PolygonMesh other = make_lod1_block(building({{rectangle(1, 1, 2, 2), {}}}, 1.0, {2.0})).mesh;
  // Weld the other cube's corner (1, 1, 1) onto this cube's vertex (1, 1, 1).
  std::uint32_t shared = 0;
  for (std::uint32_t v = 0; v < mesh.vertices.size(); ++v)
    if (mesh.vertices[v].x == 1 && mesh.vertices[v].y == 1 && mesh.vertices[v].z == 1) shared = v;
  const auto offset = static_cast<std::uint32_t>(mesh.vertices.size());
  mesh.vertices.insert(mesh.vertices.end(), other.vertices.begin(), other.vertices.end());
  for (auto face : other.faces) {
    for (auto& v : face) {
      const Point3& p = other.vertices[v];
      v = (p.x == 1 && p.y == 1 && p.z == 1) ? shared : v + offset;
    }
    mesh.faces.push_back(face);
  }
  const MeshCheck check = check_mesh(mesh);
  EXPECT_TRUE(check.closed);
  EXPECT_EQ(check.non_manifold_vertices, 1u);
  EXPECT_FALSE(check.manifold);
  EXPECT_EQ(check.shell_count, 2u);
}

TEST(MeshCheck, signed_volume_alone_is_check_meshs_number_bit_for_bit) {
  // The levels' volumes come from signed_volume(): the same sum in the same order as check_mesh's.
  std::vector<PolygonMesh> meshes{PolygonMesh{}, unit_cube()};
  PolygonMesh far_away = make_lod1_block(building({{l_shape(85012.3, 447001.7), {}}}, 0.37, {9.81})).mesh;
  meshes.push_back(far_away);
  PolygonMesh broken = far_away;
  broken.faces.push_back({0, 1, 999});  // out of range: left out by both
  std::reverse(broken.faces[1].begin(), broken.faces[1].end());
  meshes.push_back(broken);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  for (int m = 0; m < 20; ++m) {  // polygon soups of random faces: no topology to speak of
    PolygonMesh soup;
    for (int v = 0; v < 30; ++v) soup.vertices.push_back({1000.0 + u(rng), 2000.0 + u(rng), u(rng)});
    for (int f = 0; f < 25; ++f) {
      std::vector<std::uint32_t> face;
      for (int k = 0; k < 3 + f % 4; ++k) face.push_back(static_cast<std::uint32_t>(rng() % 30));
      soup.faces.push_back(face);
    }
    meshes.push_back(soup);
  }
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    const double alone = signed_volume(meshes[m]), checked = check_mesh(meshes[m]).signed_volume;
    EXPECT_EQ(std::memcmp(&alone, &checked, sizeof(double)), 0)
        << "mesh " << m << ": " << alone << " against " << checked;
  }
  EXPECT_NEAR(signed_volume(unit_cube()), 1.0, 1e-12);
}

TEST(MeshCheck, counts_degenerate_faces) {
  PolygonMesh mesh = unit_cube();
  mesh.faces.push_back({0, 1});
  mesh.faces.push_back({0, 1, 1});
  mesh.faces.push_back({0, 1, 999});
  EXPECT_EQ(check_mesh(mesh).degenerate_faces, 3u);
}

// ---------------------------------------------------------------- real data (needs the readers)

#ifndef CITY3D_NO_IO
TEST(CropRealData, the_delft_block_gives_every_footprint_points_and_a_valid_block) {
  const std::string dir = std::string(CITY3D_SHARED_DATA) + "/ahn3_delft/";
  try {
    FootprintSet set = read_footprints(dir + "footprints/bgt_pand_laz_area.gpkg");
    ASSERT_EQ(set.footprints.size(), 160u);
    Cropper cropper(std::move(set.footprints));
    for (const char* tile : {"ahn3_cropped_1.las", "ahn3_cropped_2.las"}) {
      auto reader = open_point_cloud(dir + tile, kFieldClassification);
      PointCloud chunk;
      while (true) {
        chunk.points.clear();
        chunk.classification.clear();
        if (reader->read(chunk, 100000) == 0) break;
        cropper.add(chunk);
      }
    }
    EXPECT_EQ(cropper.stats().points_seen, 640510u + 208432u);
    const auto inputs = cropper.finish();
    ASSERT_EQ(inputs.size(), 160u);
    std::size_t building_points = 0, valid = 0, with_ground = 0, with_points = 0;
    for (const BuildingInput& b : inputs) {
      building_points += b.points.size();
      with_ground += b.ground_method == "ground percentile" ? 1 : 0;
      if (b.points.empty()) continue;
      ++with_points;
      if (check_mesh(make_lod1_block(b).mesh).valid()) ++valid;
    }
    // 76,818 of the 280,065 building-class points lie inside the 8,654 m2 of footprints (the tiles
    // hold more buildings than the block); the band allows small changes in the readers.
    EXPECT_GT(building_points, 75000u);
    EXPECT_LT(building_points, 78500u);
    EXPECT_EQ(with_points, 160u);
    EXPECT_EQ(with_ground, 160u);
    EXPECT_EQ(valid, 160u);
  } catch (const Error& e) {
    if (std::string(e.what()).find("not implemented") != std::string::npos) GTEST_SKIP() << e.what();
    throw;
  }
}
#endif

}  // namespace
}  // namespace city3d

namespace city3d {
namespace {

// Roof faces only (all make_lod13_blocks reads of an LoD2 model): three flat 10 x 10 m parts, A at
// 10 m, B east of A at 4 m, C north of A at 9 m.
BuildingModel three_roof_parts() {
  BuildingModel m;
  m.id = "steps";
  const auto square = [&m](double x, double y, double z) {
    const auto b = static_cast<std::uint32_t>(m.mesh.vertices.size());
    for (auto [dx, dy] : {std::pair{0.0, 0.0}, {10.0, 0.0}, {10.0, 10.0}, {0.0, 10.0}})
      m.mesh.vertices.push_back({x + dx, y + dy, z});
    m.mesh.faces.push_back({b, b + 1, b + 2, b + 3});
    m.surfaces.push_back(SurfaceType::roof);
  };
  square(0, 0, 10);
  square(10, 0, 4);
  square(0, 10, 9);
  return m;
}

TEST(Lod13, parts_within_the_step_height_become_one_block_and_a_step_wall_separates_the_others) {
  const BuildingModel blocks = make_lod13_blocks(three_roof_parts(), {}, 0.0, 3.0);
  EXPECT_TRUE(validate_model(blocks.mesh).empty()) << validity_codes(validate_model(blocks.mesh));
  // A and C (1 m apart) are one cluster at their area-weighted mean height, B (5.5 m lower) another.
  std::vector<double> roofs;
  for (std::size_t f = 0; f < blocks.mesh.faces.size(); ++f)
    if (blocks.surfaces[f] == SurfaceType::roof) roofs.push_back(blocks.mesh.vertices[blocks.mesh.faces[f][0]].z);
  std::sort(roofs.begin(), roofs.end());
  ASSERT_EQ(roofs.size(), 2u);  // A and C merged into one roof face
  EXPECT_DOUBLE_EQ(roofs[0], 4.0);
  EXPECT_DOUBLE_EQ(roofs[1], 9.5);
  EXPECT_NEAR(check_mesh(blocks.mesh).signed_volume, 200 * 9.5 + 100 * 4.0, 1e-9);
  // A step wall from 4 m to 9.5 m on x = 10 between A and B.
  bool step = false;
  for (std::size_t f = 0; f < blocks.mesh.faces.size(); ++f) {
    if (blocks.surfaces[f] != SurfaceType::wall) continue;
    double lo = 1e9, hi = -1e9, xmin = 1e9, xmax = -1e9;
    for (auto v : blocks.mesh.faces[f]) {
      const Point3& p = blocks.mesh.vertices[v];
      lo = std::min(lo, p.z), hi = std::max(hi, p.z), xmin = std::min(xmin, p.x), xmax = std::max(xmax, p.x);
    }
    step = step || (lo == 4.0 && hi == 9.5 && xmin == 10.0 && xmax == 10.0);
  }
  EXPECT_TRUE(step);
}

TEST(Lod13, an_infinite_step_gives_one_block_the_lod12) {
  const BuildingModel block = make_lod13_blocks(three_roof_parts(), {}, 0.0, std::numeric_limits<double>::infinity());
  EXPECT_TRUE(validate_model(block.mesh).empty());
  std::size_t roofs = 0, floors = 0;
  for (SurfaceType t : block.surfaces) roofs += t == SurfaceType::roof, floors += t == SurfaceType::ground;
  EXPECT_EQ(roofs, 1u);
  EXPECT_EQ(floors, 1u);
  EXPECT_NEAR(check_mesh(block.mesh).signed_volume, 300 * (10.0 + 4.0 + 9.0) / 3.0, 1e-9);
}

TEST(Lod13, part_heights_come_from_the_points_above_them) {
  // Points over B at 6 m (its roof face says 4): B's block follows the points.
  std::vector<Point3> points;
  for (int i = 0; i < 10; ++i) points.push_back({12.0 + 0.5 * i, 5.0, 6.0});
  const BuildingModel blocks = make_lod13_blocks(three_roof_parts(), points, 0.0, 3.0);
  double b_roof = 0;
  for (std::size_t f = 0; f < blocks.mesh.faces.size(); ++f)
    if (blocks.surfaces[f] == SurfaceType::roof && blocks.mesh.vertices[blocks.mesh.faces[f][0]].x >= 10.0)
      b_roof = blocks.mesh.vertices[blocks.mesh.faces[f][0]].z;
  EXPECT_DOUBLE_EQ(b_roof, 6.0);
}

// Parts merged into one cluster stand at the percentile of all their points together, not of one
// part's: A's ten points at 10.0-10.9 m and C's five at 9.0-9.4 m make one block (1 m apart, under the
// 3 m step) at the 70th percentile of the fifteen; B's points at 4 m keep B apart.
TEST(Lod13, a_cluster_stands_at_the_percentile_of_all_its_parts_points) {
  std::vector<Point3> points;
  std::vector<double> a_and_c;
  for (int i = 0; i < 10; ++i)
    points.push_back({1.0 + 0.8 * i, 5.0, 10.0 + 0.1 * i}), a_and_c.push_back(points.back().z);
  for (int i = 0; i < 5; ++i)
    points.push_back({2.0 + 1.5 * i, 15.0, 9.0 + 0.1 * i}), a_and_c.push_back(points.back().z);
  for (int i = 0; i < 6; ++i) points.push_back({12.0 + 1.0 * i, 5.0, 4.0});
  const BuildingModel blocks = make_lod13_blocks(three_roof_parts(), points, 0.0, 3.0);
  std::set<double> roofs;
  for (std::size_t f = 0; f < blocks.mesh.faces.size(); ++f)
    if (blocks.surfaces[f] == SurfaceType::roof)
      roofs.insert(blocks.mesh.vertices[blocks.mesh.faces[f][0]].z);
  ASSERT_EQ(roofs.size(), 2u);
  EXPECT_EQ(*roofs.begin(), 4.0);
  EXPECT_EQ(*roofs.rbegin(), percentile(a_and_c, 70.0));
}

TEST(Lod13, roof_parts_made_once_give_both_levels_as_the_model_does) {
  std::vector<Point3> points;
  for (int i = 0; i < 10; ++i) points.push_back({12.0 + 0.5 * i, 5.0, 6.0});  // over B
  points.push_back({5.0, 15.0, 9.25});                                          // over C
  const Lod13Parts parts = lod13_parts(three_roof_parts(), points);
  ASSERT_EQ(parts.parts.size(), 3u);
  ASSERT_EQ(parts.part_z.size(), 3u);
  EXPECT_TRUE(parts.part_z[0].empty());  // A: no point above it
  EXPECT_EQ(parts.part_z[1].size(), 10u);
  EXPECT_EQ(parts.part_z[2], std::vector<double>{9.25});
  // A touches B (x = 10) and C (y = 10); B and C meet at the corner (10, 10) only.
  const std::set<std::pair<std::size_t, std::size_t>> adjacent{{0, 1}, {0, 2}};
  EXPECT_EQ(parts.adjacent, adjacent);
  for (const double step : {3.0, std::numeric_limits<double>::infinity()}) {
    const BuildingModel once = make_lod13_blocks(parts, 0.0, step);
    const BuildingModel whole = make_lod13_blocks(three_roof_parts(), points, 0.0, step);
    EXPECT_EQ(once.mesh.vertices.size(), whole.mesh.vertices.size());
    EXPECT_EQ(once.mesh.faces, whole.mesh.faces);
    EXPECT_EQ(once.surfaces, whole.surfaces);
    for (std::size_t v = 0; v < std::min(once.mesh.vertices.size(), whole.mesh.vertices.size()); ++v)
      EXPECT_EQ(once.mesh.vertices[v].z, whole.mesh.vertices[v].z);
  }
  EXPECT_THROW(lod13_parts(BuildingModel{}, points), ReconstructionError);
}

// Roof faces (flat, counter-clockwise) from plan-view loops at their heights.
BuildingModel roof_faces(const std::vector<std::pair<std::vector<Point2>, double>>& faces) {
  BuildingModel m;
  m.id = "faces";
  for (const auto& [loop, z] : faces) {
    std::vector<std::uint32_t> face;
    for (const Point2& p : loop) {
      face.push_back(static_cast<std::uint32_t>(m.mesh.vertices.size()));
      m.mesh.vertices.push_back({p.x, p.y, z});
    }
    m.mesh.faces.push_back(std::move(face));
    m.surfaces.push_back(SurfaceType::roof);
  }
  return m;
}

bool has_code(const std::vector<ValidityError>& errors, int code) {
  return std::any_of(errors.begin(), errors.end(), [code](const ValidityError& e) { return e.code == code; });
}

// The heights of a block model's roof faces.
std::set<double> roof_heights(const BuildingModel& blocks) {
  std::set<double> roofs;
  for (std::size_t f = 0; f < blocks.mesh.faces.size(); ++f)
    if (blocks.surfaces[f] == SurfaceType::roof)
      roofs.insert(blocks.mesh.vertices[blocks.mesh.faces[f][0]].z);
  return roofs;
}

// Two roof parts whose shared wall bends 1 mm into the lower one (two walls nearly in line, as an LoD2
// model can have them): more than the half millimetre that joins parts by default, so they share no
// edge, and the blocks have a sliver between them, walled on both sides. Joined within 1 cm, they are
// neighbours and the blocks are one valid solid.
TEST(Lod13, parts_a_millimetre_apart_are_joined_within_the_join_distance) {
  const BuildingModel model = roof_faces({{{{0, 0}, {10, 0}, {10, 10}, {0, 10}}, 10.0},
                                          {{{10, 0}, {20, 0}, {20, 10}, {10, 10}, {10.001, 5}}, 4.0}});
  const Lod13Parts apart = lod13_parts(model, {});
  EXPECT_TRUE(apart.adjacent.empty());
  EXPECT_FALSE(validate_model(make_lod13_blocks(apart, 0.0, 3.0).mesh).empty());

  const Lod13Parts joined = lod13_parts(model, {}, 0.01);
  EXPECT_EQ(joined.adjacent, (std::set<std::pair<std::size_t, std::size_t>>{{0, 1}}));
  ASSERT_EQ(joined.parts.size(), 2u);
  EXPECT_EQ(joined.parts[0].size(), 5u);  // the bend's vertex is on the taller part's edge too
  for (const double step : {3.0, std::numeric_limits<double>::infinity()}) {
    const BuildingModel blocks = make_lod13_blocks(joined, 0.0, step);
    EXPECT_TRUE(validate_model(blocks.mesh).empty()) << validity_codes(validate_model(blocks.mesh));
  }
  const BuildingModel blocks = make_lod13_blocks(joined, 0.0, 3.0);
  EXPECT_NEAR(check_mesh(blocks.mesh).signed_volume, 100.005 * 10.0 + 99.995 * 4.0, 1e-6);
}

// A part's corner 2-3 mm inside another's corner is within the join distance of both its edges
// there; splitting both would fold the part onto itself (a zero-width spike). A vertex as near an
// end of an edge is a corner of its own and splits nothing.
TEST(Lod13, a_vertex_near_a_corner_does_not_split_the_edges_there) {
  const BuildingModel model = roof_faces(
      {{{{0, 0}, {10, 0}, {10, 10}, {0, 10}}, 10.0}, {{{9.997, 0.002}, {20, 0}, {20, 10}, {10, 10}}, 4.0}});
  const Lod13Parts joined = lod13_parts(model, {}, 0.01);
  for (const auto& loop : joined.parts) {
    std::set<std::uint32_t> distinct(loop.begin(), loop.end());
    EXPECT_EQ(distinct.size(), loop.size());
  }
}

// Around (10, 10): A, B, A, B by height (A's parts joined round the top and the right, B's two
// parts diagonal). Four step walls meet on the vertical edge there; with no_overlapping_walls the B
// part across the least of them, the first of equals, joins A.
TEST(Lod13, a_cluster_meeting_itself_at_a_vertex_takes_in_a_part_between) {
  const BuildingModel model = roof_faces({
      {{{0, 10}, {10, 10}, {10, 20}, {0, 20}}, 10.0},                      // 0: A
      {{{10, 10}, {20, 10}, {20, 20}, {10, 20}}, 4.0},                     // 1: B
      {{{0, 0}, {10, 0}, {10, 10}, {0, 10}}, 4.0},                         // 2: B
      {{{10, 0}, {20, 0}, {20, 10}, {10, 10}}, 10.0},                      // 3: A
      {{{0, 20}, {10, 20}, {20, 20}, {30, 20}, {30, 30}, {0, 30}}, 10.0},  // 4: A
      {{{20, 0}, {30, 0}, {30, 20}, {20, 20}, {20, 10}}, 10.0},            // 5: A
  });
  const Lod13Parts parts = lod13_parts(model, {});
  const BuildingModel pinched = make_lod13_blocks(parts, 0.0, 3.0);
  EXPECT_TRUE(has_code(validate_model(pinched.mesh), 304)) << validity_codes(validate_model(pinched.mesh));

  const BuildingModel blocks = make_lod13_blocks(parts, 0.0, 3.0, 70.0, 1.0, true);
  EXPECT_TRUE(validate_model(blocks.mesh).empty()) << validity_codes(validate_model(blocks.mesh));
  // A with part 1: its parts' mean heights weighted by area, (700 x 10 + 100 x 4) / 800.
  EXPECT_EQ(roof_heights(blocks), (std::set<double>{4.0, 9.25}));
  EXPECT_NEAR(check_mesh(blocks.mesh).signed_volume, 800 * 9.25 + 100 * 4.0, 1e-9);
  // Where no cluster meets itself so, the flag changes nothing.
  const BuildingModel plain = make_lod13_blocks(three_roof_parts(), {}, 0.0, 3.0);
  const BuildingModel flagged =
      make_lod13_blocks(lod13_parts(three_roof_parts(), {}), 0.0, 3.0, 70.0, 1.0, true);
  EXPECT_EQ(plain.mesh.faces, flagged.mesh.faces);
}

// Around (10, 10): 10, 2, 6, 2 m, four clusters (no two adjacent parts within the 3 m step). No cluster
// meets itself, but the walls from 2 m up to 10 m and up to 6 m overlap on the column there, four of
// them from 2 to 6 m. The part across the least wall (the 2 m part beside the 6 m one, the first of
// equals) joins the 6 m part's cluster.
TEST(Lod13, walls_that_overlap_four_deep_on_a_column_are_undone_by_joining_the_part_across_the_least) {
  const BuildingModel model = roof_faces({
      {{{0, 10}, {10, 10}, {10, 20}, {0, 20}}, 10.0},   // 0
      {{{10, 10}, {20, 10}, {20, 20}, {10, 20}}, 2.0},  // 1
      {{{0, 0}, {10, 0}, {10, 10}, {0, 10}}, 2.0},      // 2
      {{{10, 0}, {20, 0}, {20, 10}, {10, 10}}, 6.0},    // 3
  });
  const Lod13Parts parts = lod13_parts(model, {});
  EXPECT_TRUE(has_code(validate_model(make_lod13_blocks(parts, 0.0, 3.0).mesh), 304));
  const BuildingModel blocks = make_lod13_blocks(parts, 0.0, 3.0, 70.0, 1.0, true);
  EXPECT_TRUE(validate_model(blocks.mesh).empty()) << validity_codes(validate_model(blocks.mesh));
  // Parts 1 and 3: (100 x 2 + 100 x 6) / 200.
  EXPECT_EQ(roof_heights(blocks), (std::set<double>{2.0, 4.0, 10.0}));
  EXPECT_NEAR(check_mesh(blocks.mesh).signed_volume, 100 * 10.0 + 200 * 4.0 + 100 * 2.0, 1e-9);
}

}  // namespace
}  // namespace city3d
