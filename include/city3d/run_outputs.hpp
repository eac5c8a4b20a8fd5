// Run-level outputs made from the per-building records alone (so a merge of shards can make them
// too): the GeoPackage (footprints with every report attribute, LoD2.2 roof parts) and report.html,
// the run overview a person looks at.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "city3d/model_io.hpp"
#include "city3d/pipeline.hpp"
#include "city3d/types.hpp"

namespace city3d {

/// Everything the overview outputs know about one input footprint (or single-building cloud).
struct OverviewRecord {
  BuildingReport report;
  std::vector<Polygon2> footprint;  ///< world coordinates; empty when unknown (skipped, or a cloud)
  Attributes footprint_attributes;  ///< the source feature's attributes, as read
  /// The highest level of detail written (LoD2.2 when it was made; the model OBJ/PLY hold), world =
  /// local + origin; empty when the building has no model, or when it was not asked for.
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
  /// Throws IoError when it cannot be read.
  virtual OverviewRecord at(std::size_t k, bool levels) const = 0;
};

/// Writes a GeoPackage with two layers: `buildings`, one feature per record (skipped and failed
/// ones included, without geometry when there is no footprint) carrying the footprint's attributes
/// with their types and every report attribute; and `roof_parts`, one feature per roof face of each
/// LoD2.2 model (its plan-view polygon, building id, lowest / highest / mean height in metres, slope
/// and azimuth in degrees, azimuth clockwise from north towards the downhill side). `crs` like
/// "EPSG:28992" or empty. Reads the records three times, one at a time. Deterministic bytes (a fixed
/// timestamp); written to a temporary name and renamed. Throws IoError naming the path.
void write_gpkg(const std::string& path, const OverviewSource& records, const std::string& crs);

/// Writes report.html: one self-contained page (inline SVG, CSS and script; nothing fetched) with
/// the run's summary, a map of the footprints coloured by status or by RMSE, histograms of RMSE,
/// faces and seconds, the worst buildings with their reason, and a 3D view of a chosen building.
/// Reads the records twice, one at a time, and the models it shows once more; the page holds a row
/// per record. Throws IoError naming the path.
void write_report_html(const std::string& path, const OverviewSource& records, const std::string& crs);

}  // namespace city3d
