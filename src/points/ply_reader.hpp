// PLY reader (private to point_cloud_io): ascii, binary little and big endian; the vertex element
// becomes a PointCloud, every other element is skipped.
#pragma once

#include <memory>
#include <string>

#include "city3d/point_cloud_io.hpp"

namespace city3d::detail {

/// Opens a PLY file and parses its header. Throws IoError naming the file and the problem.
std::unique_ptr<PointCloudReader> open_ply(const std::string& path, PointFields fields);

/// Header facts of a PLY file (point_count = number of vertices; bounds stay empty).
PointCloudInfo read_ply_info(const std::string& path);

}  // namespace city3d::detail
