// The option table behind the command line, --help, --print-config and --config (private to
// src/cli/): one row per option. A row added here is a flag, a line of --help, a key of the TOML
// configuration file and a line of --print-config, with no other code.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "city3d/options.hpp"

namespace city3d::detail {

/// One option. In the TOML file its key is the long flag without "--" ("--id-field" -> id-field),
/// and its value type follows from the row:
///   - a switch (no value_name) is a boolean: true = given, false = not given;
///   - a value whose name lists comma-separated parts ("LIST", "XMIN,YMIN,XMAX,YMAX") is an array;
///   - a value whose default prints as a number is a number (integer or float);
///   - any other value is a string (options without a default also accept a number).
struct OptionSpec {
  const char* flag;        ///< "--footprints"
  const char* short_flag;  ///< "-f" or nullptr
  const char* value_name;  ///< "PATH", or nullptr for a switch
  const char* help;
  /// The option's current value as its flag would take it ("" when unset); for a switch "true" or
  /// "false". Applied to a default RunOptions it gives the default --help prints; applied to the
  /// effective options it gives what --print-config prints. Every row needs one.
  std::function<std::string(const RunOptions&)> show;
  std::function<void(RunOptions&, const std::string&)> apply;
};

/// Every option, in --help order.
const std::vector<OptionSpec>& option_table();

/// False for the options that are actions rather than settings (--help, --version, --config,
/// --print-config): they have no key in the configuration file.
bool in_config_file(const OptionSpec& spec);

/// The long option nearest to `name` (a long option without "--", as mistyped), without "--", for
/// "did you mean": at most a third of its letters differ (one for short names); empty when none is
/// that near. With `config_file`, only the options a configuration file can set.
std::string closest_option(const std::string& name, bool config_file);

/// The shortest decimal text that reads back to exactly `v` ("0.34", "20", "1e-07").
std::string number_text(double v);

/// One option as read from a configuration file: its row, its value as flag text ("true"/"false"
/// for a switch) and where it was.
struct ConfigEntry {
  const OptionSpec* spec = nullptr;
  std::string value;
  std::string key;
  long line = 0;
};

/// Reads a TOML configuration file (parsed with toml++). Throws ConfigError naming the file, and
/// for each problem the key and line: syntax errors, unknown keys, wrong types, tables.
std::vector<ConfigEntry> read_config_file(const std::string& path);

/// As read_config_file, from text in memory; `name` stands for the file in messages.
std::vector<ConfigEntry> read_config_text(const std::string& text, const std::string& name);

}  // namespace city3d::detail
