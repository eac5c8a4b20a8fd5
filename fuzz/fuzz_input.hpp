// Shared by the fuzz harnesses: the fuzzer's bytes as a file the readers can open by path (an
// anonymous in-memory file, /proc/self/fd/N, so nothing touches the disk), and quiet logging.
#pragma once

#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "city3d/log.hpp"

namespace city3d::fuzz {

/// The bytes of one fuzz input behind a path. The file lives as long as this object.
class MemoryFile {
 public:
  MemoryFile(const std::uint8_t* data, std::size_t size) {
    fd_ = memfd_create("city3d-fuzz", MFD_CLOEXEC);
    if (fd_ < 0) throw std::runtime_error("fuzz: memfd_create failed");
    std::size_t done = 0;
    while (done < size) {
      const ssize_t n = ::write(fd_, data + done, size - done);
      if (n <= 0) throw std::runtime_error("fuzz: cannot write the input");
      done += static_cast<std::size_t>(n);
    }
    path_ = "/proc/self/fd/" + std::to_string(fd_);
  }
  ~MemoryFile() { ::close(fd_); }
  MemoryFile(const MemoryFile&) = delete;
  MemoryFile& operator=(const MemoryFile&) = delete;

  const std::string& path() const { return path_; }

 private:
  int fd_ = -1;
  std::string path_;
};

/// Warnings about broken inputs are expected by the thousand: keep stderr for the fuzzer.
inline void quiet_logging() {
  static const bool done = [] {
    set_log_level(LogLevel::quiet);
    return true;
  }();
  (void)done;
}

}  // namespace city3d::fuzz
