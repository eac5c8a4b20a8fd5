// Footprint input through GDAL/OGR (Shapefile, GeoPackage, GeoJSON, SQLite, any OGR vector source)
// and City3D's OBJ polygon files. Rings come out normalised (outer counter-clockwise, holes
// clockwise); invalid polygons are repaired or reported and skipped with their id.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "city3d/types.hpp"

namespace city3d {

/// How to read a footprint source.
struct FootprintReadOptions {
  std::string layer;             ///< layer name; empty = the first layer with polygons
  std::string id_field;          ///< attribute holding the building id; empty = the feature id (FID)
  std::string attribute_filter;  ///< OGR SQL WHERE clause, e.g. "bouwjaar > 1900"; empty = all
  std::optional<Box2> bbox;      ///< keep only footprints intersecting this box (OGR spatial filter)
  bool repair = true;            ///< repair invalid polygons with MakeValid; false = skip them
  std::string ground_field;      ///< numeric attribute with the floor height (world z); empty = none
  /// CRS of the point clouds ("EPSG:n" or WKT); empty = unknown. When the source's own CRS is
  /// known and differs, every footprint is reprojected into this one (through OGR/PROJ) and
  /// FootprintSet::srs / reprojected_from say so. --bbox still applies in the source's CRS.
  std::string target_srs;
};

/// A footprint that was not kept, and why.
struct SkippedFootprint {
  BuildingId id;       ///< id when known, else "fid N"
  std::string reason;  ///< e.g. "empty geometry", "self-intersecting polygon, repair failed"
};

/// The footprints of one source plus what happened while reading it.
struct FootprintSet {
  std::string path;
  std::string driver;   ///< OGR driver short name, or "OBJ"
  std::string layer;
  std::string id_field; ///< "FID" when the feature id is used
  std::string srs;      ///< "EPSG:28992" when identified, else WKT, else empty (after any reprojection)
  std::string reprojected_from;  ///< the source's own CRS when the footprints were reprojected, else empty
  std::vector<Footprint> footprints;
  std::vector<SkippedFootprint> skipped;
  std::size_t feature_count = 0;   ///< features read from the layer (after the filters)
  std::size_t repaired = 0;        ///< invalid polygons repaired with MakeValid
  std::size_t with_holes = 0;      ///< footprints with at least one hole
};

/// Reads footprints from an OGR source or an OBJ polygon file (by extension .obj). Throws IoError
/// when the source does not exist, cannot be opened, has no such layer or field, or has no polygon.
FootprintSet read_footprints(const std::string& path, const FootprintReadOptions& options = {});

/// Names of the layers of an OGR source (one entry "obj" for an OBJ file). Throws IoError.
std::vector<std::string> list_footprint_layers(const std::string& path);

}  // namespace city3d
