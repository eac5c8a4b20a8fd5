// The end of a run, shared by run_batch() and merge: every run-level file (CityJSON, CityJSONSeq,
// models.<ext>, report.csv, report.json, buildings.gpkg, report.html) is a function of the journal
// records in index order, so a merge of shards writes exactly what one process writes. Also the output folder's housekeeping: a
// lock, temporary files of killed runs, outputs of earlier runs, and run.json (written last: its
// presence means the run or shard finished).
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "city3d/batch.hpp"
#include "city3d/run_outputs.hpp"
#include "batch/journal.hpp"

namespace city3d::detail {

/// A record as finalise_run() reads it, parsed already by the worker that wrote it: the record its
/// line holds and, when the run-level files need it, its overview record (with its levels of detail).
struct ParsedRecord {
  BuildingRecord record;
  std::optional<OverviewRecord> overview;
};

/// One record to finalise: where it is, and the record parsed when its worker kept it (the files
/// are the same either way: the run's end then need not read it back and parse it on one thread).
struct RecordInJournal {
  const JournalReader* journal = nullptr;
  const RecordRef* ref = nullptr;
  const ParsedRecord* parsed = nullptr;
};

/// What a finished run (or shard) leaves in run.json.
struct RunManifest {
  JournalHeader header;
  std::uint64_t records = 0;  ///< records finalised
  double seconds = 0.0;       ///< wall time of the run (a merge: the sum of its shards')
  /// Run-level files written (name in the folder -> "size mtime"), so that a later run can tell
  /// whether they are still city3d's own.
  std::map<std::string, std::string> outputs;
};

/// What finalise_run() writes.
enum class FinaliseScope {
  whole_run,  ///< every run-level file of the layout
  shard,      ///< only report.csv and report.json of the shard's records
};

/// The records a run's workers append to the journal, parsed by them for finalise_run() while the
/// budget of line text lasts (a city block's records are all kept; of a larger run, those finished
/// first). keep() may be called from several threads; find() once they are done.
class ParsedRecords {
 public:
  /// The overview records are made when the run-level files of `layout` and `scope` need them.
  ParsedRecords(const RunLayout& layout, FinaliseScope scope, std::size_t budget);
  /// Keeps record `index` parsed from the JSON text of its line (Journal::append()), unless the
  /// budget is spent or the text does not parse (finalise_run() then reads it, and says why).
  void keep(std::uint64_t index, const std::string& text);
  const ParsedRecord* find(std::uint64_t index) const;

 private:
  double scale_;
  Point3 translate_;
  bool overview_;
  std::size_t budget_;
  std::atomic<std::size_t> used_{0};
  std::mutex mutex_;
  std::map<std::uint64_t, std::unique_ptr<ParsedRecord>> kept_;
};

/// The names of the run-level files finalise_run() writes for a layout.
std::vector<std::string> run_level_files(const RunLayout& layout, FinaliseScope scope);

/// The output folder of a run or a merge, held for the time city3d writes into it.
class OutputFolder {
 public:
  /// Creates the folder, takes an exclusive lock on it (IoError when another city3d
  /// writes into it), removes temporary files a killed run left there, and sets aside run.json
  /// (removing the run-level files it lists that are unchanged since that run wrote them: a run
  /// rewrites what it needs, and a folder without run.json is not finished). Those of them not in
  /// `rewritten` (the run-level files this run writes) get a warning naming them.
  OutputFolder(std::string dir, const std::vector<std::string>& rewritten);
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  const std::string& dir() const { return dir_; }

  /// Removes model files an earlier run recorded (name under models/, content hash) when they still
  /// hold what that run wrote; never another file. `same_run`: that run had the same inputs and
  /// options (not resumed), which the warning says.
  void remove_earlier_models(const std::vector<std::pair<std::string, std::string>>& models, bool same_run);

  /// Writes run.json, atomically.
  void write_manifest(const RunManifest& manifest);

 private:
  std::string dir_;
  int lock_fd_ = -1;
};

/// Reads run.json of a folder; false when there is none or it cannot be read.
bool read_manifest(const std::string& dir, RunManifest& manifest);

/// "size mtime" of a file, as run.json records it; empty when it does not exist.
std::string file_stamp_of(const std::string& path);

/// Writes the run-level files into `dir` from `records` (sorted by index) and returns the summary
/// (counts of the records, `seconds`, `resumed`: the records an earlier run left, and the problem
/// most rows share). For a whole run the records must be exactly the indices 0..layout.records-1.
/// `outputs` receives the files written. report.html reads its records on up to `threads` threads
/// (the files do not depend on it). Throws IoError.
BatchSummary finalise_run(const std::string& dir, const RunLayout& layout,
                          const std::vector<RecordInJournal>& records, double seconds, std::size_t resumed,
                          FinaliseScope scope, std::map<std::string, std::string>& outputs,
                          unsigned threads = 1);

}  // namespace city3d::detail
