// Output folders: create with std::filesystem's error codes (never its exceptions), name the path
// component at fault, and probe writability with a real file (access(2) ignores read-only mounts
// for root and knows nothing of ACLs or quotas).
#include "files/output_folder.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

#include "city3d/error.hpp"

namespace city3d::detail {
namespace fs = std::filesystem;

namespace {

/// The first existing ancestor of `p` (or `p` itself) that is not a folder, or an empty path.
fs::path blocking_file(const fs::path& p) {
  std::error_code ec;
  for (fs::path q = p; !q.empty(); q = q.parent_path()) {
    const fs::file_status s = fs::status(q, ec);
    if (fs::exists(s)) return fs::is_directory(s) ? fs::path() : q;
    if (q == q.parent_path()) break;
  }
  return {};
}

}  // namespace

void prepare_output_folder(const std::string& dir, const std::string& module) {
  if (dir.empty()) throw IoError(module + ": the folder name is empty");
  const fs::path path(dir);
  if (const fs::path file = blocking_file(path); !file.empty()) {
    throw IoError(module + ": cannot create folder " + dir + ": " + file.string() +
                  (file == path ? " exists and is a file, not a folder" : " is a file, not a folder"));
  }
  std::error_code ec;
  fs::create_directories(path, ec);
  if (ec) throw IoError(module + ": cannot create folder " + dir + ": " + ec.message());
  // A real file tells what access(2) cannot: read-only mounts, ACLs, quotas.
  const std::string probe = (path / (".city3d-write-test-" + std::to_string(::getpid()))).string();
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) {
    const int err = errno;
    throw IoError(module + ": cannot write in folder " + dir + ": " + std::strerror(err));
  }
  ::close(fd);
  ::unlink(probe.c_str());
}

void remove_output_without_results(const std::string& dir) noexcept {
  try {
    std::error_code ec;
    const fs::path root(dir);
    for (const auto& entry : fs::directory_iterator(root, ec)) {
      const std::string name = entry.path().filename().string();
      if (name == "models" && entry.is_directory(ec) && fs::is_empty(entry.path(), ec)) continue;
      if (name == "resume.journal" && entry.is_regular_file(ec)) {
        std::ifstream in(entry.path(), std::ios::binary);
        std::string line;
        std::size_t lines = 0;
        while (std::getline(in, line) && lines < 2) ++lines;
        if (lines <= 1) continue;  // the header alone: no building finished
      }
      return;  // something worth keeping
    }
    if (ec) return;
    fs::remove(root / "models", ec);
    fs::remove(root / "resume.journal", ec);
    fs::remove(root, ec);
  } catch (...) {
  }
}

}  // namespace city3d::detail
