// The per-building report of a batch run, as CSV (one row per input footprint) and JSON, and the
// attributes each building carries into CityJSON and the GeoPackage. Each row is made when its
// building finishes (and kept in the journal); the files are assembled from the rows.
#pragma once

#include <cstdio>
#include <memory>
#include <string>

#include "city3d/run_outputs.hpp"

namespace city3d::detail {

/// The CSV header line (without newline).
std::string report_csv_header();
/// One building's CSV row (without newline).
std::string report_csv_row(const BuildingReport& r);
/// One building's JSON object (one line, without newline).
std::string report_json_row(const BuildingReport& r);

/// Writes report.csv and report.json from rows given one at a time, atomically: the summary (the
/// JSON's first member) must be known before the first row.
class ReportWriter {
 public:
  ReportWriter(const std::string& csv_path, const std::string& json_path, const BatchSummary& summary);
  ~ReportWriter();
  ReportWriter(const ReportWriter&) = delete;
  ReportWriter& operator=(const ReportWriter&) = delete;
  void add(const std::string& csv_row, const std::string& json_row);
  /// Commits both files. Throws IoError.
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A building's own attributes (README, "Attributes"): 3DBAG's names where 3DBAG has the quantity
/// (b3_h_dak_70p, b3_dak_type, b3_volume_lod22, b3_rmse_lod22, ...), city3d's otherwise; numbers
/// rounded to what they mean (heights to the millimetre, volumes to 0.01 m3, RMSE to 0.1 mm); NaN
/// and unknown values are null. "seconds" only with `timings` (it differs from run to run).
Attributes building_attributes(const BuildingReport& report, bool timings);

/// The footprint's attributes (names and types as in the source; a name city3d uses itself, or the
/// GeoPackage's id, fid or geom, in any case, gets the prefix "footprint_", and a number after it where
/// the footprint has that name too), then building_attributes().
Attributes output_attributes(const BuildingReport& report, const Attributes& footprint, bool timings);

}  // namespace city3d::detail
