// Tests of the polyline, regularisation and wall stages on synthetic edge pixels: outlines and step
// lines rasterised at r = 0.2 m with jitter and outliers (fixed seeds).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "city3d/debug_output.hpp"
#include "city3d/error.hpp"
#include "city3d/polylines.hpp"
#include "city3d/regularise.hpp"
#include "city3d/walls.hpp"

using namespace city3d;

namespace {

constexpr double kR = 0.2;  // pixel size, metres

using Line = std::pair<Point2, Point2>;

// Pixels (centres) crossed by the lines, as a Canny detector would mark them, with Gaussian jitter.
std::vector<Point2> rasterise(const std::vector<Line>& lines, double jitter, unsigned seed) {
  std::set<std::pair<long, long>> cells;
  for (const auto& [a, b] : lines) {
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    const int n = static_cast<int>(std::ceil(len / (0.25 * kR)));
    for (int k = 0; k <= n; ++k) {
      const double t = static_cast<double>(k) / n;
      cells.insert({static_cast<long>(std::floor((a.x + t * (b.x - a.x)) / kR)),
                    static_cast<long>(std::floor((a.y + t * (b.y - a.y)) / kR))});
    }
  }
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, jitter);
  std::vector<Point2> pixels;
  for (const auto& [i, j] : cells)
    pixels.push_back({(i + 0.5) * kR + noise(rng), (j + 0.5) * kR + noise(rng)});
  return pixels;
}

std::vector<Line> ring_lines(const Ring2& ring) {
  std::vector<Line> lines;
  for (std::size_t i = 0; i < ring.size(); ++i) lines.push_back({ring[i], ring[(i + 1) % ring.size()]});
  return lines;
}

// Off-grid coordinates so that no line runs exactly along pixel borders.
const Ring2 kRectangle{{0.07, 0.11}, {12.07, 0.11}, {12.07, 8.11}, {0.07, 8.11}};
const Ring2 kLShape{{0.07, 0.11}, {12.07, 0.11}, {12.07, 5.11}, {6.07, 5.11}, {6.07, 10.11}, {0.07, 10.11}};
// A 12 x 8 rectangle with a 1.5 x 1.5 notch cut into its top edge between x = 5.07 and 6.57.
const Ring2 kNotched{{0.07, 0.11}, {12.07, 0.11}, {12.07, 8.11}, {6.57, 8.11},
                     {6.57, 6.61}, {5.07, 6.61},  {5.07, 8.11},  {0.07, 8.11}};

double dist(const Point2& a, const Point2& b) { return std::hypot(a.x - b.x, a.y - b.y); }

double point_segment_distance(const Point2& p, const Point2& a, const Point2& b) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double len2 = dx * dx + dy * dy;
  const double t = len2 > 0 ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / len2, 0.0, 1.0) : 0.0;
  return std::hypot(p.x - a.x - t * dx, p.y - a.y - t * dy);
}

double distance_to_polylines(const Point2& p, const std::vector<Polyline2>& lines) {
  double best = 1e300;
  for (const auto& l : lines)
    for (std::size_t i = 1; i < l.size(); ++i)
      best = std::min(best, point_segment_distance(p, l[i - 1], l[i]));
  return best;
}

double distance_to_pixels(const Point2& p, const std::vector<Point2>& pixels) {
  double best = 1e300;
  for (const auto& q : pixels) best = std::min(best, dist(p, q));
  return best;
}

// The distinct vertices of a closed polyline (without the repeated closing vertex).
std::vector<Point2> corners_of(const Polyline2& closed) { return {closed.begin(), closed.end() - 1}; }

// Every true corner has a vertex within tol, and every vertex is within tol of a true corner.
void expect_corners_match(const std::vector<Point2>& got, const Ring2& truth, double tol) {
  ASSERT_EQ(got.size(), truth.size());
  for (const auto& c : truth) {
    double best = 1e300;
    for (const auto& v : got) best = std::min(best, dist(c, v));
    EXPECT_LE(best, tol) << "corner (" << c.x << ", " << c.y << ")";
  }
  for (const auto& v : got) {
    double best = 1e300;
    for (const auto& c : truth) best = std::min(best, dist(c, v));
    EXPECT_LE(best, tol) << "vertex (" << v.x << ", " << v.y << ")";
  }
}

double seg_len(const Segment2& s) { return dist(s.a, s.b); }

