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

/// Everything the run-level outputs know about one input footprint (or single-building cloud).
struct BuildingRecord {
  BuildingReport report;
  std::vector<Polygon2> footprint;  ///< world coordinates; empty when unknown (skipped, or a cloud)
  Attributes footprint_attributes;  ///< the source feature's attributes, as read
  std::vector<CityGeometry> lods;   ///< the levels written, world = local + origin
};

/// The records of a run in report order: `rows` (one per input footprint, the skipped ones last),
/// matched with `footprints` (the first footprints->size() rows, in order; nullptr for clouds) and
/// with the written city objects by id.
std::vector<BuildingRecord> building_records(const std::vector<BuildingReport>& rows,
                                             const std::vector<Footprint>* footprints,
                                             const std::vector<CityObject>& objects);

/// Writes a GeoPackage with two layers: `buildings`, one feature per record (skipped and failed
/// ones included, without geometry when there is no footprint) carrying the footprint's attributes
/// with their types and every report attribute; and `roof_parts`, one feature per roof face of each
/// LoD2.2 model (its plan-view polygon, building id, lowest / highest / mean height in metres, slope
/// and azimuth in degrees, azimuth clockwise from north towards the downhill side). `crs` like
/// "EPSG:28992" or empty. Deterministic bytes (a fixed timestamp); written to a temporary name and
/// renamed. Throws IoError naming the path.
void write_gpkg(const std::string& path, const std::vector<BuildingRecord>& records, const std::string& crs);

/// Writes report.html: one self-contained page (inline SVG, CSS and script; nothing fetched) with
/// the run's summary, a map of the footprints coloured by status or by RMSE, histograms of RMSE,
/// faces and seconds, the worst buildings with their reason, and a 3D view of a chosen building.
/// Throws IoError naming the path.
void write_report_html(const std::string& path, const std::vector<BuildingRecord>& records, const std::string& crs);

}  // namespace city3d
