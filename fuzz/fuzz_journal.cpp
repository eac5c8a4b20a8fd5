// Fuzz harness: the resume journal (header, records, checksums, escaping), read as a resumed run
// reads it: JournalReader over the file, every record read back, then a Journal of the same run
// opened on the folder (which keeps the good records, checks their model files and rewrites the
// file). A record read back must be the one its reference names, or an IoError.
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "city3d/error.hpp"
#include "fuzz_input.hpp"
#include "batch/journal.hpp"

namespace {

/// One output folder per process, reused by every input, removed at exit.
struct Folder {
  std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("city3d_fuzz_journal_" + std::to_string(::getpid()));
  Folder() { std::filesystem::create_directories(path / "models"); }
  ~Folder() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

const std::filesystem::path& folder() {
  static const Folder dir;
  return dir.path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  city3d::fuzz::quiet_logging();
  const std::filesystem::path journal = folder() / "resume.journal";
  std::ofstream(journal, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  try {
    const city3d::detail::JournalReader reader(journal.string());
    if (!reader.header_ok()) return 0;
    for (const city3d::detail::RecordRef& ref : reader.records()) {
      try {
        const city3d::detail::BuildingRecord record = reader.read(ref);
        if (record.index != ref.index || record.id != ref.id) __builtin_trap();
        (void)reader.line(ref);
      } catch (const city3d::Error&) {
      }
    }
    const city3d::detail::JournalHeader header = reader.header();
    city3d::detail::Journal resumed(folder().string(), header, true);
    for (const city3d::detail::RecordRef& ref : reader.records()) (void)resumed.find(ref.index);
  } catch (const city3d::Error&) {
  }
  return 0;
}
