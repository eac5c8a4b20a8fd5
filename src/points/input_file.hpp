// A read-only binary file for the point-cloud readers: RAII over stdio, 64-bit offsets, large
// unbuffered block reads, and IoError messages that name the module and the file.
#pragma once

#include <sys/types.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>

#include "city3d/error.hpp"

namespace city3d::detail {

class InputFile {
 public:
  /// Opens `path` for reading. Throws IoError "<module>: cannot open <path>: <reason>".
  InputFile(const std::string& path, const std::string& module) : path_(path), module_(module) {
    file_ = std::fopen(path.c_str(), "rb");
    if (!file_) throw IoError(module_ + ": cannot open " + path_ + ": " + std::strerror(errno));
    // The readers ask for megabyte blocks; stdio's own buffer would only add a copy.
    std::setvbuf(file_, nullptr, _IONBF, 0);
    if (fseeko(file_, 0, SEEK_END) != 0) fail("cannot seek to the end");
    const off_t end = ftello(file_);
    if (end < 0) fail("cannot tell its size");
    size_ = static_cast<std::uint64_t>(end);
    seek(0);
  }
  ~InputFile() {
    if (file_) std::fclose(file_);
  }
  InputFile(InputFile&& other) noexcept
      : file_(other.file_), path_(std::move(other.path_)), module_(std::move(other.module_)),
        size_(other.size_) {
    other.file_ = nullptr;
  }
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;
  InputFile& operator=(InputFile&&) = delete;

  const std::string& path() const { return path_; }
  std::uint64_t size() const { return size_; }

  void seek(std::uint64_t offset) {
    if (fseeko(file_, static_cast<off_t>(offset), SEEK_SET) != 0)
      fail("cannot seek to byte " + std::to_string(offset));
  }

  /// Reads up to `n` bytes at the current position; fewer only at the end of the file.
  std::size_t read_some(void* dst, std::size_t n) {
    const std::size_t got = std::fread(dst, 1, n, file_);
    if (got < n && std::ferror(file_)) fail("read error");
    return got;
  }

  /// Reads up to `n` bytes at `offset` (clamped to the file); returns how many it read.
  std::size_t read_at(std::uint64_t offset, void* dst, std::size_t n) {
    if (offset >= size_) return 0;
    seek(offset);
    return read_some(dst, n);
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw IoError(module_ + ": " + what + " in " + path_ + ": " + std::strerror(errno));
  }

  std::FILE* file_ = nullptr;
  std::string path_;
  std::string module_;
  std::uint64_t size_ = 0;
};

}  // namespace city3d::detail