Point2 unit(const Segment2& s) {
  const double l = seg_len(s);
  return {(s.b.x - s.a.x) / l, (s.b.y - s.a.y) / l};
}

bool inside(const Ring2& r, const Point2& p) {
  bool in = false;
  for (std::size_t i = 0, j = r.size() - 1; i < r.size(); j = i++)
    if ((r[i].y > p.y) != (r[j].y > p.y) &&
        p.x < (r[j].x - r[i].x) * (p.y - r[i].y) / (r[j].y - r[i].y) + r[i].x)
      in = !in;
  return in;
}

std::vector<Polygon2> footprint_of(const Ring2& outer) { return {Polygon2{outer, {}}}; }

}  // namespace

// ---------------------------------------------------------------------------------------------
// Polylines

TEST(Polylines, rectangle_outline_gives_one_closed_polyline_with_four_corners) {
  const auto pixels = rasterise(ring_lines(kRectangle), 0.02, 1);
  PolylineParams params;
  const auto lines = extract_polylines(pixels, params);
  ASSERT_EQ(lines.size(), 1u);
  ASSERT_TRUE(is_closed(lines[0]));
  expect_corners_match(corners_of(lines[0]), kRectangle, 0.25);
  for (const auto& v : lines[0]) EXPECT_LE(distance_to_pixels(v, pixels), params.max_hausdorff);
}

TEST(Polylines, l_shape_outline_gives_six_corners) {
  const auto pixels = rasterise(ring_lines(kLShape), 0.02, 2);
  const auto lines = extract_polylines(pixels, PolylineParams{});
  ASSERT_EQ(lines.size(), 1u);
  ASSERT_TRUE(is_closed(lines[0]));
  expect_corners_match(corners_of(lines[0]), kLShape, 0.25);
}

TEST(Polylines, every_pixel_stays_within_the_hausdorff_bound_of_the_polylines) {
  const auto pixels = rasterise(ring_lines(kLShape), 0.03, 3);
  PolylineParams params;
  PolylineStats stats;
  const auto lines = extract_polylines(pixels, params, &stats);
  double worst = 0;
  for (const auto& p : pixels) worst = std::max(worst, distance_to_polylines(p, lines));
  EXPECT_LE(worst, params.max_hausdorff);
  EXPECT_LE(stats.max_pixel_distance, params.max_hausdorff);
  EXPECT_NEAR(stats.resolution, kR, 0.05);
  EXPECT_GT(stats.collapses, pixels.size() / 2);
}

TEST(Polylines, a_diagonal_outline_is_simplified_despite_its_staircase) {
  // A rectangle rotated by 30 degrees: its pixels form staircases, still 4 corners.
  Ring2 rotated;
  const double c = std::cos(kPi / 6), s = std::sin(kPi / 6);
  for (const auto& p : kRectangle) rotated.push_back({20 + c * p.x - s * p.y, 3 + s * p.x + c * p.y});
  const auto pixels = rasterise(ring_lines(rotated), 0.02, 4);
  const auto lines = extract_polylines(pixels, PolylineParams{});
  ASSERT_EQ(lines.size(), 1u);
  ASSERT_TRUE(is_closed(lines[0]));
  expect_corners_match(corners_of(lines[0]), rotated, 0.3);
}

TEST(Polylines, isolated_outlier_pixels_produce_no_polyline) {
  std::vector<Point2> outliers{{30.1, 30.1}, {-20.3, 4.1}, {40.5, -10.1}, {25.1, 25.3}, {25.3, 25.1}};
  EXPECT_TRUE(extract_polylines(outliers, PolylineParams{}).empty());

  auto pixels = rasterise(ring_lines(kRectangle), 0.02, 5);
  pixels.insert(pixels.end(), outliers.begin(), outliers.end());
  const auto lines = extract_polylines(pixels, PolylineParams{});
  ASSERT_EQ(lines.size(), 1u);
  for (const auto& v : lines[0]) EXPECT_LT(v.x, 13.0);
}

TEST(Polylines, result_does_not_depend_on_pixel_order) {
  auto pixels = rasterise(ring_lines(kLShape), 0.03, 6);
  const auto first = extract_polylines(pixels, PolylineParams{});
  std::mt19937 rng(7);
  std::shuffle(pixels.begin(), pixels.end(), rng);
  const auto second = extract_polylines(pixels, PolylineParams{});
  ASSERT_EQ(first.size(), second.size());
  for (std::size_t i = 0; i < first.size(); ++i) {
    ASSERT_EQ(first[i].size(), second[i].size());
    for (std::size_t k = 0; k < first[i].size(); ++k) {
      EXPECT_EQ(first[i][k].x, second[i][k].x);
      EXPECT_EQ(first[i][k].y, second[i][k].y);
    }
  }
}

