// The per-building report of a batch run, as CSV (one row per input footprint) and JSON. Each row is
// made when its building finishes (and kept in the journal); the files are assembled from the rows.
#pragma once

#include <cstdio>
#include <memory>
#include <string>

#include "city3d/batch.hpp"

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

}  // namespace city3d::detail
