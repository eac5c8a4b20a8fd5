// Decode speed of the LAZ decoder: decodes every record of one LAZ file, several times, on one
// core, and prints points per second (thread CPU time and wall time) per run and the median.
// With a list of thread counts it instead reads the file through the LAS reader
// (open_point_cloud(path, kFieldXyz, threads): decoding plus conversion to xyz), each thread count
// once per run in turn, and prints the median wall-clock rate of each side by side.
// Usage: bench_laz_decode FILE.laz [repeats=11] [THREADS,THREADS,...]
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/point_cloud_io.hpp"
#include "laz/laz_decoder.hpp"

namespace {

using city3d::detail::LaszipVlr;
using city3d::detail::LazDecoder;
using city3d::detail::LazLayout;

template <typename T>
T field(const std::vector<std::uint8_t>& bytes, std::size_t offset) {
  if (offset + sizeof(T) > bytes.size()) throw city3d::IoError("bench: header field past end of file");
  T v;
  std::memcpy(&v, bytes.data() + offset, sizeof v);
  return v;
}

/// Reads the LAS header fields and the LASzip VLR the decoder needs (the LAS reader's job in the library).
void read_layout(const std::string& path, LaszipVlr& vlr, LazLayout& layout) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw city3d::IoError("bench: cannot open " + path);
  std::vector<std::uint8_t> head(64 * 1024);
  in.read(reinterpret_cast<char*>(head.data()), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  in.clear();
  in.seekg(0, std::ios::end);
  layout.path = path;
  layout.file_size = static_cast<std::uint64_t>(in.tellg());
  const auto header_size = field<std::uint16_t>(head, 94);
  layout.point_data_offset = field<std::uint32_t>(head, 96);
  const auto vlr_count = field<std::uint32_t>(head, 100);
  const auto format_byte = field<std::uint8_t>(head, 104);
  layout.point_format = format_byte & 0x3F;
  layout.record_length = field<std::uint16_t>(head, 105);
  layout.point_count = field<std::uint32_t>(head, 107);
  if (field<std::uint8_t>(head, 25) >= 4 && header_size >= 255)
    layout.point_count = field<std::uint64_t>(head, 247);
  std::size_t at = header_size;
  for (std::uint32_t i = 0; i < vlr_count; ++i) {
    const auto length = field<std::uint16_t>(head, at + 20);
    if (at + 54 + length > head.size()) break;
    if (std::strncmp(reinterpret_cast<const char*>(head.data() + at + 2), "laszip encoded", 16) == 0 &&
        field<std::uint16_t>(head, at + 18) == 22204) {
      vlr = city3d::detail::parse_laszip_vlr(head.data() + at + 54, length, path);
      return;
    }
    at += 54 + length;
  }
  city3d::detail::check_laszip_vlr_present(false, format_byte, path);
  throw city3d::IoError("bench: " + path + " is not a LAZ file");
}

double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Reads `path` through the LAS reader once per run for each thread count, interleaved so that
/// every count sees the same machine load, and prints wall-clock rates and their medians.
int compare_threads(const std::string& path, int repeats, const std::vector<unsigned>& thread_counts) {
  std::vector<std::vector<double>> rates(thread_counts.size());
  std::uint64_t expected = 0;
  for (int run = 0; run < repeats; ++run) {
    std::printf("run %2d:", run + 1);
    for (std::size_t t = 0; t < thread_counts.size(); ++t) {
      const auto wall0 = std::chrono::steady_clock::now();
      auto reader = city3d::open_point_cloud(path, city3d::kFieldXyz, thread_counts[t]);
      city3d::PointCloud cloud;
      std::uint64_t points = 0;
      while (const std::size_t n = reader->read(cloud, 1u << 20)) {
        points += n;
        cloud.clear();  // time decoding and conversion, not the growth of one huge cloud
      }
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
      if (expected == 0) expected = points;
      if (points != expected || points != reader->info().point_count) {
        std::fprintf(stderr, "bench: read %llu points with %u threads, expected %llu\n",
                     static_cast<unsigned long long>(points), thread_counts[t],
                     static_cast<unsigned long long>(reader->info().point_count));
        return 1;
      }
      rates[t].push_back(static_cast<double>(points) / wall / 1e6);
      std::printf("  %u thread%s %.2f Mpts/s", thread_counts[t], thread_counts[t] == 1 ? "" : "s",
                  rates[t].back());
    }
    std::printf("\n");
  }
  std::printf("%s: median wall over %d runs (LAS reader, xyz):", path.c_str(), repeats);
  for (std::size_t t = 0; t < thread_counts.size(); ++t)
    std::printf("  %u thread%s %.2f Mpts/s (x%.2f)", thread_counts[t], thread_counts[t] == 1 ? "" : "s",
                median(rates[t]), median(rates[t]) / median(rates[0]));
  std::printf("\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s FILE.laz [repeats=11] [THREADS,THREADS,...]\n", argv[0]);
    return 2;
  }
  const std::string path = argv[1];
  const int repeats = argc > 2 ? std::max(1, std::atoi(argv[2])) : 11;
  try {
    if (argc > 3) {
      std::vector<unsigned> thread_counts;
      for (const char* p = argv[3]; *p != '\0';) {
        char* end = nullptr;
        const unsigned long n = std::strtoul(p, &end, 10);
        if (end == p || n == 0 || n > 256) {
          std::fprintf(stderr, "bench: bad thread list '%s' (e.g. 1,2)\n", argv[3]);
          return 2;
        }
        thread_counts.push_back(static_cast<unsigned>(n));
        p = *end == ',' ? end + 1 : end;
      }
      return compare_threads(path, repeats, thread_counts);
    }
    LaszipVlr vlr;
    LazLayout layout;
    read_layout(path, vlr, layout);
    constexpr std::size_t kBatch = 50000;  // records per decode() call
    std::vector<std::uint8_t> buffer(kBatch * layout.record_length);
    std::vector<double> cpu_rates, wall_rates;
    for (int run = 0; run < repeats; ++run) {
      const double cpu0 = thread_cpu_seconds();
      const auto wall0 = std::chrono::steady_clock::now();
      LazDecoder decoder(vlr, layout);  // includes reading the chunk table, like laz-perf's reader
      std::uint64_t points = 0;
      while (const std::size_t n = decoder.decode(buffer.data(), kBatch)) points += n;
      const double cpu = thread_cpu_seconds() - cpu0;
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
      if (points != layout.point_count) {
        std::fprintf(stderr, "bench: decoded %llu of %llu points\n", static_cast<unsigned long long>(points),
                     static_cast<unsigned long long>(layout.point_count));
        return 1;
      }
      cpu_rates.push_back(static_cast<double>(points) / cpu / 1e6);
      wall_rates.push_back(static_cast<double>(points) / wall / 1e6);
      std::printf("run %2d: %llu points, cpu %.4f s (%.2f Mpts/s), wall %.4f s (%.2f Mpts/s)\n", run + 1,
                  static_cast<unsigned long long>(points), cpu, cpu_rates.back(), wall, wall_rates.back());
    }
    std::printf("%s: median %.2f Mpts/s cpu (best %.2f), %.2f Mpts/s wall (best %.2f), %d runs\n",
                path.c_str(), median(cpu_rates), *std::max_element(cpu_rates.begin(), cpu_rates.end()),
                median(wall_rates), *std::max_element(wall_rates.begin(), wall_rates.end()), repeats);
  } catch (const city3d::Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