// Relocation's numbers are the ones it uses: without the corner placement (a corner angle no corner
// reaches) or held in place (a pull a million times the pixels' weight), the staircase rectangle's
// polyline is another.
TEST(Polylines, relocations_numbers_change_the_polyline) {
  Ring2 rotated;
  const double c = std::cos(kPi / 6), s = std::sin(kPi / 6);
  for (const auto& p : kRectangle) rotated.push_back({20 + c * p.x - s * p.y, 3 + s * p.x + c * p.y});
  const auto pixels = rasterise(ring_lines(rotated), 0.02, 4);
  const auto same = [](const std::vector<Polyline2>& a, const std::vector<Polyline2>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (a[i].size() != b[i].size()) return false;
      for (std::size_t k = 0; k < a[i].size(); ++k)
        if (a[i][k].x != b[i][k].x || a[i][k].y != b[i][k].y) return false;
    }
    return true;
  };
  const auto defaults = extract_polylines(pixels, PolylineParams{});
  PolylineParams changed;
  changed.corner_min_sine = 0.999;
  EXPECT_FALSE(same(defaults, extract_polylines(pixels, changed))) << "corner_min_sine";
  changed = {};
  changed.relocate_pull = 1e6;
  EXPECT_FALSE(same(defaults, extract_polylines(pixels, changed))) << "relocate_pull";
  changed = {};
  changed.relocate_rounds = 100;
  EXPECT_TRUE(same(defaults, extract_polylines(pixels, changed))) << "the rounds stop when nothing collapses";
}

TEST(Polylines, rejects_invalid_parameters_listing_every_problem) {
  PolylineParams params;
  params.max_hausdorff = 0;
  params.link_pixels = 0.5;
  try {
    extract_polylines({}, params);
    FAIL() << "no exception";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("max_hausdorff"), std::string::npos) << what;
    EXPECT_NE(what.find("link_pixels"), std::string::npos) << what;
  }
  params = {};
  params.relocate_pull = 0;
  params.corner_min_sine = 1;
  params.relocate_rounds = 0;
  try {
    extract_polylines({}, params);
    FAIL() << "no exception";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    for (const char* name :
         {"relocate_pull must be > 0", "corner_min_sine must be in [0, 1)", "relocate_rounds must be >= 1"})
      EXPECT_NE(what.find(name), std::string::npos) << what;
    EXPECT_EQ(what.find("max_hausdorff"), std::string::npos) << what;
  }
}

TEST(Polylines, obj_writer_writes_vertices_and_closed_line) {
  const auto path = std::filesystem::temp_directory_path() / "city3d_test_polylines.obj";
  write_polylines_obj(path.string(), {{{0, 0}, {1, 0}, {1, 1}, {0, 0}}, {{5, 5}, {6, 5}}}, 2.0);
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_EQ(ss.str(),
            "# city3d polylines: 2\nv 0 0 2\nv 1 0 2\nv 1 1 2\nl 1 2 3 1\nv 5 5 2\nv 6 5 2\nl 4 5\n");
  std::filesystem::remove(path);
}

// ---------------------------------------------------------------------------------------------
// Regularisation

