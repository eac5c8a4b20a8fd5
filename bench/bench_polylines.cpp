// Time of the wall-inference stages on synthetic edge pixels: extract_polylines, regularise and
// infer_walls, for buildings of about 500 to 5,000 edge pixels (r = 0.2 m, jitter, outliers).
// Usage: bench_polylines [repeats]   (prints, per size, the median milliseconds of each stage)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "city3d/polylines.hpp"
#include "city3d/regularise.hpp"
#include "city3d/walls.hpp"

namespace {

using city3d::Point2;
using Line = std::pair<Point2, Point2>;
constexpr double kR = 0.2;

// A comb-shaped building `width` metres wide: a 12 m deep body with 2 x 3 m teeth along its top edge
// (many corners) and a roof step line every 6 m, rasterised like Canny edges, plus 10 outliers.
std::vector<Point2> comb_building(double width, unsigned seed, city3d::Ring2& outline) {
  outline.clear();
  outline.push_back({0.07, 0.11});
  outline.push_back({width + 0.07, 0.11});
  const int teeth = static_cast<int>(width / 6.0);
  for (int k = teeth; k >= 0; --k) {  // top edge, right to left, one 3 m tooth per 6 m
    const double x0 = 0.07 + 6.0 * k;
    const double x1 = std::min(x0 + 3.0, width + 0.07);
    if (k == teeth) outline.push_back({width + 0.07, 12.11});
    if (x1 <= x0 + 0.5 || x1 > width + 0.07) continue;
    outline.push_back({x1, 12.11});
    outline.push_back({x1, 14.11});
    outline.push_back({x0, 14.11});
    outline.push_back({x0, 12.11});
  }
  outline.push_back({0.07, 12.11});
  std::vector<Line> lines;
  for (std::size_t i = 0; i < outline.size(); ++i)
    lines.push_back({outline[i], outline[(i + 1) % outline.size()]});
  for (double x = 6.03; x < width - 1; x += 6.0) lines.push_back({{x, 0.11}, {x, 12.11}});

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
  std::normal_distribution<double> jitter(0.0, 0.03);
  std::uniform_real_distribution<double> anywhere(-5.0, width + 5.0);
  std::vector<Point2> pixels;
  for (const auto& [i, j] : cells)
    pixels.push_back({(i + 0.5) * kR + jitter(rng), (j + 0.5) * kR + jitter(rng)});
  for (int k = 0; k < 10; ++k) pixels.push_back({anywhere(rng), anywhere(rng) * 0.2 + 20});
  return pixels;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 7;
  std::printf("%8s %8s %10s %12s %12s %10s %10s\n", "pixels", "polys", "segments", "polylines_ms",
              "regularise_ms", "walls_ms", "total_ms");
  for (double width : {16.0, 28.0, 58.0, 118.0, 210.0}) {
    city3d::Ring2 outline;
    const auto pixels = comb_building(width, 42, outline);
    const std::vector<city3d::Polygon2> footprint{{outline, {}}};
    std::vector<double> t_poly, t_reg, t_walls;
    std::size_t n_lines = 0, n_segments = 0;
    for (int r = 0; r < repeats; ++r) {
      auto t0 = std::chrono::steady_clock::now();
      const auto lines = city3d::extract_polylines(pixels, city3d::PolylineParams{});
      t_poly.push_back(ms_since(t0));
      t0 = std::chrono::steady_clock::now();
      const auto regular = city3d::regularise(lines, &footprint, city3d::RegulariseParams{});
      t_reg.push_back(ms_since(t0));
      t0 = std::chrono::steady_clock::now();
      const auto walls = city3d::infer_walls(regular, &footprint, {}, city3d::WallParams{});
      t_walls.push_back(ms_since(t0));
      n_lines = lines.size();
      n_segments = regular.segments.size();
      if (walls.empty()) return 1;  // keeps the work observable
    }
    const double p = median(t_poly), g = median(t_reg), w = median(t_walls);
    std::printf("%8zu %8zu %10zu %12.2f %12.2f %10.2f %10.2f\n", pixels.size(), n_lines, n_segments, p, g, w,
                p + g + w);
  }
  return 0;
}
