// The city3d executable: parses the command line and runs the chosen command; nothing else.
#include <unistd.h>

#include <cstdio>
#include <exception>
#include <iostream>

#include "city3d/error.hpp"
#include "city3d/info.hpp"
#include "city3d/log.hpp"
#include "city3d/options.hpp"
#include "city3d/batch.hpp"
#include "city3d/pipeline.hpp"

namespace {

int run_info(const city3d::RunOptions& options) {
  for (std::size_t i = 0; i < options.inputs.size(); ++i) {
    const std::string& path = options.inputs[i];
    if (i > 0) std::cout << "\n";
    if (city3d::looks_like_point_cloud(path))
      std::cout << city3d::describe_point_cloud(city3d::summarise_point_cloud(path));
    else
      std::cout << city3d::describe_footprints(city3d::read_footprints(path, options.batch.footprint));
    std::cout.flush();
  }
  return city3d::kExitOk;
}

int run_reconstruct(const city3d::RunOptions& options) {
  city3d::BatchOptions batch = options.batch;
  batch.point_clouds = options.inputs;
  batch.progress = options.progress == 1 || (options.progress == -1 && options.verbosity > 0 && isatty(2));
  const city3d::BatchSummary s = city3d::run_batch(batch);
  if (options.verbosity > 0)
    std::fprintf(stderr,
                 "city3d: %zu buildings: %zu ok, %zu fallback, %zu skipped, %zu failed in %.1f s; report %s\n",
                 s.buildings, s.ok, s.fallback, s.skipped, s.failed, s.seconds, s.report_path.c_str());
  return options.strict && s.failed > 0 ? city3d::kExitStrict : city3d::kExitOk;
}

int run_merge(const city3d::RunOptions& options) {
  const city3d::BatchSummary s = city3d::merge_shards({options.inputs, options.batch.output_dir});
  if (options.verbosity > 0)
    std::fprintf(stderr, "city3d: merged %zu shard folders: %zu buildings: %zu ok, %zu fallback, %zu skipped, "
                 "%zu failed; report %s\n",
                 options.inputs.size(), s.buildings, s.ok, s.fallback, s.skipped, s.failed, s.report_path.c_str());
  return options.strict && s.failed > 0 ? city3d::kExitStrict : city3d::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  city3d::RunOptions options;
  try {
    options = city3d::parse_command_line(argc, argv);
  } catch (const city3d::ConfigError& e) {
    std::cerr << "city3d: " << e.what() << "\n";
    return city3d::kExitUsage;
  }
  if (options.help) {
    std::cout << city3d::help_text();
    return city3d::kExitOk;
  }
  if (options.version) {
    std::cout << "city3d " << CITY3D_VERSION << "\n";
    return city3d::kExitOk;
  }
  city3d::set_log_level(static_cast<city3d::LogLevel>(options.verbosity));
  try {
    if (options.command == "info") return run_info(options);
    if (options.command == "reconstruct") return run_reconstruct(options);
    if (options.command == "merge") return run_merge(options);
    if (options.command == "evaluate") {
      std::cout << city3d::evaluate_model(options.inputs[0], options.inputs[1], options.residuals);
      return city3d::kExitOk;
    }
  } catch (const city3d::ConfigError& e) {
    std::cerr << "city3d: " << e.what() << "\n";
    return city3d::kExitUsage;
  } catch (const city3d::Error& e) {
    std::cerr << "city3d: " << e.what() << "\n";
    return city3d::kExitInput;
  } catch (const std::exception& e) {
    std::cerr << "city3d: internal error: " << e.what() << "\n";
    return city3d::kExitInternal;
  }
  return city3d::kExitOk;
}
