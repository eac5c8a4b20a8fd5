// Run-level outputs made from the per-building records alone (so a merge of shards can make them
// too): the GeoPackage (footprints with every report attribute, LoD2.2 roof parts) and report.html,
// the run overview a person looks at.
#pragma once

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
  std::vector<CityGeometry> lods;   ///< the levels written, world = local + origin
};

/// The overview records of a run from its journal records in output order: each building's
/// report.json object and CityJSONFeature text (empty when it has no model; vertices quantised with
/// `scale` and `translate`), matched with `footprints` by position (the first footprints.size()
/// records; the skipped footprints come after them and have none). Throws IoError when a text is
/// not what the run wrote.
std::vector<OverviewRecord> overview_records(const std::vector<std::string>& report_json,
                                             const std::vector<std::string>& features,
                                             const std::vector<Footprint>& footprints, double scale,
                                             const Point3& translate);

/// Writes a GeoPackage with two layers: `buildings`, one feature per record (skipped and failed
/// ones included, without geometry when there is no footprint) carrying the footprint's attributes
/// with their types and every report attribute; and `roof_parts`, one feature per roof face of each
/// LoD2.2 model (its plan-view polygon, building id, lowest / highest / mean height in metres, slope
/// and azimuth in degrees, azimuth clockwise from north towards the downhill side). `crs` like
/// "EPSG:28992" or empty. Deterministic bytes (a fixed timestamp); written to a temporary name and
/// renamed. Throws IoError naming the path.
void write_gpkg(const std::string& path, const std::vector<OverviewRecord>& records, const std::string& crs);

/// Writes report.html: one self-contained page (inline SVG, CSS and script; nothing fetched) with
/// the run's summary, a map of the footprints coloured by status or by RMSE, histograms of RMSE,
/// faces and seconds, the worst buildings with their reason, and a 3D view of a chosen building.
/// Throws IoError naming the path.
void write_report_html(const std::string& path, const std::vector<OverviewRecord>& records, const std::string& crs);

}  // namespace city3d
