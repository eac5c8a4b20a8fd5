// Footprint input through GDAL/OGR (Shapefile, GeoPackage, GeoJSON, SQLite, any OGR vector source)
// and City3D's OBJ polygon files. Rings come out normalised (outer counter-clockwise, holes
// clockwise); invalid polygons are repaired or reported and skipped with their id.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <utility>
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
  /// Footprints wider or longer than this (metres, bounding box) are skipped: no building is 5 km
  /// across, and one such footprint (a wrong unit or CRS, a placeholder) would take every point of
  /// the tiles into one building.
  double max_extent = 5000.0;
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
  /// Features of the layer without --where and --bbox: counted only when the filters leave none (to
  /// say how many they turned away); else 0.
  std::size_t unfiltered_count = 0;
  std::size_t repaired = 0;        ///< invalid polygons repaired with MakeValid
  std::size_t with_holes = 0;      ///< footprints with at least one hole
};

/// Reads footprints from an OGR source or an OBJ polygon file (by extension .obj). Throws IoError
/// when the source does not exist, cannot be opened, has no such layer or field, or has no polygon.
FootprintSet read_footprints(const std::string& path, const FootprintReadOptions& options = {});

/// One attribute field of a footprint layer, from the values of its features: what `info` shows so
/// that an id field can be found without ogrinfo, and what a non-unique --id-field is told with.
struct FieldSummary {
  std::string name;
  std::string type;          ///< OGR's type name: "String", "Integer", "Integer64", "Real", "Date", ...
  std::size_t values = 0;    ///< features with a value (not null) among those read
  std::size_t distinct = 0;  ///< distinct values among them
  /// Every feature read has a value, and no two the same: the field can be the id field.
  bool unique(std::size_t features) const { return features > 0 && values == features && distinct == values; }
};

/// The fields of a footprint source's layer (options.layer; the attribute filter applied, not the
/// bbox) with their values' counts over its first `max_features` features; `features` receives how
/// many were read. An OBJ file has no fields. Throws IoError as read_footprints() does.
std::vector<FieldSummary> summarise_fields(const std::string& path, const FootprintReadOptions& options,
                                           std::size_t max_features, std::size_t& features);

/// Names of the layers of an OGR source (one entry "obj" for an OBJ file). Throws IoError.
std::vector<std::string> list_footprint_layers(const std::string& path);

/// A footprint simplified for reconstruction: the polygons, and what was done (empty when nothing).
struct SimplifiedFootprint {
  std::vector<Polygon2> polygons;
  std::size_t vertices_before = 0, vertices_after = 0;
  double tolerance = 0.0;  ///< metres; 0 when the footprint was kept as it is
};

/// Footprint polygons of more than `max_vertices` vertices in all (outer rings and holes) are
/// simplified by GEOS's topology-preserving simplifier (no ring made to cross itself or another),
/// with a tolerance of 0.01 m doubled until at most `max_vertices` vertices remain; at most
/// `max_vertices` ones are returned as they are. Deterministic. Each vertex stays within the
/// tolerance of the original boundary. Throws ReconstructionError when no tolerance up to the
/// footprint's size brings it down (not expected for any polygon).
SimplifiedFootprint simplify_footprint(const std::vector<Polygon2>& polygons, std::size_t max_vertices);

/// A footprint source read block by block, for sources too large to hold in memory (a country's
/// footprints): scan() reads every feature once and numbers the footprints it keeps, without keeping
/// their geometry; read_box() then reads the kept footprints of a region through an OGR spatial
/// filter (the driver's index: GeoPackage R-tree, Shapefile .qix, SpatiaLite). A source whose
/// features have no unique feature ids (FID), and an OBJ file, are held in memory instead.
class FootprintSource {
 public:
  FootprintSource(std::string path, FootprintReadOptions options);
  ~FootprintSource();
  FootprintSource(const FootprintSource&) = delete;
  FootprintSource& operator=(const FootprintSource&) = delete;

  /// Reads every feature once, with the filters, rules and messages of read_footprints(), and calls
  /// `kept` for each footprint read_footprints() would keep, with its number (0, 1, ... in the order
  /// read_footprints() returns them). Returns the source's description and skipped features (no
  /// footprints). Call once, before read_box(). Throws IoError as read_footprints() does.
  FootprintSet scan(const std::function<void(std::size_t number, const Footprint& footprint)>& kept);

  /// The kept footprints (as scan() numbered them) whose polygons may meet `box`: every one whose
  /// polygon meets it, and possibly others whose bounding box does; sorted by number. Throws IoError.
  std::vector<std::pair<std::size_t, Footprint>> read_box(const Box2& box) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace city3d
