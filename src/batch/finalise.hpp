// The end of a run, shared by run_batch() and merge: every run-level file (CityJSON, CityJSONSeq,
// models.<ext>, report.csv, report.json, buildings.gpkg, report.html) is a function of the journal
// records in index order, so a merge of shards writes exactly what one process writes. Also the output folder's housekeeping: a
// lock, temporary files of killed runs, outputs of earlier runs, and run.json (written last: its
// presence means the run or shard finished).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "city3d/batch.hpp"
#include "batch/journal.hpp"

namespace city3d::detail {

/// One record to finalise: where it is.
struct RecordInJournal {
  const JournalReader* journal = nullptr;
  const RecordRef* ref = nullptr;
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
