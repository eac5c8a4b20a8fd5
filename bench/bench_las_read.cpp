// Throughput of the streaming LAS reader: xyz + classification in 1M-point chunks, single thread.
// Usage: bench_las_read FILE [repeats]   (prints points/s per run and the median)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/point_cloud_io.hpp"

namespace {

constexpr std::size_t kChunkPoints = 1u << 20;

/// Reads the whole file once; returns the number of points and checks the class vector keeps up.
std::uint64_t read_once(const std::string& path, std::uint64_t& class_sum) {
  auto reader = city3d::open_point_cloud(path, city3d::kFieldClassification);
  city3d::PointCloud chunk;
  std::uint64_t total = 0;
  for (;;) {
    chunk.clear();  // keeps capacity: the steady state allocates nothing
    const std::size_t n = reader->read(chunk, kChunkPoints);
    if (n == 0) break;
    total += n;
    class_sum += chunk.classification[n - 1];  // touch the output so nothing is optimised away
  }
  return total;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: bench_las_read FILE [repeats]\n");
    return 2;
  }
  const std::string path = argv[1];
  const int repeats = argc == 3 ? std::atoi(argv[2]) : 5;
  if (repeats < 1) {
    std::fprintf(stderr, "bench_las_read: repeats must be >= 1, got '%s'\n", argv[2]);
    return 2;
  }
  try {
    std::uint64_t class_sum = 0;
    read_once(path, class_sum);  // warm the page cache
    std::vector<double> rates;
    for (int r = 0; r < repeats; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      const std::uint64_t points = read_once(path, class_sum);
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      rates.push_back(points / seconds);
      std::printf("run %d: %llu points in %.4f s = %.1f Mpoints/s\n", r + 1,
                  static_cast<unsigned long long>(points), seconds, points / seconds / 1e6);
    }
    std::sort(rates.begin(), rates.end());
    const std::size_t m = rates.size();
    const double median = m % 2 ? rates[m / 2] : 0.5 * (rates[m / 2 - 1] + rates[m / 2]);
    std::printf("median: %.1f Mpoints/s (xyz + classification, %zu-point chunks, %d runs; checksum %llu)\n",
                median / 1e6, kChunkPoints, repeats, static_cast<unsigned long long>(class_sum));
  } catch (const city3d::Error& e) {
    std::fprintf(stderr, "bench_las_read: %s\n", e.what());
    return 1;
  }
  return 0;
}
