// LAS 1.0-1.4 reader (private to point_cloud_io): header validation, VLR/EVLR walk, streaming
// conversion of raw point records (formats 0-10) into PointCloud.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "city3d/point_cloud_io.hpp"

namespace city3d::detail {

/// Opens a LAS or LAZ file whose signature has been checked by the caller. Throws IoError on any
/// header problem (all of them in one message) and on an unusable LASzip VLR or chunk table. A LAZ
/// file with several chunks is decoded on `decode_threads` threads (1: in the calling thread). With
/// `extents` and `regions`, as open_point_cloud(path, fields, threads, extents, regions).
std::unique_ptr<PointCloudReader> open_las(const std::string& path, PointFields fields,
                                           unsigned decode_threads = 1, ChunkExtents* extents = nullptr,
                                           const std::vector<Box2>* regions = nullptr);

/// Header facts of a LAS or LAZ file (LAZ works: compressed = true, format "LAZ").
PointCloudInfo read_las_info(const std::string& path);

/// The raw point records at both ends of a LAS or LAZ file: the first min(n, count) records, then
/// the last min(n, count) (so a file of fewer than 2n points gives some twice), record_length bytes
/// each, decompressed for LAZ. A LAZ file of several chunks decodes its first and last chunk only;
/// one of a single stream (compressor 1) is decoded through. What tells a LAS file and its LAZ twin
/// (the same records, other bytes) without reading either whole. Throws IoError as open_las() does.
std::string read_las_end_records(const std::string& path, std::size_t n);

}  // namespace city3d::detail
