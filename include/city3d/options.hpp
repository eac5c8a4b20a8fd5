// The command line: one table maps every flag onto the run options (and the stage parameter
// structs), and the same table prints --help with the defaults.
#pragma once

#include <string>
#include <vector>

#include "city3d/batch.hpp"

namespace city3d {

/// Process exit codes of the `city3d` executable (docs/MESSAGES.md lists them with every warning).
enum ExitCode : int {
  kExitOk = 0,        ///< the run finished and built something (for `reconstruct`: even if some buildings fell back or failed)
  kExitInput = 1,     ///< the run could not go on: unreadable or invalid input, unwritable output, or no footprint selected
  kExitNothing = 1,   ///< the run finished but built nothing: every building skipped or failed (the report says why)
  kExitUsage = 2,     ///< bad command line: unknown command or option, bad value
  kExitInternal = 3,  ///< an unexpected internal error (a bug): please report it
  kExitStrict = 4,    ///< `--strict`: the run finished but some buildings failed or are partial
  kExitMainProblem = 5,  ///< `--strict`: more than half of the buildings share one problem (a misconfigured run)
  kExitInterrupted = 130,  ///< interrupted (Ctrl-C; 128 + the signal: 143 for SIGTERM); a rerun resumes
};

/// Everything one invocation of `city3d` can set, with its defaults.
struct RunOptions {
  std::string command;               ///< "info", "reconstruct", "evaluate" or "merge"; empty with --help / --version
  bool help = false;
  bool version = false;
  std::vector<std::string> inputs;   ///< positional arguments: files for `info`, point clouds for `reconstruct`, shard folders for `merge`
  BatchOptions batch;                ///< footprints, stage parameters, outputs, threads
  std::string format = "obj";        ///< obj, ply, ply-ascii (parsed into batch.format)
  bool strict = false;               ///< exit non-zero when any building failed or is partial, or most share a problem
  int progress = -1;                 ///< -1 automatic (on when stderr is a terminal), 0 off, 1 on
  int verbosity = 1;                 ///< 0 quiet, 1 warnings, 2 info, 3 debug
  std::string residuals;             ///< evaluate: CSV of each point's distance to the model, or empty
  std::string config_path;           ///< --config: the TOML file the options were read from, or empty
  bool print_config = false;         ///< --print-config: print the effective options as TOML and exit
  bool profile = false;              ///< --profile: the CPU of each stage, summed over the run, on stderr at its end
};

/// Parses argv. With `--config FILE.toml`, the file's options are applied first and those given on
/// the command line replace them (`--switch=false` undoes the file's `switch = true`). Throws
/// ConfigError naming the offending argument (unknown option, missing or bad value, unknown
/// command), or the file, key and line of a configuration problem, after collecting every problem.
RunOptions parse_command_line(int argc, const char* const* argv);

/// The TOML configuration text --print-config prints: every option of the table (but --help,
/// --version, --config, --print-config) with its value in `options`, under a comment with its help;
/// options without a value are commented out. --config reads it back to the same options.
std::string config_text(const RunOptions& options);

/// The options that describe a run's outputs as a JSON object of option names (without "--") and
/// values, typed as --print-config types them ({"lambda-data": 0.34, "gpkg": true, "lod": ["1.2",
/// "1.3", "2.2"], "where": null, ...}): every option of the configuration file but those that do
/// not change the outputs (-o, -j, --shard, --block-size, --group-area, --strict, --debug, the
/// messages and progress) and the inputs, which the outputs record apart (--footprints, --layer,
/// --id-field). For BatchOptions::parameters.
std::string run_parameters_json(const RunOptions& options);

/// The --help text: usage, commands, every option with its default, exit codes.
std::string help_text();

}  // namespace city3d
