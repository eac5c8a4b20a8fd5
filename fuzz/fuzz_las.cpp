// Fuzz harness: the LAS reader (header validation, VLR/EVLR walk, point records of formats 0-10) as
// city3d uses it: header only, then every point with every attribute, in small reads. A city3d::Error
// is the expected answer to a broken file; anything else (a crash, another exception, a leak, a
// hang, an allocation the file cannot justify) is a bug.
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
    while (const std::size_t n = reader->read(cloud, 997)) {
      total += n;
      // Every attribute vector is empty or exactly as long as the points (PointCloud's invariant).
      for (const std::size_t s : {cloud.intensity.size(), cloud.classification.size(), cloud.gps_time.size(),
                                  cloud.rgb.size(), cloud.return_number.size()})
        if (s != 0 && s != cloud.size()) __builtin_trap();
      for (const city3d::Point3& p : cloud.points)
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) __builtin_trap();
      cloud.clear();
    }
    // A reader that finishes without an error delivered exactly the points its header announced,
    // less those flagged withheld (which the LAS specification says to leave out).
    if (total + reader->withheld_points() != info.point_count) __builtin_trap();
  } catch (const city3d::Error&) {
  }
  return 0;
}
