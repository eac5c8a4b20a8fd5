// LAS 1.0-1.4 reader (private to point_cloud_io): header validation, VLR/EVLR walk, streaming
// conversion of raw point records (formats 0-10) into PointCloud.
#pragma once

#include <memory>
#include <string>

#include "city3d/point_cloud_io.hpp"

namespace city3d::detail {

/// Opens a LAS or LAZ file whose signature has been checked by the caller. Throws IoError on any
/// header problem (all of them in one message) and on an unusable LASzip VLR or chunk table. A LAZ
/// file with several chunks is decoded on `decode_threads` threads (1: in the calling thread).
std::unique_ptr<PointCloudReader> open_las(const std::string& path, PointFields fields,
                                           unsigned decode_threads = 1);

/// Header facts of a LAS or LAZ file (LAZ works: compressed = true, format "LAZ").
PointCloudInfo read_las_info(const std::string& path);

}  // namespace city3d::detail
