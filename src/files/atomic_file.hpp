// Atomic file output: write to a temporary file beside the target, rename over it on commit, so a
// crash or kill never leaves a half-written file under the final name.
#pragma once

#include <cstdio>
#include <string>

namespace city3d::detail {

class AtomicFile {
 public:
  /// Opens "<path>.tmp-<pid>-<n>" for binary writing. Throws IoError naming `path` on failure.
  explicit AtomicFile(std::string path);
  /// Removes the temporary file unless commit() succeeded.
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  std::FILE* file() { return file_; }
  /// Flushes, closes and renames the temporary file to the final path. Throws IoError on failure
  /// (disk full, permissions), naming the path.
  void commit();

 private:
  std::string path_;
  std::string temp_path_;
  std::FILE* file_ = nullptr;
};

}  // namespace city3d::detail
