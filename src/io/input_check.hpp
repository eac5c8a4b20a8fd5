// Checks of a run's inputs taken together, before anything is read in full or written: the same
// tile given twice, point clouds in different or unusable CRSs, footprints that meet no tile.
#pragma once

#include <string>
#include <vector>

#include "city3d/footprint_io.hpp"
#include "city3d/point_cloud_io.hpp"

namespace city3d::detail {

/// What distinct_inputs() drops.
enum class Repeats {
  /// Tiles (with footprints): the same file under another name, a copy of its bytes, and a twin
  /// holding the same points in another encoding (a LAS file and its LAZ): reading a tile twice
  /// would double the points of every building on it.
  tiles,
  /// Single-building clouds: only the same file under another name. Each file is a building, so a
  /// copy is a building of its own (with a warning: it is seldom meant).
  clouds,
};

/// `files` without repeats, first occurrence kept, in order. The same file is one under another
/// name (a second mention, a folder holding a file also given alone, a symbolic or hard link); a
/// copy has the same size and the same first and last 64 KiB; a twin is a LAS or LAZ file with the
/// same header facts (point count, format, record length, scale, offset; bounds within half a scale
/// step) and the same first and last kTwinRecords point records, decompressed. Each dropped file gets a warning naming both.
std::vector<std::string> distinct_inputs(const std::vector<std::string>& files, Repeats repeats = Repeats::tiles);

/// Point records compared at each end of two LAS/LAZ files with the same header facts.
constexpr std::size_t kTwinRecords = 64;

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
