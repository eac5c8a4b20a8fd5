// Decode speed of the LAZ decoder: decodes every record of one LAZ file, several times, on one
// core, and prints points per second (thread CPU time and wall time) per run and the median.
// Usage: bench_laz_decode FILE.laz [repeats=11]
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

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s FILE.laz [repeats=11]\n", argv[0]);
    return 2;
  }
  const std::string path = argv[1];
  const int repeats = argc > 2 ? std::max(1, std::atoi(argv[2])) : 11;
  try {
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
