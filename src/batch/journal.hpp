// The journal of a batch run (resume.journal in the output folder): one line per finished building,
// holding everything the run-level files need from it (its CityJSONFeature text, report rows, model
// file name and hash), appended and flushed as buildings finish, so that a run killed at any point
// resumes without recomputing or losing finished buildings, and so that the run-level files (and a
// merge of shards) are a function of these records alone. Every line carries a checksum: a damaged
// line, or a model file that no longer matches its recorded hash, is recomputed with a warning.
#pragma once

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "city3d/batch.hpp"

namespace city3d::detail {

/// One finished building (or one skipped footprint) as the run-level files need it.
struct BuildingRecord {
  std::uint64_t index = 0;  ///< position in the run's output order (input order; skipped footprints last)
  BuildingId id;
  BuildingStatus status = BuildingStatus::failed;
  std::string report_csv;   ///< its report.csv row, without newline
  std::string report_json;  ///< its report.json object, one line
  std::string feature;      ///< its CityJSONFeature text (one line); empty when it has no model
  std::string model_file;   ///< file name under models/ (empty when none was written)
  std::string model_hash;   ///< content_hash() of that file
  std::optional<BuildingModel> mesh;  ///< the model itself, kept only when a run-level file needs it (--merged)
  /// The input footprint as read: its polygons (world coordinates) and the source's attributes with
  /// their types, nothing else of it. Kept only when the overview outputs (buildings.gpkg,
  /// report.html) need it, so that a merge of shards makes them from the records alone.
  std::optional<Footprint> footprint;
};

/// What the run-level files of a run look like: the same for every shard of it.
struct RunLayout {
  std::string crs;               ///< "EPSG:7415", "EPSG:28992" or empty (resolve_run_crs())
  std::string crs_source;        ///< where the CRS came from: "--crs", "point clouds", "footprints"; empty without one
  Point3 translate{0, 0, 0};     ///< CityJSON transform translation (from the inputs' extent, z = 0)
  double scale = 0.001;          ///< CityJSON transform scale
  std::uint64_t records = 0;     ///< records of the whole run: buildings, then skipped footprints
  bool cityjson = true;
  bool cityjson_seq = false;
  bool merged_file = false;
  bool per_building_files = true;
  bool local_coordinates = false;
  MeshFormat format = MeshFormat::obj;
  bool gpkg = false;             ///< buildings.gpkg
  bool html = false;             ///< report.html
  bool tiles3d = false;          ///< 3dtiles/tileset.json and its content
  /// What the run was given, as JSON objects: the options that describe its outputs
  /// (BatchOptions::parameters) and its inputs ({"point_clouds": [canonical paths], "footprints":
  /// ..., "layer": ..., "id_field": ...}), for the metadata of CityJSON, run.json and report.html.
  std::string parameters = "{}";
  std::string inputs = "{}";
};

/// The first line of a journal: which run (and which shard of it) the records belong to.
struct JournalHeader {
  std::string fingerprint;      ///< batch_fingerprint() of the inputs and parameters
  int shard = 0;                ///< 1..shards; 0 for a whole run
  int shards = 0;               ///< 0 for a whole run
  double block_size = 0.0;      ///< the block size the shards were cut with (shards only)
  std::uint64_t expected = 0;   ///< records this journal holds when its run (or shard) is complete
  RunLayout layout;
  bool same_run(const JournalHeader& o) const;
};

/// Where one valid record sits in a journal file, with what is needed without reading it.
struct RecordRef {
  std::uint64_t index = 0;
  BuildingId id;
  BuildingStatus status = BuildingStatus::failed;
  std::string model_file, model_hash;
  std::uint64_t offset = 0;  ///< byte offset of its line
  std::size_t length = 0;    ///< line length without the newline
};

/// Reads a journal file. Complete lines with a good checksum are records (a later record of the
/// same index replaces an earlier one); damaged lines and a truncated last line are counted.
class JournalReader {
 public:
  /// Throws IoError when the file cannot be read.
  explicit JournalReader(std::string path);
  /// A journal this process has just written (Journal::take_written()): its records as written, not read
  /// back and parsed; each is still checked when read(). The same records the constructor above would
  /// find in the file.
  JournalReader(std::string path, JournalHeader header, std::vector<RecordRef> written);
  const std::string& path() const { return path_; }
  /// False when the first line is missing, damaged or not a city3d journal of this version.
  bool header_ok() const { return header_ok_; }
  const JournalHeader& header() const { return header_; }
  /// The valid records in file order.
  const std::vector<RecordRef>& records() const { return records_; }
  /// 1-based line numbers of damaged lines (bad checksum or unreadable), with the id when readable.
  const std::vector<std::pair<std::size_t, std::string>>& damaged() const { return damaged_; }
  /// Reads one record back; throws IoError when its line changed since it was checked.
  BuildingRecord read(const RecordRef& ref) const;
  /// The exact text of a record's line (without newline). Both may be called from several threads.
  std::string line(const RecordRef& ref) const;