TEST(Regularise, noisy_directions_come_out_exactly_parallel_or_orthogonal) {
  // A quadrilateral whose edges are 3 to 8 degrees off a 12 x 8 rectangle's.
  const double off[4] = {5, -3, 8, -6};  // degrees, per edge
  const Point2 mid[4] = {{6, 0}, {12, 4}, {6, 8}, {0, 4}};
  const double base[4] = {0, 90, 180, 270};
  Point2 dirs[4];
  for (int i = 0; i < 4; ++i) {
    const double t = (base[i] + off[i]) * kPi / 180;
    dirs[i] = {std::cos(t), std::sin(t)};
  }
  auto intersect = [&](int i, int j) {  // lines mid[i] + s dirs[i] and mid[j] + u dirs[j]
    const double det = dirs[i].x * -dirs[j].y + dirs[i].y * dirs[j].x;
    const double rx = mid[j].x - mid[i].x, ry = mid[j].y - mid[i].y;
    const double s = (rx * -dirs[j].y + ry * dirs[j].x) / det;
    return Point2{mid[i].x + s * dirs[i].x, mid[i].y + s * dirs[i].y};
  };
  Polyline2 quad;
  for (int i = 0; i < 4; ++i) quad.push_back(intersect((i + 3) % 4, i));
  quad.push_back(quad.front());

  const auto result = regularise({quad}, nullptr, RegulariseParams{});
  EXPECT_EQ(result.segments_before, 4u);
  ASSERT_EQ(result.segments_after, 4u);
  ASSERT_EQ(result.segments.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i)
    for (std::size_t j = i + 1; j < 4; ++j) {
      const Point2 u = unit(result.segments[i]), v = unit(result.segments[j]);
      const double cross = std::abs(u.x * v.y - u.y * v.x), dot = std::abs(u.x * v.x + u.y * v.y);
      EXPECT_LT(std::min(cross, dot), 1e-12) << i << " vs " << j;
    }
  // The directions are a rotated rectangle's: the longest edge (near 0 degrees) keeps a direction
  // within the noise, it is not forced to the axes.
  int near_axis = 0;
  for (const auto& s : result.segments) {
    const Point2 u = unit(s);
    if (std::abs(u.y) < std::sin(9 * kPi / 180) || std::abs(u.x) < std::sin(9 * kPi / 180)) ++near_axis;
  }
  EXPECT_EQ(near_axis, 4);
}

TEST(Regularise, near_collinear_pieces_become_one_segment) {
  // Two pieces of one wall, 0.1 m apart sideways and 2 degrees apart, overlapping end to end.
  const Polyline2 a{{0, 0}, {5, 0.05}};
  const Polyline2 b{{4.9, 0.12}, {10, 0.3}};
  const auto result = regularise({a, b}, nullptr, RegulariseParams{});
  EXPECT_EQ(result.segments_before, 2u);
  ASSERT_EQ(result.segments.size(), 1u);
  EXPECT_NEAR(seg_len(result.segments[0]), 10.0, 0.05);
}

TEST(Regularise, segments_near_a_footprint_edge_align_to_it) {
  // Footprint: a rectangle rotated by 30 degrees; a line 6 degrees off one edge, 0.2 m inside.
  const double t = kPi / 6;
  const Point2 u{std::cos(t), std::sin(t)}, n{-std::sin(t), std::cos(t)};
  Ring2 fp;
  for (const auto& [x, y] : std::vector<std::pair<double, double>>{{0, 0}, {10, 0}, {10, 6}, {0, 6}})
    fp.push_back({x * u.x + y * n.x, x * u.y + y * n.y});
  const auto footprint = footprint_of(fp);
  const double off = t + 6 * kPi / 180;
  const Point2 a{1 * u.x + 0.2 * n.x, 1 * u.y + 0.2 * n.y};
  const Polyline2 line{a, {a.x + 8 * std::cos(off), a.y + 8 * std::sin(off)}};
  const auto result = regularise({line}, &footprint, RegulariseParams{});
  ASSERT_EQ(result.segments.size(), 1u);
  const Point2 d = unit(result.segments[0]);
  EXPECT_LT(std::abs(d.x * u.y - d.y * u.x), 1e-12);

  // Without the footprint the line keeps its own direction.
  const auto free = regularise({line}, nullptr, RegulariseParams{});
  const Point2 e = unit(free.segments[0]);
  EXPECT_GT(std::abs(e.x * u.y - e.y * u.x), 0.09);
}

