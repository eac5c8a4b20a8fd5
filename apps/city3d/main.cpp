// The city3d executable: parses the command line and runs the chosen command; nothing else.
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>

#include <cstdio>
#include <exception>
#include <filesystem>
#include <new>
#include <string>
#include <system_error>
#include <vector>
#include <iostream>

#include "city3d/error.hpp"
#include "city3d/info.hpp"
#include "city3d/log.hpp"
#include "city3d/options.hpp"
#include "city3d/batch.hpp"
#include "city3d/pipeline.hpp"
#include "city3d/stage_profile.hpp"

namespace {

// Ctrl-C (SIGINT) and SIGTERM during a run: the progress line is ended and the user told that the
// finished buildings are kept (the journal is flushed as each one finishes), then the process exits
// with 128 + the signal. The message is made before the run, as a handler may only write().
char g_interrupt_message[1024] = "\ncity3d: interrupted\n";
std::size_t g_interrupt_length = 0;

extern "C" void on_interrupt(int signal) {
  const ssize_t ignored = ::write(2, g_interrupt_message, g_interrupt_length);
  (void)ignored;
  ::_exit(128 + signal);
}

void catch_interrupts(const std::string& what_is_kept) {
  const std::string message = "\ncity3d: interrupted; " + what_is_kept + "\n";
  g_interrupt_length = std::min(message.size(), sizeof g_interrupt_message - 1);
  std::memcpy(g_interrupt_message, message.data(), g_interrupt_length);
  struct sigaction action {};
  action.sa_handler = on_interrupt;
  sigemptyset(&action.sa_mask);
  for (const int signal : {SIGINT, SIGTERM}) {
    // A signal the caller ignores (a background job's SIGINT, nohup) stays ignored.
    struct sigaction before {};
    if (::sigaction(signal, nullptr, &before) == 0 && before.sa_handler == SIG_IGN) continue;
    ::sigaction(signal, &action, nullptr);
  }
}

int run_info(const city3d::RunOptions& options) {
  // A folder stands for its point-cloud files, as for reconstruct; one without any may be a footprint
  // source (a folder of Shapefiles).
  std::vector<std::string> paths;
  for (const std::string& path : options.inputs) {
    std::error_code ec;
    const std::vector<std::string> clouds =
        std::filesystem::is_directory(path, ec) ? city3d::point_cloud_files_in(path) : std::vector<std::string>{};
    if (clouds.empty()) paths.push_back(path);
    paths.insert(paths.end(), clouds.begin(), clouds.end());
  }
  for (std::size_t i = 0; i < paths.size(); ++i) {
    const std::string& path = paths[i];
    if (i > 0) std::cout << "\n";
    if (city3d::looks_like_point_cloud(path)) {
      std::cout << city3d::describe_point_cloud(city3d::summarise_point_cloud(path));
    } else {
      const city3d::FootprintSet set = city3d::read_footprints(path, options.batch.footprint);
      std::size_t features = 0;
      const std::vector<city3d::FieldSummary> fields =
          city3d::summarise_fields(path, options.batch.footprint, static_cast<std::size_t>(-1), features);
      std::cout << city3d::describe_footprints(set, fields, features);
    }
    std::cout.flush();
  }
  return city3d::kExitOk;
}

// --profile: the CPU of each stage over the buildings this run reconstructed (resumed ones took none),
// on stderr whatever the verbosity (it was asked for). A line per stage, `profile: NAME FIRST REBUILDS
// TOTAL SHARE`, for bench/stage_profile.py.
void print_profile(const city3d::BatchSummary& s) {
  const city3d::StageProfile p = city3d::stage_profile();
  const double total = p.total();
  std::fprintf(stderr, "profile: CPU seconds per stage, %zu buildings reconstructed (their threads and solver "
                       "processes; a rung's first model, its rebuilds)\n",
               s.buildings - s.resumed);
  std::fprintf(stderr, "profile: %-11s %9s %9s %9s %7s\n", "stage", "first", "rebuilds", "total", "share");
  double first = 0.0, rebuild = 0.0;
  for (std::size_t i = 0; i < city3d::kStageCount; ++i) {
    const double both = p.first[i] + p.rebuild[i];
    first += p.first[i], rebuild += p.rebuild[i];
    std::fprintf(stderr, "profile: %-11s %9.3f %9.3f %9.3f %6.1f%%\n", city3d::stage_name(static_cast<city3d::Stage>(i)),
                 p.first[i], p.rebuild[i], both, total > 0.0 ? 100.0 * both / total : 0.0);
  }
  std::fprintf(stderr, "profile: %-11s %9.3f %9.3f %9.3f %6.1f%%\n", "all", first, rebuild, total, total > 0.0 ? 100.0 : 0.0);
}

// The end of a run or a merge: its summary line, the problem most buildings share with its likely
// fix, and the exit code (README, "Exit codes").
int finish(const city3d::RunOptions& options, const city3d::BatchSummary& s, const std::string& what) {
  if (options.verbosity > 0) {
    std::string resumed;
    if (s.resumed > 0)
      resumed = " (" + std::to_string(s.resumed) + " of them taken from the journal of an earlier run into " +
                options.batch.output_dir + "; --no-resume recomputes them)";
    std::fprintf(stderr,
                 "city3d: %s%zu building%s: %zu ok, %zu fallback, %zu skipped, %zu failed, %zu partial in "
                 "%.1f s%s; report %s\n",
                 what.c_str(), s.buildings, s.buildings == 1 ? "" : "s", s.ok, s.fallback, s.skipped,
                 s.failed, s.partial, s.seconds, resumed.c_str(), s.report_path.c_str());
    if (!s.advice.empty()) std::fprintf(stderr, "city3d: %s\n", s.advice.c_str());
    if (s.nothing_built())
      std::fprintf(stderr, "city3d: no building was reconstructed (each one's reason is in %s)\n", s.report_path.c_str());
  }
  // Nothing built is a failed run, --strict or not; --strict also fails a run whose buildings mostly
  // share one problem (a misconfiguration), and one where some failed or are partial. A shard is a
  // part of a run: what it built or not is judged by the merge (a shard of footprints without points
  // must not stop a Slurm merge that waits for every shard to succeed).
  const bool shard = options.command == "reconstruct" && options.batch.shards > 0;
  if (s.nothing_built() && !shard) return city3d::kExitNothing;
  if (options.strict && !s.main_problem.empty() && !shard) return city3d::kExitMainProblem;
  if (options.strict && (s.failed > 0 || s.partial > 0)) return city3d::kExitStrict;
  return city3d::kExitOk;
}

int run_reconstruct(const city3d::RunOptions& options) {
  city3d::BatchOptions batch = options.batch;
  batch.point_clouds = options.inputs;
  batch.parameters = city3d::run_parameters_json(options);
  batch.progress = options.progress == 1 || (options.progress == -1 && options.verbosity > 0 && isatty(2));
  catch_interrupts("the buildings finished so far are kept in " + batch.output_dir +
                   "/resume.journal: the same command resumes where this one stopped");
  const city3d::BatchSummary summary = city3d::run_batch(batch);
  if (options.profile) print_profile(summary);
  return finish(options, summary, "");
}

int run_merge(const city3d::RunOptions& options) {
  catch_interrupts("no file of the merge is left half-written: the same command merges again");
  const city3d::BatchSummary s =
      city3d::merge_shards({options.inputs, options.batch.output_dir, options.batch.threads});
  return finish(options, s, "merged " + std::to_string(options.inputs.size()) + " shard folders: ");
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
  if (options.print_config) {
    std::cout << city3d::config_text(options);
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
  } catch (const std::filesystem::filesystem_error& e) {
    // The library checks its folders up front; should the file system still refuse (a folder
    // removed or a disk gone read-only during the run), that is the environment, not a bug.
    std::cerr << "city3d: " << e.path1().string() << ": " << e.code().message() << "\n";
    return city3d::kExitInput;
  } catch (const std::system_error& e) {
    // The operating system refused a resource (a thread, a file): the environment, not a bug.
    std::cerr << "city3d: the system refused: " << e.what() << " (try fewer --jobs)\n";
    return city3d::kExitInput;
  } catch (const std::bad_alloc&) {
    std::cerr << "city3d: out of memory (try fewer --jobs or a smaller --block-size)\n";
    return city3d::kExitInput;
  } catch (const std::exception& e) {
    std::cerr << "city3d: internal error: " << e.what() << "\n";
    return city3d::kExitInternal;
  }
  return city3d::kExitOk;
}
