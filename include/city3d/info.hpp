// `city3d info`: a human-readable summary of what a point-cloud file or a footprint source holds.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "city3d/footprint_io.hpp"
#include "city3d/point_cloud_io.hpp"

namespace city3d {

/// A point-cloud file's header plus what only reading every point tells: the class histogram.
struct PointCloudSummary {
  PointCloudInfo info;
  std::uint64_t points_read = 0;  ///< withheld records not counted
  std::uint64_t withheld = 0;     ///< LAS/LAZ records flagged withheld, left out as deleted
  bool has_classes = false;
  std::array<std::uint64_t, 256> class_counts{};
};

/// Reads the header and streams every point's classification. Throws IoError.
PointCloudSummary summarise_point_cloud(const std::string& path);

/// True when the file is named .las, .laz or .ply (case-insensitive), whether or not it exists, or
/// starts with a point-cloud signature ("LASF" or "ply").
bool looks_like_point_cloud(const std::string& path);

/// The text `city3d info` prints for a point-cloud file (header, count, bounds, class histogram, CRS).
std::string describe_point_cloud(const PointCloudSummary& summary);

/// The text `city3d info` prints for a footprint source (driver, layer, count, id field, SRS, holes,
/// repaired and skipped features with their reasons) and its fields (`fields`, of `features`
/// features: summarise_fields()), those usable as --id-field marked.
std::string describe_footprints(const FootprintSet& footprints, const std::vector<FieldSummary>& fields = {},
                                std::size_t features = 0);

/// The text `city3d evaluate` prints: a model (OBJ or one of ours) against a point cloud: faces,
/// RMSE of the points to the model surface, and validity (closed, 2-manifold, outward, planar faces,
/// no self-intersection). Both are moved to the model's bounding-box centre before any geometry.
/// When `residuals_path` is not empty, every point's distance to the model surface is written there
/// as CSV (`x,y,z,distance`, world coordinates, in the cloud's order), to see where a model misses.
/// Throws IoError when a file cannot be read or the residuals cannot be written.
std::string evaluate_model(const std::string& model_path, const std::string& points_path,
                           const std::string& residuals_path = "");

}  // namespace city3d