TEST(Regularise, keeps_a_notch_of_one_and_a_half_metres) {
  const auto pixels = rasterise(ring_lines(kNotched), 0.02, 8);
  const auto lines = extract_polylines(pixels, PolylineParams{});
  const auto result = regularise(lines, nullptr, RegulariseParams{});
  // The notch bottom (y = 6.61) and both sides (x = 5.07 and 6.57) survive as segments >= 1 m, within
  // 2 degrees of the axes (without a footprint the directions are the clusters' means, not the axes).
  const double tilt = std::sin(2 * kPi / 180);
  bool bottom = false, left = false, right = false;
  for (const auto& s : result.segments) {
    const Point2 d = unit(s);
    const Point2 m{0.5 * (s.a.x + s.b.x), 0.5 * (s.a.y + s.b.y)};
    if (seg_len(s) < 1.0) continue;
    if (std::abs(d.y) < tilt && std::abs(m.y - 6.61) < 0.25 && m.x > 5 && m.x < 6.7) bottom = true;
    if (std::abs(d.x) < tilt && std::abs(m.x - 5.07) < 0.25 && m.y > 6.5) left = true;
    if (std::abs(d.x) < tilt && std::abs(m.x - 6.57) < 0.25 && m.y > 6.5) right = true;
  }
  EXPECT_TRUE(bottom);
  EXPECT_TRUE(left);
  EXPECT_TRUE(right);
  // The top edge stays split in two around the notch.
  int top_pieces = 0;
  for (const auto& s : result.segments)
    if (std::abs(s.a.y - 8.11) < 0.25 && std::abs(s.b.y - 8.11) < 0.25 && seg_len(s) > 3) ++top_pieces;
  EXPECT_EQ(top_pieces, 2);
  EXPECT_EQ(result.segments_after, 8u);  // the notched outline's 8 edges
}

// ---------------------------------------------------------------------------------------------
// Walls

TEST(Walls, outer_walls_equal_the_footprint_edges_with_outward_normals) {
  // An L-shape given clockwise, with an extra vertex in the middle of its first edge.
  Ring2 ring{{0.07, 0.11}, {6.07, 0.11},  {12.07, 0.11}, {12.07, 5.11},
             {6.07, 5.11}, {6.07, 10.11}, {0.07, 10.11}};
  std::reverse(ring.begin(), ring.end());
  const auto footprint = footprint_of(ring);
  const auto walls = infer_walls(RegularisationResult{}, &footprint, {}, WallParams{});
  ASSERT_EQ(walls.size(), 6u);
  for (const auto& w : walls) {
    EXPECT_TRUE(w.outer);
    EXPECT_EQ(w.source, VerticalPlane::Source::footprint);
    EXPECT_NEAR(std::hypot(w.normal.x, w.normal.y), 1.0, 1e-12);
    EXPECT_NEAR(w.normal.x * w.a.x + w.normal.y * w.a.y, w.offset, 1e-9);
    EXPECT_NEAR(w.normal.x * w.b.x + w.normal.y * w.b.y, w.offset, 1e-9);
    const Point2 m{0.5 * (w.a.x + w.b.x), 0.5 * (w.a.y + w.b.y)};
    EXPECT_FALSE(inside(kLShape, {m.x + 0.1 * w.normal.x, m.y + 0.1 * w.normal.y}));
    EXPECT_TRUE(inside(kLShape, {m.x - 0.1 * w.normal.x, m.y - 0.1 * w.normal.y}));
    // Each wall is exactly one edge of the L-shape (the split edge merged back).
    bool matched = false;
    for (std::size_t i = 0; i < kLShape.size(); ++i) {
      const Point2 p = kLShape[i], q = kLShape[(i + 1) % kLShape.size()];
      if ((dist(p, w.a) < 1e-12 && dist(q, w.b) < 1e-12) || (dist(p, w.b) < 1e-12 && dist(q, w.a) < 1e-12))
        matched = true;
    }
    EXPECT_TRUE(matched) << "(" << w.a.x << ", " << w.a.y << ") - (" << w.b.x << ", " << w.b.y << ")";
  }
}

TEST(Walls, step_between_two_flat_roofs_gives_one_inner_wall) {
  // Rectangle outline plus the step line between a low and a high roof at x = 5.03.
  const double step_x = 5.03;
  auto lines_in = ring_lines(kRectangle);
  lines_in.push_back({{step_x, 0.11}, {step_x, 8.11}});
  const auto pixels = rasterise(lines_in, 0.03, 9);
  const auto polylines = extract_polylines(pixels, PolylineParams{});
  const auto footprint = footprint_of(kRectangle);
  const auto regular = regularise(polylines, &footprint, RegulariseParams{});
  const auto walls = infer_walls(regular, &footprint, {}, WallParams{});
  std::vector<VerticalPlane> inner;
  int outer = 0;
  for (const auto& w : walls) (w.outer ? (void)++outer : inner.push_back(w));
  EXPECT_EQ(outer, 4);
  ASSERT_EQ(inner.size(), 1u);
  const auto& w = inner[0];
  EXPECT_EQ(w.source, VerticalPlane::Source::inferred);
  EXPECT_NEAR(0.5 * (w.a.x + w.b.x), step_x, 0.3);
  const double angle = std::atan2(std::abs(w.b.x - w.a.x), std::abs(w.b.y - w.a.y)) * 180 / kPi;
  EXPECT_LT(angle, 5.0);
  EXPECT_GT(dist(w.a, w.b), 6.0);  // spans most of the building
}

