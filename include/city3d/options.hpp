// The command line: one table maps every flag onto the run options (and the stage parameter
// structs), and the same table prints --help with the defaults.
#pragma once

#include <string>
#include <vector>

#include "city3d/batch.hpp"

namespace city3d {

/// Process exit codes of the `city3d` executable.
enum ExitCode : int {
  kExitOk = 0,        ///< the run finished (for `reconstruct`: even if some buildings fell back or failed)
  kExitInput = 1,     ///< the run could not go on: unreadable or invalid input, unwritable output
  kExitUsage = 2,     ///< bad command line: unknown command or option, bad value
  kExitInternal = 3,  ///< an unexpected internal error (a bug): please report it
  kExitStrict = 4,    ///< `reconstruct --strict`: the run finished but some buildings failed
};

/// Everything one invocation of `city3d` can set, with its defaults.
struct RunOptions {
  std::string command;               ///< "info", "reconstruct", "evaluate" or "merge"; empty with --help / --version
  bool help = false;
  bool version = false;
  std::vector<std::string> inputs;   ///< positional arguments: files for `info`, point clouds for `reconstruct`, shard folders for `merge`
  BatchOptions batch;                ///< footprints, stage parameters, outputs, threads
  std::string format = "obj";        ///< obj, ply, ply-ascii (parsed into batch.format)
  bool strict = false;               ///< exit non-zero when any building failed
  int progress = -1;                 ///< -1 automatic (on when stderr is a terminal), 0 off, 1 on
  int verbosity = 1;                 ///< 0 quiet, 1 warnings, 2 info, 3 debug
  std::string residuals;             ///< evaluate: CSV of each point's distance to the model, or empty
};

/// Parses argv. Throws ConfigError naming the offending argument (unknown option, missing or bad
/// value, unknown command) after collecting every problem.
RunOptions parse_command_line(int argc, const char* const* argv);

/// The --help text: usage, commands, every option with its default, exit codes.
std::string help_text();

}  // namespace city3d
