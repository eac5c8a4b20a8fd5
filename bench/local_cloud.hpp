// A single-building cloud as the benchmarks hand it to a stage: read (xyz) and moved to a local frame
// by subtracting its bounding box's centre.
#pragma once

#include <string>
#include <vector>

#include "city3d/point_cloud_io.hpp"

namespace city3d::bench {

inline std::vector<Point3> local_points(const std::string& path) {
  const PointCloud cloud = read_point_cloud(path, kFieldXyz);
  Box3 box;
  for (const auto& p : cloud.points) box.add(p);
  const Point3 centre{(box.min.x + box.max.x) / 2, (box.min.y + box.max.y) / 2, (box.min.z + box.max.z) / 2};
  std::vector<Point3> local;
  local.reserve(cloud.points.size());
  for (const auto& p : cloud.points) local.push_back({p.x - centre.x, p.y - centre.y, p.z - centre.z});
  return local;
}

}  // namespace city3d::bench
