// Fuzz harness: the --config TOML file (toml++ parse, keys and types from the option table, values
// through each option's parser, stage validation), read as `city3d reconstruct x.las --config F`
// reads it. A file that is accepted must survive the round trip: --print-config's text, read back,
// gives the same options (the same text again).
#include <cstdint>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/options.hpp"
#include "fuzz_input.hpp"

namespace {

city3d::RunOptions parse_with_config(const std::string& path) {
  const char* argv[] = {"city3d", "reconstruct", "x.las", "--config", path.c_str()};
  return city3d::parse_command_line(5, argv);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  city3d::fuzz::quiet_logging();
  const city3d::fuzz::MemoryFile file(data, size);
  city3d::RunOptions options;
  try {
    options = parse_with_config(file.path());
  } catch (const city3d::ConfigError&) {
    return 0;
  }
  const std::string text = city3d::config_text(options);
  const city3d::fuzz::MemoryFile again(reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
  try {
    if (city3d::config_text(parse_with_config(again.path())) != text) __builtin_trap();
  } catch (const city3d::ConfigError&) {
    __builtin_trap();  // --print-config wrote a file --config refuses
  }
  return 0;
}