 private:
  std::string path_;
  bool header_ok_ = false;
  JournalHeader header_;
  std::vector<RecordRef> records_;
  std::map<std::uint64_t, std::size_t> position_of_index_;  ///< where each index is in records_
  std::vector<std::pair<std::size_t, std::string>> damaged_;
  void add_record(RecordRef ref);  ///< a later record of an index replaces the earlier one, in its place
  mutable std::ifstream in_;  ///< kept open for read() and line()
  mutable std::mutex in_mutex_;  ///< one reader of in_ at a time (the parsing is outside it)
};

/// The journal a run writes into its output folder.
class Journal {
 public:
  /// Opens `<output_dir>/resume.journal`: with `resume`, keeps the records of a journal of the same
  /// run whose checksum and model file (under output_dir/models) are good, warning about every
  /// record it drops; rewrites the file with the kept records and keeps it open for appending.
  /// A journal of another run is set aside: its model files are reported by earlier_models().
  /// Throws IoError when the file cannot be written.
  Journal(const std::string& output_dir, JournalHeader header, bool resume);
  ~Journal();
  Journal(const Journal&) = delete;
  Journal& operator=(const Journal&) = delete;

  const std::string& path() const { return path_; }
  /// The finished record of this index, or nullptr.
  const RecordRef* find(std::uint64_t index) const;
  std::size_t restored() const { return done_.size(); }
  /// Appends one record and flushes it to the operating system. Thread-safe.
  void append(const BuildingRecord& record);
  /// Flushes and closes the file (the destructor does too).
  void close();
  /// Every record line of the file, in file order, as JournalReader would read it back: the kept
  /// records of a resumed journal, then those appended. After close(), for the run's finalise: the
  /// list is handed over (moved out).
  std::vector<RecordRef> take_written();
  /// Model files (name under models/, content hash) an earlier run recorded in this folder's journal,
  /// when it is not resumed (other inputs or parameters, or --no-resume).
  const std::vector<std::pair<std::string, std::string>>& earlier_models() const { return earlier_models_; }
  /// Whether those are of a journal of the same run, not resumed (--no-resume; a merge's folder).
  bool earlier_of_the_same_run() const { return earlier_same_run_; }

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
  std::mutex mutex_;
  std::map<std::uint64_t, RecordRef> done_;
  std::vector<RecordRef> written_;  ///< the kept records, as rewritten
  // The appended records, without a string of their own each (worker threads append them: small
  // allocations that live through the run would be scattered over every thread's heap, 4-6 MB more
  // peak memory on the synthetic tile): their strings one after another in appended_text_.
  struct Appended {
    std::uint64_t index, offset;
    std::size_t length;
    BuildingStatus status;
    std::size_t id_end, model_file_end, model_hash_end;  ///< where each string ends in appended_text_
  };
  std::vector<Appended> appended_;
  std::string appended_text_;
  std::uint64_t size_ = 0;  ///< the file's size: where the next line begins
  std::vector<std::pair<std::string, std::string>> earlier_models_;
  bool earlier_same_run_ = false;
};

/// Writes a journal that holds `header` and `count` record lines, line_at(k) giving the k-th (as
/// JournalReader::line() returns it), atomically; one line is held at a time. Used by merge to leave a
/// journal beside the merged output.
void write_journal(const std::string& path, const JournalHeader& header, std::size_t count,
                   const std::function<std::string(std::size_t)>& line_at);

/// A fingerprint of everything that determines the records of a run: the version, the input files
/// (canonical path, size, modification time) and every option that changes a building's outputs.
std::string batch_fingerprint(const BatchOptions& options, const std::vector<std::string>& point_cloud_files);

/// A 64-bit FNV-1a hash of some bytes as 16 hex digits: any single changed byte changes it.
std::string content_hash(const std::string& bytes);
/// content_hash() of a file's bytes; empty when it cannot be read.
std::string file_hash(const std::string& path);

}  // namespace city3d::detail
