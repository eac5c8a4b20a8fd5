// Time of the k-nearest-neighbour lists of the planes stage (src/planes/neighbours.cpp) against
// CGAL's kd-tree search, which the planes used alone before, on every .ply cloud under the folders
// given: each cloud moved to a local frame (its bounding box's centre subtracted) and its repeated
// points dropped, as the pipeline hands them to the planes. Checks that both give the same lists,
// entry for entry, and prints per folder the points, the share the grid settled, and the seconds
// of each search (the median of `runs` runs of the whole folder).
// Usage: bench_neighbours [--runs N] [--k K] FOLDER...
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Shape_detection/Region_growing/Region_growing_on_point_set/K_neighbor_query.h>
#include <CGAL/property_map.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/point_cloud_io.hpp"
#include "local_cloud.hpp"
#include "planes/neighbours.hpp"

namespace {

using Clock = std::chrono::steady_clock;
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using PointWithNormal = std::pair<Kernel::Point_3, Kernel::Vector_3>;
using Range = std::vector<PointWithNormal>;
using TreeQuery =
    CGAL::Shape_detection::Point_set::K_neighbor_query<Kernel, Range,
                                                       CGAL::First_of_pair_property_map<PointWithNormal>>;

std::vector<city3d::Point3> local_distinct_points(const std::string& path) {
  std::vector<city3d::Point3> local = city3d::bench::local_points(path);
  const auto less = [](const city3d::Point3& a, const city3d::Point3& b) {
    return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z;
  };
  const auto same = [](const city3d::Point3& a, const city3d::Point3& b) {
    return a.x == b.x && a.y == b.y && a.z == b.z;
  };
  std::sort(local.begin(), local.end(), less);
  local.erase(std::unique(local.begin(), local.end(), same), local.end());
  return local;
}

std::vector<std::uint32_t> tree_lists(const std::vector<city3d::Point3>& points, std::size_t k) {
  Range range;
  range.reserve(points.size());
  for (const auto& p : points) range.emplace_back(Kernel::Point_3(p.x, p.y, p.z), Kernel::Vector_3(0, 0, 1));
  const TreeQuery search(range, k);
  std::vector<std::uint32_t> lists;
  lists.reserve(points.size() * std::min(k, points.size()));
  std::vector<std::size_t> neighbours;
  for (std::size_t i = 0; i < points.size(); ++i) {
    search(i, neighbours);
    lists.insert(lists.end(), neighbours.begin(), neighbours.end());
  }
  return lists;
}

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  int runs = 5;
  std::size_t k = 12;
  std::vector<std::filesystem::path> folders;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--runs" && a + 1 < argc) {
      runs = std::max(1, std::atoi(argv[++a]));
    } else if (arg == "--k" && a + 1 < argc) {
      k = static_cast<std::size_t>(std::max(1, std::atoi(argv[++a])));
    } else if (!arg.empty() && arg[0] == '-') {
      std::fprintf(stderr, "usage: bench_neighbours [--runs N] [--k K] FOLDER...\n");
      return 2;
    } else {
      folders.emplace_back(arg);
    }
  }
  if (folders.empty()) {
    std::fprintf(stderr, "usage: bench_neighbours [--runs N] [--k K] FOLDER...\n");
    return 2;
  }
  int mismatches = 0;
  std::printf("%-40s %7s %10s %8s %9s %9s %6s\n", "folder", "clouds", "points", "grid", "tree_s", "grid_s",
              "ratio");
  for (const auto& folder : folders) {
    std::vector<std::filesystem::path> files;
    std::error_code error;
    for (std::filesystem::recursive_directory_iterator it(folder, error), end; !error && it != end;
         it.increment(error))
      if (it->is_regular_file() && it->path().extension() == ".ply") files.push_back(it->path());
    std::sort(files.begin(), files.end());
    if (error || files.empty()) {
      std::fprintf(stderr, "bench_neighbours: no .ply files under %s\n", folder.string().c_str());
      return 1;
    }
    std::vector<std::vector<city3d::Point3>> clouds;
    std::size_t points = 0;
    for (const auto& file : files) {
      try {
        clouds.push_back(local_distinct_points(file.string()));
        points += clouds.back().size();
      } catch (const city3d::Error& e) {
        std::fprintf(stderr, "bench_neighbours: %s: %s\n", file.string().c_str(), e.what());
        return 1;
      }
    }
    std::size_t settled = 0;
    for (const auto& cloud : clouds) {
      city3d::detail::NeighbourStats stats;
      if (city3d::detail::k_nearest_lists(cloud, k, &stats) != tree_lists(cloud, k)) ++mismatches;
      settled += stats.from_grid;
    }
    std::vector<double> tree_s, grid_s;
    std::size_t sink = 0;
    for (int r = 0; r < runs; ++r) {  // the two in alternation
      auto start = Clock::now();
      for (const auto& cloud : clouds) sink += tree_lists(cloud, k).size();
      tree_s.push_back(seconds_since(start));
      start = Clock::now();
      for (const auto& cloud : clouds) sink += city3d::detail::k_nearest_lists(cloud, k).size();
      grid_s.push_back(seconds_since(start));
    }
    const double t = median(tree_s), g = median(grid_s);
    std::printf("%-40s %7zu %10zu %7.2f%% %9.3f %9.3f %6.2f%s\n", folder.filename().string().c_str(),
                clouds.size(), points, 100.0 * static_cast<double>(settled) / static_cast<double>(points), t,
                g, g / t, sink == 0 ? " (no lists)" : "");
  }
  if (mismatches) std::printf("%d clouds whose lists differ from the tree's\n", mismatches);
  return mismatches ? 1 : 0;
}
