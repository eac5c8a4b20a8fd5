// AtomicFile: temporary file + rename (rename is atomic within one file system on POSIX).
#include "files/atomic_file.hpp"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>

#include "city3d/error.hpp"

namespace city3d::detail {
namespace {
std::atomic<unsigned> g_counter{0};
}

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  temp_path_ = path_ + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(g_counter++);
  file_ = std::fopen(temp_path_.c_str(), "wb");
  if (!file_) throw IoError("write: cannot create " + path_ + ": " + std::strerror(errno));
  // A large buffer: model files are written in many small fprintf calls.
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 16);
}

AtomicFile::~AtomicFile() {
  if (file_) {
    std::fclose(file_);
    std::remove(temp_path_.c_str());
  }
}

void AtomicFile::commit() {
  const bool write_failed = std::ferror(file_) != 0;
  const bool close_failed = std::fclose(file_) != 0;
  file_ = nullptr;
  if (write_failed || close_failed) {
    std::remove(temp_path_.c_str());
    throw IoError("write: writing " + path_ + " failed: " + std::strerror(errno));
  }
  if (std::rename(temp_path_.c_str(), path_.c_str()) != 0) {
    const int err = errno;
    std::remove(temp_path_.c_str());
    throw IoError("write: cannot rename temporary file to " + path_ + ": " + std::strerror(err));
  }
}

}  // namespace city3d::detail