TEST(Walls, without_footprint_the_outline_walls_face_outwards_and_the_step_is_inner) {
  const double step_x = 5.03;
  auto lines_in = ring_lines(kRectangle);
  lines_in.push_back({{step_x, 0.11}, {step_x, 8.11}});
  const auto pixels = rasterise(lines_in, 0.03, 10);
  const auto regular = regularise(extract_polylines(pixels, PolylineParams{}), nullptr, RegulariseParams{});
  const auto walls = infer_walls(regular, nullptr, {}, WallParams{});
  int inner_near_step = 0;
  double outer_length = 0;
  for (const auto& w : walls) {
    const Point2 m{0.5 * (w.a.x + w.b.x), 0.5 * (w.a.y + w.b.y)};
    if (!w.outer) {
      if (std::abs(m.x - step_x) < 0.3) ++inner_near_step;
      continue;
    }
    outer_length += dist(w.a, w.b);
    EXPECT_FALSE(inside(kRectangle, {m.x + 0.5 * w.normal.x, m.y + 0.5 * w.normal.y}))
        << "(" << w.a.x << ", " << w.a.y << ") - (" << w.b.x << ", " << w.b.y << ")";
  }
  EXPECT_GE(inner_near_step, 1);
  EXPECT_NEAR(outer_length, 40.0, 2.0);  // the rectangle's perimeter
}

TEST(Walls, inner_lines_along_the_footprint_boundary_are_dropped) {
  const auto footprint = footprint_of(kRectangle);
  RegularisationResult lines;
  lines.segments = {{{1.0, 0.25}, {11.0, 0.25}},  // 0.14 m inside the bottom edge: duplicate
                    {{1.0, 4.0}, {11.0, 4.0}},    // a real inner line
                    {{15.0, 1.0}, {15.0, 7.0}}};  // outside the footprint
  const auto walls = infer_walls(lines, &footprint, {}, WallParams{});
  std::vector<VerticalPlane> inner;
  for (const auto& w : walls)
    if (!w.outer) inner.push_back(w);
  ASSERT_EQ(inner.size(), 1u);
  EXPECT_NEAR(inner[0].a.y, 4.0, 1e-12);
  EXPECT_NEAR(inner[0].b.y, 4.0, 1e-12);
}

TEST(Walls, inner_line_crossing_the_boundary_is_clipped_to_the_footprint) {
  const auto footprint = footprint_of(kRectangle);
  RegularisationResult lines;
  lines.segments = {{{-3.0, 4.0}, {5.0, 4.0}}};
  const auto walls = infer_walls(lines, &footprint, {}, WallParams{});
  ASSERT_EQ(walls.size(), 5u);
  const auto& w = walls.back();
  EXPECT_FALSE(w.outer);
  EXPECT_NEAR(std::min(w.a.x, w.b.x), 0.07, 0.06);
  EXPECT_NEAR(std::max(w.a.x, w.b.x), 5.0, 1e-9);
}

TEST(Walls, automatic_mode_uses_detected_lines_only_when_plentiful) {
  RegularisationResult inferred;
  for (const auto& [a, b] : ring_lines(kRectangle)) inferred.segments.push_back({a, b});
  const auto detected = ring_lines(kRectangle);
  const auto with_detected = infer_walls(inferred, nullptr, detected, WallParams{});
  ASSERT_EQ(with_detected.size(), 4u);
  for (const auto& w : with_detected) EXPECT_EQ(w.source, VerticalPlane::Source::detected);

  const std::vector<Line> few{detected[0]};
  const auto with_few = infer_walls(inferred, nullptr, few, WallParams{});
  ASSERT_EQ(with_few.size(), 4u);
  for (const auto& w : with_few) {
    EXPECT_EQ(w.source, VerticalPlane::Source::inferred);
    EXPECT_TRUE(w.outer);
  }
}

