// Run-level outputs made from the per-building records alone (so a merge of shards can make them
// too): the GeoPackage (footprints with every report attribute, each level's roof parts and
// models), the 3D Tiles tileset, and report.html, the run overview a person looks at.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "city3d/model_io.hpp"
#include "city3d/building_report.hpp"
#include "city3d/footprint_io.hpp"
#include "city3d/types.hpp"

namespace city3d {

/// Counts of one batch run.
struct BatchSummary {
  std::size_t buildings = 0, ok = 0, fallback = 0, skipped = 0, failed = 0;
  std::size_t partial = 0;  ///< reconstructed from points that cover too little of the footprint
  std::size_t resumed = 0;  ///< buildings taken from the journal of an earlier run into the folder
  double seconds = 0.0;     ///< this run's wall time (a resumed run's own; a merge: its shards' sum)
  std::string report_path;  ///< report.html when the run wrote it, else report.csv
  /// When more than half of the rows share one problem (a status skipped, failed or partial and its
  /// reason, numbers left out: "skipped: no building points inside the footprint"): that problem,
  /// the rows that have it and, of those, the footprints outside every tile given (coverage 0).
  /// Empty otherwise.
  std::string main_problem;
  std::size_t main_problem_rows = 0;
  std::size_t main_problem_outside = 0;
  /// One line naming the main problem and its likely fix (the tiles have no building class, these
  /// classes are present; the footprints lie outside the tiles; ...); empty without a main problem.
  std::string advice;
  /// Nothing was reconstructed: every row is skipped or failed.
  bool nothing_built() const { return ok + fallback + partial == 0; }
};

/// Everything the overview outputs know about one input footprint (or single-building cloud).
struct OverviewRecord {
  BuildingReport report;
  std::vector<Polygon2> footprint;  ///< world coordinates; empty when unknown (skipped, or a cloud)
  Attributes footprint_attributes;  ///< the source feature's attributes, as read
  /// Every level of detail written, lowest first (the last is the highest, which the model OBJ/PLY
  /// hold), world = local + origin; empty when the building has no model, or when it was not asked for.
  std::vector<CityGeometry> lods;
};

/// The overview record of one building from its journal record: its report.json object and
/// CityJSONFeature text (empty when it has no model; vertices quantised with `scale` and
/// `translate`) and its footprint (polygons and attributes; none for skipped footprints and clouds).
/// `position` names it in errors; without `levels` the feature is not parsed. Throws IoError when a
/// text is not what the run wrote.
OverviewRecord overview_record(const std::string& report_json, const std::string& feature, Footprint footprint,
                               double scale, const Point3& translate, std::size_t position, bool levels);

/// The overview records of a run, in output order, read one at a time: a run's records can be
/// millions, and the writers below never hold them all.
class OverviewSource {
 public:
  virtual ~OverviewSource() = default;
  virtual std::size_t size() const = 0;
  /// Record k (0 <= k < size()); with `levels` false, without its levels of detail (cheaper).
  /// Throws IoError when it cannot be read. write_report_html() with more than one thread calls it
  /// from several threads at once.
  virtual OverviewRecord at(std::size_t k, bool levels) const = 0;
};

/// Writes a GeoPackage laid out as 3DBAG's: `buildings`, one feature per record (skipped and failed
/// ones included, without geometry when there is no footprint) carrying the footprint's attributes
/// with their types and every report attribute (lists as JSON text); for each level of detail (1.2,
/// 1.3, 2.2) `lodXX_2d`, one feature per roof face of the level's model (its plan-view polygon,
/// building id, ground height, lowest / highest / mean height in metres, slope and azimuth in
/// degrees, azimuth clockwise from north towards the downhill side, plan area), and `lodXX_3d`, one
/// MultiPolygonZ feature per building with the level (its faces, grounds, walls then roofs, and
/// their semantic types in the JSON list `surfaces`; id, status, ground and highest height, volume,
/// RMSE, val3dity codes); and `roof_parts`, a view of lod22_2d with earlier versions' columns.
/// `crs` like "EPSG:7415" or empty. Reads the records three times, one at a time. Deterministic
/// bytes (a fixed timestamp); written to a temporary name and renamed. Throws IoError naming the path.
void write_gpkg(const std::string& path, const OverviewSource& records, const std::string& crs);

/// What report.html says of the run itself.
struct RunDescription {
  std::string crs;         ///< "EPSG:7415", or empty
  std::string crs_source;  ///< "--crs", "point clouds", "footprints", or empty
  std::string inputs;      ///< JSON object: point_clouds, footprints, layer, id_field
  std::string parameters;  ///< JSON object: option name -> value
};

/// Writes report.html: one self-contained page (inline SVG, CSS and script; nothing fetched) with
/// the run's summary, its inputs, CRS and parameters, a map of the footprints (or, for
/// single-building clouds, of the outlines inferred from their points, side by side) coloured by
/// status or by RMSE, with a scale bar and each building's figures on hover, histograms of RMSE,
/// faces and seconds, the worst buildings with their reason, and a 3D view of a chosen building.
/// Reads the records twice, a few dozen at a time on up to `threads` threads (parsing them is most of
/// its work), and the models it shows once more; the page holds a row per record and does not depend
/// on `threads`. Throws IoError naming the path.
void write_report_html(const std::string& path, const OverviewSource& records, const RunDescription& run,
                       unsigned threads = 1);

/// The folder of the tileset in a run's output folder.
constexpr const char* kTilesetFolder = "3dtiles";

/// Writes a 3D Tiles 1.1 tileset into `folder`: `tileset.json` and binary glTF content under
/// `tiles/`, and returns the names written (relative to `folder`, tileset.json last). The buildings
/// (those with a model) are grouped by a quadtree of their plan-view centres, at most 64 per leaf;
/// each leaf is a tile of LoD1.2 (each building's lowest level), refined (REPLACE) by a tile of
/// LoD2.2 (its highest). Each glTF holds per semantic surface a primitive with its material and the
/// building of each vertex as an EXT_mesh_features feature ID, and the buildings' id and attributes
/// in an EXT_structural_metadata property table. Vertices go from `crs` (the run's, horizontal or
/// compound) to the globe through PROJ (see tiles_writer.cpp). Reads every record twice, one at a
/// time. Deterministic bytes. Throws IoError naming the folder; ConfigError when `crs` cannot be
/// placed on the globe.
std::vector<std::string> write_3dtiles(const std::string& folder, const OverviewSource& records, const std::string& crs);

}  // namespace city3d
