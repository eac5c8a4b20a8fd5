// Fuzz harness: the PLY reader (ascii and binary headers, every scalar type, list properties,
// elements before the vertex element), header only and then every vertex in small reads.
#include <cmath>
#include <cstdint>

#include "city3d/error.hpp"
#include "city3d/point_cloud_io.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  city3d::fuzz::quiet_logging();
  const city3d::fuzz::MemoryFile file(data, size);
  try {
    const city3d::PointCloudInfo info = city3d::read_point_cloud_info(file.path());
    auto reader = city3d::open_point_cloud(file.path(), city3d::kFieldAll);
    city3d::PointCloud cloud;
    std::uint64_t total = 0;
    while (const std::size_t n = reader->read(cloud, 509)) {
      total += n;
      for (const std::size_t s : {cloud.intensity.size(), cloud.classification.size(), cloud.rgb.size(),
                                  cloud.normals.size()})
        if (s != 0 && s != cloud.size()) __builtin_trap();
      cloud.clear();
    }
    if (total != info.point_count) __builtin_trap();
  } catch (const city3d::Error&) {
  }
  return 0;
}
