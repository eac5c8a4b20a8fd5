// Checks of a run's inputs taken together, before anything is read in full or written: the same
// tile given twice, point clouds in different or unusable CRSs, footprints that meet no tile.
#pragma once

#include <string>
#include <vector>

#include "city3d/footprint_io.hpp"
#include "city3d/point_cloud_io.hpp"

namespace city3d::detail {

/// `files` without repeats, first occurrence kept, in order. A repeat is the same file under another
/// name (a second mention, a folder holding a file also given alone, a symbolic or hard link) or a
/// copy (same size, same first and last 64 KiB). Each dropped file gets a warning naming both:
/// reading a tile twice would double the points of every building on it.
std::vector<std::string> distinct_inputs(const std::vector<std::string>& files);

/// The CRS the point clouds share ("EPSG:n" or WKT as the files record it), or empty when none of
/// them records one. Throws IoError when two files record different CRSs, or when the CRS is
/// geographic (degrees, where city3d needs metres).
std::string common_point_cloud_crs(const std::vector<std::string>& files, const std::vector<PointCloudInfo>& infos);

/// Throws IoError when none of the footprints' bounding boxes `boxes` (those `footprints` kept, in
/// the points' CRS) meets any point cloud's header bounds (the usual sign of footprints and points
/// in different CRSs), naming both extents and CRSs. Does nothing when there are no footprints or
/// some cloud's bounds are unknown (PLY).
void check_footprints_meet_points(const std::vector<Box2>& boxes, const FootprintSet& footprints,
                                  const std::vector<PointCloudInfo>& infos, const std::string& points_crs);

}  // namespace city3d::detail
