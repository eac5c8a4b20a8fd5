// The per-building report of a batch run, as CSV (one row per input footprint) and JSON.
#pragma once

#include <string>
#include <vector>

#include "city3d/batch.hpp"

namespace city3d::detail {

/// Writes the CSV report (header + one row per building), atomically. Throws IoError.
void write_report_csv(const std::string& path, const std::vector<BuildingReport>& rows);

/// Writes the JSON report ({"summary": ..., "buildings": [...]}), atomically. Throws IoError.
void write_report_json(const std::string& path, const std::vector<BuildingReport>& rows, const BatchSummary& summary);

}  // namespace city3d::detail
