// The resume journal of a batch run: one line per finished building (its report row and model),
// appended and flushed in output order, so that a run killed at any point can be resumed without
// recomputing or losing finished buildings. The first line holds a fingerprint of the inputs and
// parameters; a journal with another fingerprint is ignored (and replaced).
#pragma once

#include <cstdio>
#include <map>
#include <mutex>
#include <string>

#include "city3d/batch.hpp"

namespace city3d::detail {

class Journal {
 public:
  /// Opens `path`: reads the finished buildings of a journal with the same `fingerprint` (a
  /// truncated last line is dropped), rewrites it without damaged lines, and keeps it open for
  /// appending. Throws IoError when the file cannot be written.
  Journal(std::string path, const std::string& fingerprint, bool resume);
  ~Journal();
  Journal(const Journal&) = delete;
  Journal& operator=(const Journal&) = delete;

  /// The finished building with this id, or nullptr.
  const BuildingResult* find(const BuildingId& id) const;
  std::size_t restored() const { return done_.size(); }

  /// Appends one finished building and flushes it to the operating system. Thread-safe.
  void append(const BuildingResult& result);

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
  std::mutex mutex_;
  std::map<BuildingId, BuildingResult> done_;
};

/// A fingerprint of everything that determines a run's output: the version, the input files (path,
/// size, modification time) and the effective options.
std::string batch_fingerprint(const BatchOptions& options, const std::vector<std::string>& point_cloud_files);

}  // namespace city3d::detail
