// PointCloud, the points of every stage: world coordinates and the attributes a file can give,
// each attribute either absent or one value per point. Read by points/ (point_cloud_io.hpp).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "city3d/types.hpp"

namespace city3d {

/// Attributes a reader can fill, combined as a bit mask. xyz is always read.
enum PointField : std::uint32_t {
  kFieldXyz = 0,
  kFieldIntensity = 1u << 0,
  kFieldReturns = 1u << 1,         ///< return number and number of returns
  kFieldClassification = 1u << 2,  ///< LAS class (extended 8-bit class for formats 6-10), PLY class/label
  kFieldGpsTime = 1u << 3,
  kFieldRgb = 1u << 4,
  kFieldNormal = 1u << 5,          ///< PLY nx/ny/nz
  kFieldAll = 0xFFFFFFFFu,
};
using PointFields = std::uint32_t;

/// Points with optional attributes. `points` is always filled; every other vector is either empty
/// (attribute absent from the file or not requested) or exactly as long as `points`.
struct PointCloud {
  std::vector<Point3> points;                         ///< world coordinates, metres
  std::vector<std::uint16_t> intensity;
  std::vector<std::uint8_t> return_number;
  std::vector<std::uint8_t> number_of_returns;
  std::vector<std::uint8_t> classification;
  std::vector<double> gps_time;
  std::vector<std::array<std::uint16_t, 3>> rgb;
  std::vector<std::array<float, 3>> normals;

  std::size_t size() const { return points.size(); }
  bool empty() const { return points.empty(); }
  void clear();
  /// Appends all points (and the attributes both clouds have) of `other`.
  void append(const PointCloud& other);
};

}  // namespace city3d
