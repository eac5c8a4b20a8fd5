// Fuzz harness: LAZ decoding (LASzip VLR, chunk table, compressors 1-3, every item decoder) through
// the LAS reader, once in the calling thread and once on three decoding threads (the parallel chunk
// path): both must give the same points and the same error. Before an error, the two paths may hand
// out a different number of good points (the parallel one hands out every chunk before the broken
// one; the streaming one loses the records of its last read): those they both gave must agree.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/point_cloud_io.hpp"
#include "fuzz_input.hpp"

namespace {

struct Decoded {
  std::vector<city3d::Point3> points;
  std::vector<std::uint8_t> classes;
  std::string error;
};

Decoded decode(const std::string& path, unsigned threads) {
  Decoded d;
  try {
    auto reader = city3d::open_point_cloud(path, city3d::kFieldAll, threads);
    city3d::PointCloud cloud;
    while (reader->read(cloud, 4093) > 0) {
      d.points.insert(d.points.end(), cloud.points.begin(), cloud.points.end());
      d.classes.insert(d.classes.end(), cloud.classification.begin(), cloud.classification.end());
      cloud.clear();
    }
  } catch (const city3d::Error& e) {
    d.error = e.what();
  }
  return d;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  city3d::fuzz::quiet_logging();
  const city3d::fuzz::MemoryFile file(data, size);
  const Decoded one = decode(file.path(), 1);
  const Decoded three = decode(file.path(), 3);
  if (one.error != three.error) __builtin_trap();
  if (one.error.empty() && (one.points.size() != three.points.size() || one.classes != three.classes)) __builtin_trap();
  const std::size_t common = std::min(one.points.size(), three.points.size());
  if (common > 0 && std::memcmp(one.points.data(), three.points.data(), common * sizeof(city3d::Point3)) != 0)
    __builtin_trap();
  if (!std::equal(one.classes.begin(), one.classes.begin() + static_cast<std::ptrdiff_t>(std::min(common, one.classes.size())),
                  three.classes.begin()))
    __builtin_trap();
  return 0;
}
