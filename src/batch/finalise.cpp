// Run-level output assembly and output-folder housekeeping (see finalise.hpp).
#include "batch/finalise.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <sstream>

#include <nlohmann/json.hpp>

#include "city3d/error.hpp"
#include "city3d/log.hpp"
#include "city3d/model_io.hpp"
#include "city3d/run_outputs.hpp"
#include "core/in_order.hpp"
#include "files/atomic_file.hpp"
#include "reports/report.hpp"

namespace city3d::detail {
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

constexpr const char* kManifest = "run.json";
// Journal records read together, on the run's threads (for_each_in_order).
constexpr std::size_t kRecordBatch = 64;

// A name run.json may list: a file in the folder, or under models/ or the tileset's folder (its
// tiles), never outside it.
bool run_level_name(const std::string& name) {
  if (name.empty() || name.find("..") != std::string::npos || name[0] == '/') return false;
  const std::size_t slash = name.find('/');
  if (slash == std::string::npos) return true;
  const std::string folder = name.substr(0, slash);
  return folder == "models" || folder == kTilesetFolder;
}

// The names AtomicFile gives its temporary files ("<name>.tmp-<pid>-<n>"), and the journal's.
bool temporary_name(const std::string& name, long& pid) {
  static const std::regex pattern(R"(.+\.tmp-([0-9]+)-[0-9]+)");
  std::smatch m;
  if (std::regex_match(name, m, pattern)) {
    pid = std::stol(m[1].str());
    return true;
  }
  pid = 0;
  return name == "resume.journal.tmp";
}

void remove_temporary_files(const fs::path& folder, bool locked) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    long pid = 0;
    if (!entry.is_regular_file(ec) || !temporary_name(name, pid)) continue;
    // With the folder locked no other city3d writes here, so every temporary file is stale.
    // Without a lock (a file system without flock) only those of processes that are gone are.
    if (!locked && pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM)) continue;
    if (fs::remove(entry.path(), ec)) log_info("output: removed " + entry.path().string() + ", left by a killed run");
  }
}

// The records of a run as the overview outputs read them from their journals: at() may be called from
// several threads (JournalReader reads one line at a time and parses outside its lock).
class JournalOverview : public OverviewSource {
 public:
  JournalOverview(const std::vector<RecordInJournal>& records, const RunLayout& layout)
      : records_(records), layout_(layout) {}
  std::size_t size() const override { return records_.size(); }
  OverviewRecord at(std::size_t k, bool levels) const override {
    BuildingRecord r = records_[k].journal->read(*records_[k].ref);
    return overview_record(r.report_json, r.feature, r.footprint ? std::move(*r.footprint) : Footprint{},
                           layout_.scale, layout_.translate, k, levels);
  }

 private:
  const std::vector<RecordInJournal>& records_;
  const RunLayout& layout_;
};

// A JSON object from its text; an empty object when the text is none.
json json_object_of(const std::string& text) {
  json j = json::parse(text, nullptr, false);
  return j.is_object() ? j : json::object();
}

// The CityJSON metadata member "city3d": the version, where the CRS came from, the parameters.
std::string city3d_metadata(const RunLayout& layout) {
  json j = {{"version", CITY3D_VERSION}};
  if (!layout.crs_source.empty()) j["crs_source"] = layout.crs_source;
  j["parameters"] = json_object_of(layout.parameters);
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

// What report.html says of the run: its CRS and where it came from, its inputs and parameters.
RunDescription run_description(const RunLayout& layout) {
  return {layout.crs, layout.crs_source, layout.inputs, layout.parameters};
}

// What a row's problem is, whatever its numbers: "status: reason", the reason up to its first ';'
// (a further reason), without parenthesised details, digits as '#' ("skipped: duplicated id",
// "failed: planes: no roof plane among # points"). A partial row's reason says how much of it lies
// outside the tiles, or holds other classes only, before any fallback's: one key for each.
std::string problem_key(BuildingStatus status, const std::string& reason) {
  if (status == BuildingStatus::partial)
    return reason.rfind("building points in only", 0) == 0
               ? "partial: building points in only part of the footprint"
               : "partial: partly covered by the tiles given";
  std::string key = std::string(status_name(status)) + ": ";
  int depth = 0;
  bool digits = false;
  for (char c : reason.substr(0, reason.find(';'))) {
    if (c == '(') ++depth;
    if (depth == 0) {
      const bool digit = c >= '0' && c <= '9';
      if (digit && !digits) key += '#';
      if (!digit && !(digits && c == '.')) key += c;
      digits = digit || (digits && c == '.');
    }
    if (c == ')' && depth > 0) --depth;
  }
  while (!key.empty() && key.back() == ' ') key.pop_back();
  return key;
}

}  // namespace

