// Time of the paper's section 3.2 stages per building (detect_planes, rasterise_tin, detect_edges,
// extract_polylines, infer_outline + regularise), single thread, default params, as the pipeline calls them.
// Usage: bench_planes_heightmap [FOLDER]   (default /work/shared/data/city3d_dev, searched
// recursively for .ply; each cloud is moved to a local frame by subtracting its bbox centre)
// Prints one line per building and the median and maximum of the per-building total.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/heightmap.hpp"
#include "city3d/planes.hpp"
#include "city3d/point_cloud_io.hpp"
#include "city3d/polylines.hpp"
#include "city3d/regularise.hpp"
#include "local_cloud.hpp"

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  return values[static_cast<std::size_t>(q * static_cast<double>(values.size() - 1) + 0.5)];
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 2) {
    std::fprintf(stderr, "usage: bench_planes_heightmap [FOLDER]\n");
    return 2;
  }
  const std::filesystem::path folder = argc == 2 ? argv[1] : "/work/shared/data/city3d_dev";
  std::vector<std::filesystem::path> files;
  std::error_code error;
  for (std::filesystem::recursive_directory_iterator it(folder, error), end; !error && it != end;
       it.increment(error))
    if (it->is_regular_file() && it->path().extension() == ".ply") files.push_back(it->path());
  if (error || files.empty()) {
    std::fprintf(stderr, "bench_planes_heightmap: no .ply files under %s\n", folder.string().c_str());
    return 1;
  }
  std::sort(files.begin(), files.end());

  const city3d::PlaneParams plane_params;
  const city3d::HeightmapParams heightmap_params;
  const city3d::PolylineParams polyline_params;
  const city3d::RegulariseParams regularise_params;
  std::vector<double> totals, planes_ms, raster_ms, edges_ms, poly_ms, reg_ms;
  int failures = 0;
  std::printf("%-28s %8s %6s %5s %9s %6s %9s %9s %9s %9s %9s %9s\n", "building", "points", "roofs", "walls",
              "raster", "edges", "planes_ms", "tin_ms", "edges_ms", "poly_ms", "reg_ms", "total_ms");
  for (const auto& file : files) {
    const std::string name = std::filesystem::relative(file, folder).string();
    try {
      const auto points = city3d::bench::local_points(file.string());
      auto start = Clock::now();
      const auto segments = city3d::detect_planes(points, plane_params);
      const double t_planes = ms_since(start);
      start = Clock::now();
      const auto map = city3d::rasterise_tin(points, heightmap_params);
      const double t_raster = ms_since(start);
      start = Clock::now();
      const auto edges = city3d::detect_edges(map, heightmap_params);
      const double t_edges = ms_since(start);
      start = Clock::now();
      const auto polylines = city3d::extract_polylines(edges, polyline_params);
      const double t_poly = ms_since(start);
      start = Clock::now();
      std::vector<city3d::Polygon2> outline;
      for (const auto& p : city3d::infer_outline(map, points, polyline_params.max_hausdorff))
        outline.push_back(city3d::regularise_outline(p, regularise_params.angle_threshold));
      const auto lines = city3d::regularise(polylines, outline.empty() ? nullptr : &outline, regularise_params);
      const double t_reg = ms_since(start);
      std::size_t walls = 0;
      for (const auto& s : segments) walls += s.kind == city3d::PlanarSegment::Kind::wall;
      const double total = t_planes + t_raster + t_edges + t_poly + t_reg;
      char raster[32];
      std::snprintf(raster, sizeof raster, "%dx%d", map.width, map.height);
      std::printf("%-28s %8zu %6zu %5zu %9s %6zu %9.1f %9.1f %9.1f %9.1f %9.1f %9.1f  (%zu -> %zu segments)\n",
                  name.c_str(), points.size(), segments.size() - walls, walls, raster, edges.size(), t_planes, t_raster,
                  t_edges, t_poly, t_reg, total, lines.segments_before, lines.segments_after);
      totals.push_back(total);
      planes_ms.push_back(t_planes);
      raster_ms.push_back(t_raster);
      edges_ms.push_back(t_edges);
      poly_ms.push_back(t_poly);
      reg_ms.push_back(t_reg);
    } catch (const city3d::Error& e) {
      ++failures;
      std::printf("%-28s failed: %s\n", name.c_str(), e.what());
    }
  }
  std::printf("\n%zu buildings (%d failed)\n", totals.size(), failures);
  std::printf("%-10s %9s %9s %9s %9s %9s %9s\n", "", "planes_ms", "tin_ms", "edges_ms", "poly_ms", "reg_ms",
              "total_ms");
  for (const double q : {0.5, 1.0})
    std::printf("%-10s %9.1f %9.1f %9.1f %9.1f %9.1f %9.1f\n", q == 0.5 ? "median" : "max", percentile(planes_ms, q),
                percentile(raster_ms, q), percentile(edges_ms, q), percentile(poly_ms, q), percentile(reg_ms, q),
                percentile(totals, q));
  return failures == 0 ? 0 : 1;
}
