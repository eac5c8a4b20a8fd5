// Report writers: CSV for spreadsheets and shell tools, JSON for programs. Numbers are printed with
// fixed precision so that reports of identical runs differ only in their timings.
#include "pipeline/report.hpp"

#include <cstdio>

#include "io/atomic_file.hpp"

namespace city3d::detail {
namespace {

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out + "\"";
}

std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

}  // namespace

std::string report_csv_header() {
  return "id,status,level,stage,reason,note,points,ground_points,ground_z,ground_method,roof_z,planes,walls,"
         "candidate_faces,faces,rmse,valid,seconds";
}

std::string report_csv_row(const BuildingReport& r) {
  return csv_field(r.id) + "," + to_string(r.status) + "," + to_string(r.level) + "," + csv_field(r.stage) + "," +
         csv_field(r.reason) + "," + csv_field(r.note) + "," + std::to_string(r.points) + "," +
         std::to_string(r.ground_points) + "," + fixed(r.ground_z, 3) + "," + csv_field(r.ground_method) + "," +
         fixed(r.roof_z, 3) + "," + std::to_string(r.planes) + "," + std::to_string(r.walls) + "," +
         std::to_string(r.candidate_faces) + "," + std::to_string(r.faces) + "," +
         (r.rmse >= 0 ? fixed(r.rmse, 4) : "") + "," + (r.valid ? "1" : "0") + "," + fixed(r.seconds, 4);
}

std::string report_json_row(const BuildingReport& r) {
  return "{\"id\": " + json_string(r.id) + ", \"status\": \"" + to_string(r.status) + "\", \"level\": \"" +
         to_string(r.level) + "\", \"stage\": " + json_string(r.stage) + ", \"reason\": " + json_string(r.reason) +
         ", \"note\": " + json_string(r.note) + ", \"points\": " + std::to_string(r.points) +
         ", \"ground_points\": " + std::to_string(r.ground_points) + ", \"ground_z\": " + fixed(r.ground_z, 3) +
         ", \"ground_method\": " + json_string(r.ground_method) + ", \"roof_z\": " + fixed(r.roof_z, 3) +
         ", \"planes\": " + std::to_string(r.planes) + ", \"walls\": " + std::to_string(r.walls) +
         ", \"candidate_faces\": " + std::to_string(r.candidate_faces) + ", \"faces\": " + std::to_string(r.faces) +
         ", \"rmse\": " + (r.rmse >= 0 ? fixed(r.rmse, 4) : "null") + ", \"valid\": " + (r.valid ? "true" : "false") +
         ", \"seconds\": " + fixed(r.seconds, 4) + "}";
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
  std::fprintf(impl_->json.file(),
               "{\n  \"summary\": {\"buildings\": %zu, \"ok\": %zu, \"fallback\": %zu, \"skipped\": %zu, "
               "\"failed\": %zu, \"seconds\": %s},\n  \"buildings\": [",
               summary.buildings, summary.ok, summary.fallback, summary.skipped, summary.failed,
               fixed(summary.seconds, 3).c_str());
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

}  // namespace city3d::detail