std::string file_stamp_of(const std::string& path) {
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  if (ec) return {};
  const auto time = fs::last_write_time(path, ec).time_since_epoch().count();
  if (ec) return {};
  return std::to_string(size) + " " + std::to_string(time);
}

bool read_manifest(const std::string& dir, RunManifest& manifest) {
  std::ifstream in(fs::path(dir) / kManifest, std::ios::binary);
  if (!in) return false;
  try {
    const json j = json::parse(in);
    RunManifest m;
    m.header.fingerprint = j.at("fingerprint").get<std::string>();
    m.header.shard = j.at("shard").get<int>();
    m.header.shards = j.at("shards").get<int>();
    m.header.expected = j.at("expected").get<std::uint64_t>();
    m.records = j.at("records").get<std::uint64_t>();
    m.seconds = j.at("seconds").get<double>();
    for (const auto& [name, stamp] : j.at("outputs").items()) m.outputs[name] = stamp.get<std::string>();
    manifest = std::move(m);
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

std::vector<std::string> run_level_files(const RunLayout& layout, FinaliseScope scope) {
  if (scope == FinaliseScope::shard) return {"report.csv", "report.json"};
  std::vector<std::string> names;
  if (layout.cityjson) names.push_back("buildings.city.json");
  if (layout.cityjson_seq) names.push_back("buildings.city.jsonl");
  if (layout.merged_file) names.push_back("models" + mesh_extension(layout.format));
  names.push_back("report.csv");
  names.push_back("report.json");
  if (layout.gpkg) names.push_back("buildings.gpkg");
  if (layout.html) names.push_back("report.html");
  // The OBJ models' materials, beside them.
  if (layout.format == MeshFormat::obj && layout.merged_file) names.push_back(kSurfaceMaterialFile);
  if (layout.format == MeshFormat::obj && layout.per_building_files)
    names.push_back(std::string("models/") + kSurfaceMaterialFile);
  if (layout.tiles3d) names.push_back(std::string(kTilesetFolder) + "/tileset.json");
  return names;
}

OutputFolder::OutputFolder(std::string dir, const std::vector<std::string>& rewritten) : dir_(std::move(dir)) {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) throw IoError("output: cannot create " + dir_ + ": " + ec.message());
  // An exclusive lock on the folder itself: two runs writing into one folder would mix their
  // journals. A file system without flock (some cluster mounts) gets no lock, and a warning.
  lock_fd_ = ::open(dir_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  bool locked = false;
  if (lock_fd_ >= 0) {
    if (::flock(lock_fd_, LOCK_EX | LOCK_NB) == 0) {
      locked = true;
    } else if (errno == EWOULDBLOCK) {
      ::close(lock_fd_);
      lock_fd_ = -1;
      throw IoError("output: another city3d process is writing into " + dir_ + "; wait for it or choose another folder");
    } else {
      log_debug("output: cannot lock " + dir_ + ": " + std::strerror(errno));
    }
  }
  remove_temporary_files(dir_, locked);
  remove_temporary_files(fs::path(dir_) / "models", locked);

  // The run-level files of the previous run here: this run rewrites those it writes; those it does
  // not would describe other buildings than the models beside them.
  RunManifest previous;
  if (read_manifest(dir_, previous)) {
    std::string gone;  // removed and not written again: the user should know
    std::size_t tiles_gone = 0;
    const std::string tileset = std::string(kTilesetFolder) + "/tileset.json";
    const bool tiles_rewritten = std::find(rewritten.begin(), rewritten.end(), tileset) != rewritten.end();
    for (const auto& [name, stamp] : previous.outputs) {
      const fs::path file = fs::path(dir_) / name;
      if (!run_level_name(name)) continue;
      if (!stamp.empty() && file_stamp_of(file.string()) == stamp && fs::remove(file, ec)) {
        log_debug("output: removed " + file.string() + " of the previous run");
        const bool tile = name.rfind(std::string(kTilesetFolder) + "/", 0) == 0;
        if (tile) {
          // A tileset is many files: named once, as its folder.
          tiles_gone += !tiles_rewritten;
        } else if (std::find(rewritten.begin(), rewritten.end(), name) == rewritten.end()) {
          gone += (gone.empty() ? "" : ", ") + name;
        }
      }
    }
    if (tiles_gone > 0) gone += (gone.empty() ? "" : ", ") + std::string(kTilesetFolder) + "/ (the tileset)";
    // Its folders, when nothing else is left in them.
    for (const char* folder : {"3dtiles/tiles", "3dtiles"}) fs::remove(fs::path(dir_) / folder, ec);
    if (!gone.empty())
      log_warning("output: removed " + gone + " from " + dir_ + ": the earlier run there wrote " +
                  (gone.find(',') == std::string::npos ? "it" : "them") + ", this one does not");
  }
  fs::remove(fs::path(dir_) / kManifest, ec);
}

OutputFolder::~OutputFolder() {
  if (lock_fd_ >= 0) ::close(lock_fd_);
}

void OutputFolder::remove_earlier_models(const std::vector<std::pair<std::string, std::string>>& models,
                                         bool same_run) {
  std::size_t removed = 0;
  for (const auto& [name, hash] : models) {
    if (name.empty() || name.find('/') != std::string::npos || name[0] == '.') continue;
    const fs::path file = fs::path(dir_) / "models" / name;
    std::error_code ec;
    if (!hash.empty() && file_hash(file.string()) == hash && fs::remove(file, ec)) ++removed;
  }
  if (removed > 0)
    log_warning("output: removed the " + std::to_string(removed) + " model files an earlier run of " +
                (same_run ? "the same inputs and options (not resumed)" : "other inputs or options") +
                " wrote into " + (fs::path(dir_) / "models").string() + "; this run writes its own");
}

void OutputFolder::write_manifest(const RunManifest& m) {
  json outputs = json::object();
  for (const auto& [name, stamp] : m.outputs) outputs[name] = stamp;
  const RunLayout& layout = m.header.layout;
  const json j = {{"city3d", CITY3D_VERSION},
                  {"crs", layout.crs},
                  {"crs_source", layout.crs_source},
                  {"inputs", json_object_of(layout.inputs)},
                  {"parameters", json_object_of(layout.parameters)},
                  {"fingerprint", m.header.fingerprint},
                  {"shard", m.header.shard},
                  {"shards", m.header.shards},
                  {"expected", m.header.expected},
                  {"records", m.records},
                  {"seconds", m.seconds},
                  {"outputs", outputs}};
  AtomicFile file((fs::path(dir_) / kManifest).string());
  const std::string text = j.dump(2, ' ', false, json::error_handler_t::replace) + "\n";
  std::fwrite(text.data(), 1, text.size(), file.file());
  file.commit();
}

BatchSummary finalise_run(const std::string& dir, const RunLayout& layout,
                          const std::vector<RecordInJournal>& records, double seconds, std::size_t resumed,
                          FinaliseScope scope, std::map<std::string, std::string>& outputs,
                          unsigned threads) {
  const fs::path out(dir);
  const bool whole = scope == FinaliseScope::whole_run;
  if (whole) {
    // Every index exactly once: anything else is a bug in the caller, or a merge of the wrong shards.
    if (records.size() != layout.records)
      throw Error("finalise: " + std::to_string(records.size()) + " records for a run of " +
                  std::to_string(layout.records));
    for (std::size_t i = 0; i < records.size(); ++i)
      if (records[i].ref->index != i) throw Error("finalise: record " + std::to_string(i) + " is missing");
  }

  BatchSummary summary;
  summary.buildings = records.size();
  for (const RecordInJournal& r : records) {
    summary.ok += r.ref->status == BuildingStatus::ok;
    summary.fallback += r.ref->status == BuildingStatus::fallback;
    summary.skipped += r.ref->status == BuildingStatus::skipped;
    summary.failed += r.ref->status == BuildingStatus::failed;
    summary.partial += r.ref->status == BuildingStatus::partial;
  }
  summary.seconds = seconds;
  summary.resumed = resumed;
  summary.report_path = (out / "report.csv").string();

  const CityJsonOptions cityjson_options{layout.crs, layout.scale, "", city3d_metadata(layout)};
  std::unique_ptr<CityJsonAssembler> cityjson;
  std::unique_ptr<CityJsonSeqAssembler> seq;
  std::vector<BuildingModel> merged;
  if (whole && layout.cityjson)
    cityjson = std::make_unique<CityJsonAssembler>((out / "buildings.city.json").string(), cityjson_options,
                                                   layout.translate);
  if (whole && layout.cityjson_seq)
    seq = std::make_unique<CityJsonSeqAssembler>((out / "buildings.city.jsonl").string(), cityjson_options,
                                                 layout.translate);
  ReportWriter report((out / "report.csv").string(), (out / "report.json").string(), summary);

  std::map<std::string, std::pair<std::size_t, std::size_t>> problems;  // key -> rows, rows outside every tile
  // The records are read (parsed) a batch at a time on the run's threads, and taken in order.
  const auto read = [&records](std::size_t k) { return records[k].journal->read(*records[k].ref); };
  for_each_in_order(records.size(), threads, kRecordBatch, read, [&](std::size_t, BuildingRecord r) {
    report.add(r.report_csv, r.report_json);
    // A fallback has its model (a lower rung): not a problem of the run.
    if (r.status != BuildingStatus::ok && r.status != BuildingStatus::fallback) {
      const json row = json::parse(r.report_json, nullptr, false);
      if (!row.is_discarded()) {
        auto& [rows, outside] = problems[problem_key(r.status, row.value("reason", std::string()))];
        ++rows;
        const auto coverage = row.find("coverage");
        outside += coverage != row.end() && coverage->is_number() && coverage->get<double>() == 0.0;
      }
    }
    if (r.feature.empty()) return;
    if (cityjson) cityjson->add(r.feature);
    if (seq) seq->add(r.feature);
    if (whole && layout.merged_file) {
      if (!r.mesh)
        throw Error("finalise: record " + std::to_string(r.index) + " (" + r.id + ") holds no mesh");
      merged.push_back(std::move(*r.mesh));
    }
  });

  // The problem most rows share, when more than half do (ties: the first key).
  for (const auto& [key, counts] : problems)
    if (2 * counts.first > summary.buildings && counts.first > summary.main_problem_rows) {
      summary.main_problem = key;
      summary.main_problem_rows = counts.first;
      summary.main_problem_outside = counts.second;
    }

  std::vector<std::string> written;
  if (cityjson) {
    cityjson->close();
    written.push_back("buildings.city.json");
  }
  if (seq) {
    seq->close();
    written.push_back("buildings.city.jsonl");
  }
  if (whole && layout.merged_file) {
    const std::string name = "models" + mesh_extension(layout.format);
    write_models((out / name).string(), merged, {layout.format, layout.local_coordinates});
    written.push_back(name);
  }
  if (whole && layout.format == MeshFormat::obj && layout.merged_file) {
    write_surface_materials((out / kSurfaceMaterialFile).string());
    written.push_back(kSurfaceMaterialFile);
  }
  if (whole && layout.format == MeshFormat::obj && layout.per_building_files) {
    const std::string name = std::string("models/") + kSurfaceMaterialFile;
    fs::create_directories(out / "models");
    write_surface_materials((out / name).string());
    written.push_back(name);
  }
  report.close();
  written.push_back("report.csv");
  written.push_back("report.json");
  // The overview outputs, reading the records again one at a time (a run's records are never all in
  // memory at once).
  if (whole && (layout.gpkg || layout.html || layout.tiles3d)) {
    const JournalOverview overview(records, layout);
    if (layout.tiles3d) {
      for (const std::string& name : write_3dtiles((out / kTilesetFolder).string(), overview, layout.crs))
        written.push_back(std::string(kTilesetFolder) + "/" + name);
    }
    if (layout.gpkg) {
      write_gpkg((out / "buildings.gpkg").string(), overview, layout.crs);
      written.push_back("buildings.gpkg");
    }
    if (layout.html) {
      write_report_html((out / "report.html").string(), overview, run_description(layout), threads);
      written.push_back("report.html");
      summary.report_path = (out / "report.html").string();
    }
  }
  for (const std::string& name : written) outputs[name] = file_stamp_of((out / name).string());
  return summary;
}

}  // namespace city3d::detail
