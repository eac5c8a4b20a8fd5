// Throughput of the cropper: the points of point-cloud files, held in memory in the chunks a cropping
// pass streams (65,536 points), assigned to the footprints of a layer, on one thread.
// Usage: bench_crop FOOTPRINTS CLOUD [CLOUD...] [--runs N]   (prints each run and the median)
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include "city3d/crop.hpp"
#include "city3d/error.hpp"
#include "city3d/footprint_io.hpp"
#include "city3d/point_cloud_io.hpp"

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  int runs = 7;
  const auto flag = std::find(args.begin(), args.end(), "--runs");
  if (flag != args.end()) {
    if (flag + 1 == args.end() || (runs = std::atoi((flag + 1)->c_str())) < 1) {
      std::fprintf(stderr, "bench_crop: --runs needs a number >= 1\n");
      return 2;
    }
    args.erase(flag, flag + 2);
  }
  if (args.size() < 2) {
    std::fprintf(stderr, "usage: bench_crop FOOTPRINTS CLOUD [CLOUD...] [--runs N]\n");
    return 2;
  }
  try {
    const city3d::FootprintSet set = city3d::read_footprints(args[0]);
    std::vector<city3d::PointCloud> chunks;
    std::size_t points = 0;
    for (std::size_t f = 1; f < args.size(); ++f) {
      auto reader = city3d::open_point_cloud(args[f], city3d::kFieldClassification);
      for (;;) {
        city3d::PointCloud chunk;
        const std::size_t n = reader->read(chunk, std::size_t{1} << 16);
        if (n == 0) break;
        points += n;
        chunks.push_back(std::move(chunk));
      }
    }
    std::vector<double> seconds;
    std::uint64_t assigned = 0;
    for (int r = 0; r < runs; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      city3d::Cropper cropper(set.footprints);
      for (const city3d::PointCloud& chunk : chunks) cropper.add(chunk);
      const std::vector<city3d::BuildingInput> inputs = cropper.finish();
      seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      assigned = cropper.stats().building_points + cropper.stats().ground_points;
      std::printf("run %d: %.4f s, %.1f Mpoints/s\n", r + 1, seconds.back(), points / seconds.back() / 1e6);
    }
    std::sort(seconds.begin(), seconds.end());
    const std::size_t m = seconds.size();
    const double median = m % 2 ? seconds[m / 2] : 0.5 * (seconds[m / 2 - 1] + seconds[m / 2]);
    std::printf("median: %.4f s for %zu points and %zu footprints (%.1f Mpoints/s; %llu assignments kept)\n",
                median, points, set.footprints.size(), points / median / 1e6,
                static_cast<unsigned long long>(assigned));
  } catch (const city3d::Error& e) {
    std::fprintf(stderr, "bench_crop: %s\n", e.what());
    return 1;
  }
  return 0;
}