// A line screened on one side by a line 1 m off and 7 m long, with a long line below it: of the rays
// at 0, +-30 and +-60 degrees from its three points only two escape past the screen's ends, fewer than
// min_escaping_rays; at 0, +-40 and +-80 degrees four do, and it faces out.
TEST(Walls, the_fan_of_rays_decides_whether_a_screened_line_faces_out) {
  RegularisationResult lines;
  lines.segments = {{{0.0, 0.0}, {10.0, 0.0}}, {{1.5, 1.0}, {8.5, 1.0}}, {{-100.0, -1.0}, {100.0, -1.0}}};
  WallParams params;
  params.mode = WallMode::inferred;
  const auto the_line = [](const std::vector<VerticalPlane>& walls) {
    for (const VerticalPlane& w : walls)
      if (std::abs(w.a.y) < 1e-12 && std::abs(w.b.y) < 1e-12) return w;
    ADD_FAILURE() << "no wall along y = 0";
    return VerticalPlane{};
  };
  EXPECT_FALSE(the_line(infer_walls(lines, nullptr, {}, params)).outer);
  params.ray_fan_step = 40.0;
  const VerticalPlane wide = the_line(infer_walls(lines, nullptr, {}, params));
  EXPECT_TRUE(wide.outer);
  EXPECT_GT(wide.normal.y, 0.99);
}

// A detected wall along a footprint 0.5 m wide: its side is told at footprint_margin + side_probe off
// its middle, inside the footprint at the default (so it faces away from it), beyond the far side at
// 0.3 m (so it keeps the side it was drawn with).
TEST(Walls, the_side_probe_tells_which_side_of_a_detected_wall_is_inside) {
  const auto strip = footprint_of({{0, 0}, {12, 0}, {12, 0.5}, {0, 0.5}});
  WallParams params;
  params.mode = WallMode::detected;
  const std::vector<Line> detected{{{1.0, 0.0}, {11.0, 0.0}}};
  const auto near = infer_walls(RegularisationResult{}, &strip, detected, params);
  ASSERT_EQ(near.size(), 1u);
  EXPECT_TRUE(near[0].outer);
  EXPECT_LT(near[0].normal.y, -0.99);
  params.side_probe = 0.3;
  const auto far = infer_walls(RegularisationResult{}, &strip, detected, params);
  ASSERT_EQ(far.size(), 1u);
  EXPECT_GT(far[0].normal.y, 0.99);
}

TEST(Walls, footprint_mode_without_footprint_is_a_config_error) {
  WallParams params;
  params.mode = WallMode::footprint;
  EXPECT_THROW(infer_walls(RegularisationResult{}, nullptr, {}, params), ConfigError);
  params.mode = WallMode::detected;
  EXPECT_THROW(infer_walls(RegularisationResult{}, nullptr, {}, params), ReconstructionError);
}

// ---------------------------------------------------------------------------------------------
// Defaults: a change must be deliberate (the paper's eps_d = 0.25, eps_c = 2.0, 20 degrees).

TEST(Defaults, stage_parameters_keep_their_documented_defaults) {
  const PolylineParams p;
  EXPECT_EQ(p.max_hausdorff, 0.25);
  EXPECT_EQ(p.max_cost, 2.0);
  EXPECT_EQ(p.resolution, 0.0);
  EXPECT_EQ(p.link_pixels, 2.5);
  EXPECT_EQ(p.min_polyline_length, 1.0);
  EXPECT_TRUE(p.relocate);
  const RegulariseParams r;
  EXPECT_EQ(r.angle_threshold, 20.0);
  EXPECT_EQ(r.cluster_distance, 0.5);
  EXPECT_EQ(r.cluster_angle, 15.0);
  EXPECT_EQ(r.min_cluster, 1);
  EXPECT_EQ(r.merge_gap, 0.3);
  const WallParams w;
  EXPECT_EQ(w.mode, WallMode::automatic);
  EXPECT_EQ(w.min_wall_length, 0.5);
  EXPECT_EQ(w.footprint_margin, 0.3);
  const StepLineParams st;
  EXPECT_TRUE(st.enabled);
  EXPECT_EQ(st.min_step, 0.5);
  EXPECT_EQ(st.search_spacings, 3.0);
  EXPECT_EQ(st.line_tolerance, 0.25);
  EXPECT_EQ(st.min_length, 1.0);
  EXPECT_EQ(st.min_samples, 4);
  EXPECT_EQ(st.min_separation, 0.65);
}

TEST(Polylines, fewer_than_two_pixels_give_no_polyline) {
  EXPECT_TRUE(extract_polylines({}, PolylineParams{}).empty());
  EXPECT_TRUE(extract_polylines({{1.0, 2.0}, {1.0, 2.0}}, PolylineParams{}).empty());
}
