// Report writers: CSV for spreadsheets and shell tools, JSON for programs. Numbers are rounded to
// fixed decimals so that reports of identical runs differ only in their timings. report.json's
// objects are made with nlohmann (ordered_json: the keys in the columns' order) and written as
// they come, one building a line.
#include "reports/report.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <set>

#include "files/atomic_file.hpp"

namespace city3d::detail {
namespace {

using ordered_json = nlohmann::ordered_json;

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

// v rounded half away from zero to `decimals` decimals, as the double nearest that decimal:
// round(v x 10^d) is an exact integer and the one division by the exact 10^d rounds once, so
// shortest round-trip printing writes 0.013 (not 0.013000000000000001) and "%.*f" that decimal.
double round_decimals(double v, int decimals) {
  const double f = std::pow(10.0, decimals);
  return std::round(v * f) / f;
}

// Rounded as the building attributes round (round_decimals()), then printed: printf alone rounds the
// exact binary value, and 6.5215 (a median between two millimetres) became 6.521 here but 6.522 in
// CityJSON (20 of 1,280 values of the Delft block). Beyond 1e15 (no decimals left) v as it is.
std::string fixed(double v, int decimals) {
  char buf[64];
  const double r = std::isfinite(v) && std::fabs(v) < 1e15 ? round_decimals(v, decimals) : v;
  std::snprintf(buf, sizeof buf, "%.*f", decimals, r == 0 ? 0.0 : r);
  return buf;
}

// A number for CSV, empty when unknown.
std::string csv_number(double v, int decimals) { return std::isfinite(v) ? fixed(v, decimals) : ""; }

// A number for report.json, the value fixed() prints: nlohmann writes the rounded double in its
// shortest round-trip form, which reads back as that decimal (12.5 for "12.50"). -0 as 0, no
// decimals as an integer (a count: 12, not 12.0), null when unknown.
ordered_json json_number(double v, int decimals) {
  if (!std::isfinite(v)) return nullptr;
  if (std::fabs(v) >= 1e15) return v;
  const double r = round_decimals(v, decimals);
  if (decimals == 0) return static_cast<std::int64_t>(r);
  return r == 0 ? 0.0 : r;
}

// report.json's text of an object: nlohmann's compact form; a byte that is not UTF-8 (an id from a
// footprint file in another encoding) becomes U+FFFD, as the journal keeps it.
std::string compact_json(const ordered_json& j) { return j.dump(-1, ' ', false, ordered_json::error_handler_t::replace); }

// The value nearest to v with `decimals` decimals (round_decimals()); null when not finite.
AttributeValue rounded(double v, int decimals) {
  if (!std::isfinite(v)) return AttributeValue{};
  return round_decimals(v, decimals);
}

AttributeValue text_or_null(const std::string& s) { return s.empty() ? AttributeValue{} : AttributeValue{s}; }

// The report columns that CSV and JSON share beyond the first ones: name, decimals (-1 for text).
struct Extra {
  const char* name;
  int decimals;
  double BuildingReport::*number;
  std::string BuildingReport::*text;
};
const Extra kExtras[] = {
    {"lods", -1, nullptr, &BuildingReport::lods},
    {"lods_reconstructed", -1, nullptr, &BuildingReport::lods_reconstructed},
    {"footprint_area", 2, &BuildingReport::footprint_area, nullptr},
    {"point_density", 2, &BuildingReport::point_density, nullptr},
    {"coverage", 3, &BuildingReport::coverage, nullptr},
    {"point_coverage", 3, &BuildingReport::point_coverage, nullptr},
    {"building_coverage", 3, &BuildingReport::building_coverage, nullptr},
    {"h_roof_50p", 3, &BuildingReport::h_roof_50p, nullptr},
    {"h_roof_70p", 3, &BuildingReport::h_roof_70p, nullptr},
    {"h_roof_min", 3, &BuildingReport::h_roof_min, nullptr},
    {"h_roof_max", 3, &BuildingReport::h_roof_max, nullptr},
    {"h_ridge", 3, &BuildingReport::h_ridge, nullptr},
    {"roof_type", -1, nullptr, &BuildingReport::roof_type},
    {"volume_lod12", 2, &BuildingReport::volume_lod12, nullptr},
    {"volume_lod13", 2, &BuildingReport::volume_lod13, nullptr},
    {"volume_lod22", 2, &BuildingReport::volume_lod22, nullptr},
    {"rmse_lod12", 4, &BuildingReport::rmse_lod12, nullptr},
    {"rmse_lod13", 4, &BuildingReport::rmse_lod13, nullptr},
    {"rmse_lod22", 4, &BuildingReport::rmse_lod22, nullptr},
    {"unexplained_points", 0, &BuildingReport::unexplained_points, nullptr},
    {"unexplained_share", 4, &BuildingReport::unexplained_share, nullptr},
    {"unsupported_area", 2, &BuildingReport::unsupported_area, nullptr},
    {"height_excess", 3, &BuildingReport::height_excess, nullptr},
    {"validity_found", -1, nullptr, &BuildingReport::validity_found},
    {"repairs", -1, nullptr, &BuildingReport::repairs},
};

std::string csv_extras(const BuildingReport& r) {
  std::string extra;
  for (const Extra& e : kExtras) extra += "," + (e.text ? csv_field(r.*e.text) : csv_number(r.*e.number, e.decimals));
  return extra;
}

}  // namespace

std::string report_csv_header() {
  std::string header =
      "id,status,level,stage,reason,note,points,ground_points,ground_z,ground_method,roof_z,planes,walls,"
      "candidate_faces,faces,rmse,valid";
  for (const Extra& e : kExtras) header += std::string(",") + e.name;
  return header + ",cpu_seconds,seconds";  // last: timings, the only columns that differ between identical runs
}

std::string report_csv_row(const BuildingReport& r) {
  return csv_field(r.id) + "," + status_name(r.status) + "," + level_name(r.level) + "," + csv_field(r.stage) + "," +
         csv_field(r.reason) + "," + csv_field(r.note) + "," + std::to_string(r.points) + "," +
         std::to_string(r.ground_points) + "," + fixed(r.ground_z, 3) + "," + csv_field(r.ground_method) + "," +
         fixed(r.roof_z, 3) + "," + std::to_string(r.planes) + "," + std::to_string(r.walls) + "," +
         std::to_string(r.candidate_faces) + "," + std::to_string(r.faces) + "," +
         (r.rmse >= 0 ? fixed(r.rmse, 4) : "") + "," + (r.valid ? "1" : "0") + csv_extras(r) + "," +
         fixed(r.cpu_seconds, 4) + "," + fixed(r.seconds, 4);
}

std::string report_json_row(const BuildingReport& r) {
  ordered_json row;
  row["id"] = r.id;
  row["status"] = status_name(r.status);
  row["level"] = level_name(r.level);
  row["stage"] = r.stage;
  row["reason"] = r.reason;
  row["note"] = r.note;
  row["points"] = r.points;
  row["ground_points"] = r.ground_points;
  row["ground_z"] = json_number(r.ground_z, 3);
  row["ground_method"] = r.ground_method;
  row["roof_z"] = json_number(r.roof_z, 3);
  row["planes"] = r.planes;
  row["walls"] = r.walls;
  row["candidate_faces"] = r.candidate_faces;
  row["faces"] = r.faces;
  row["rmse"] = r.rmse >= 0 ? json_number(r.rmse, 4) : nullptr;
  row["valid"] = r.valid;
  for (const Extra& e : kExtras) row[e.name] = e.text ? ordered_json(r.*e.text) : json_number(r.*e.number, e.decimals);
  row["cpu_seconds"] = json_number(r.cpu_seconds, 4);  // last: timings, as in CSV
  row["seconds"] = json_number(r.seconds, 4);
  return compact_json(row);
}

struct ReportWriter::Impl {
  AtomicFile csv;
  AtomicFile json;
  std::size_t rows = 0;
  Impl(const std::string& c, const std::string& j) : csv(c), json(j) {}
};

ReportWriter::ReportWriter(const std::string& csv_path, const std::string& json_path, const BatchSummary& summary)
    : impl_(new Impl(csv_path, json_path)) {
  std::fputs((report_csv_header() + "\n").c_str(), impl_->csv.file());
  const ordered_json counts = {{"buildings", summary.buildings}, {"ok", summary.ok},
                                {"fallback", summary.fallback}, {"skipped", summary.skipped},
                                {"failed", summary.failed},     {"partial", summary.partial},
                                {"resumed", summary.resumed},   {"seconds", json_number(summary.seconds, 3)}};
  // The frame by hand, the rows streamed into it: the summary first, then one building a line.
  std::fputs(("{\n  \"summary\": " + compact_json(counts) + ",\n  \"buildings\": [").c_str(), impl_->json.file());
}

ReportWriter::~ReportWriter() = default;

void ReportWriter::add(const std::string& csv_row, const std::string& json_row) {
  std::fputs(csv_row.c_str(), impl_->csv.file());
  std::fputc('\n', impl_->csv.file());
  std::fputs(impl_->rows++ ? ",\n    " : "\n    ", impl_->json.file());
  std::fputs(json_row.c_str(), impl_->json.file());
}

void ReportWriter::close() {
  std::fputs("\n  ]\n}\n", impl_->json.file());
  impl_->csv.commit();
  impl_->json.commit();
}

Attributes building_attributes(const BuildingReport& r, bool timings) {
  const auto count = [](std::size_t n) { return AttributeValue{static_cast<std::int64_t>(n)}; };
  const bool written = !r.lods.empty();
  const auto val3dity = [&](const char* lod) {
    // The val3dity codes of the level as written: none, since an invalid model is never written (a
    // list, as 3DBAG's; null for a level not written).
    return written && r.lods.find(lod) != std::string::npos ? AttributeValue{AttributeList{"[]"}} : AttributeValue{};
  };
  Attributes a = {
      {"status", std::string(status_name(r.status))},
      {"level", std::string(level_name(r.level))},
      {"reason", text_or_null(r.reason)},
      {"note", text_or_null(r.note)},
      {"lods", text_or_null(r.lods)},
      {"lods_reconstructed", text_or_null(r.lods_reconstructed)},
      {"b3_h_maaiveld", rounded(r.status == BuildingStatus::skipped && r.points == 0 ? NAN : r.ground_z, 3)},
      {"ground_method", text_or_null(r.ground_method)},
      {"b3_h_dak_50p", rounded(r.h_roof_50p, 3)},
      {"b3_h_dak_70p", rounded(r.h_roof_70p, 3)},
      {"b3_h_dak_min", rounded(r.h_roof_min, 3)},
      {"b3_h_dak_max", rounded(r.h_roof_max, 3)},
      {"h_ridge", rounded(r.h_ridge, 3)},
      {"b3_dak_type", text_or_null(r.roof_type)},
      {"b3_volume_lod12", rounded(r.volume_lod12, 2)},
      {"b3_volume_lod13", rounded(r.volume_lod13, 2)},
      {"b3_volume_lod22", rounded(r.volume_lod22, 2)},
      {"b3_rmse_lod12", rounded(r.rmse_lod12, 4)},
      {"b3_rmse_lod13", rounded(r.rmse_lod13, 4)},
      {"b3_rmse_lod22", rounded(r.rmse_lod22, 4)},
      {"unexplained_points", std::isfinite(r.unexplained_points)
                                 ? AttributeValue{static_cast<std::int64_t>(r.unexplained_points)}
                                 : AttributeValue{}},
      {"unexplained_share", rounded(r.unexplained_share, 4)},
      {"unsupported_area", rounded(r.unsupported_area, 2)},
      {"height_excess", rounded(r.height_excess, 3)},
      {"b3_val3dity_lod12", val3dity("1.2")},
      {"b3_val3dity_lod13", val3dity("1.3")},
      {"b3_val3dity_lod22", val3dity("2.2")},
      {"validity_found", text_or_null(r.validity_found)},
      {"repairs", text_or_null(r.repairs)},
      {"b3_opp_grond", rounded(r.footprint_area, 2)},
      {"point_density", rounded(r.point_density, 2)},
      {"coverage", rounded(r.coverage, 3)},
      {"point_coverage", rounded(r.point_coverage, 3)},
      {"building_coverage", rounded(r.building_coverage, 3)},
      {"points", count(r.points)},
      {"planes", count(r.planes)},
      {"faces", count(r.faces)},
  };
  if (timings) a.emplace_back("seconds", rounded(r.seconds, 3));
  return a;
}

Attributes output_attributes(const BuildingReport& r, const Attributes& footprint, bool timings) {
  Attributes own = building_attributes(r, timings);
  // Names compare as GeoPackage (SQLite) columns do, whatever their case. Besides city3d's own names,
  // the GeoPackage's id, fid and geom columns are taken.
  const auto lower = [](std::string s) {
    std::transform(s.begin(), s.end(), s.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
  };
  std::set<std::string> reserved = {"id", "fid", "geom"};
  for (const auto& o : own) reserved.insert(lower(o.first));
  std::set<std::string> taken = reserved;
  for (const auto& f : footprint) taken.insert(lower(f.first));
  Attributes a;
  for (const auto& [name, value] : footprint) {
    std::string out = name;
    if (reserved.count(lower(name))) {
      out = "footprint_" + name;
      for (int k = 2; taken.count(lower(out)); ++k) out = "footprint_" + name + "_" + std::to_string(k);
      taken.insert(lower(out));
    }
    a.emplace_back(out, value);
  }
  a.insert(a.end(), own.begin(), own.end());
  return a;
}

}  // namespace city3d::detail
