// Runs a piece of work in a child process (fork) and hands its output back: how face selection calls
// COIN-OR CBC. CbcMain1 in Debian's CBC 2.10.8 keeps its state in globals, so two threads cannot solve
// at once in one process, and an assertion inside Clp aborts whatever process it runs in. In a child
// of its own, each solve runs beside the others and a crash or a hang costs that solve only.
#pragma once

#include <functional>
#include <string>

namespace city3d::detail {

/// What became of the child.
struct ChildResult {
  bool completed = false;  ///< the work returned and its output arrived whole
  bool timed_out = false;  ///< killed at the wall-clock limit
  std::string output;      ///< what `work` returned (when completed)
  std::string failure;     ///< otherwise: how the child ended ("killed by signal 6 (Aborted)", ...)
  std::string stderr_tail; ///< the last lines the child wrote to its standard error (an assertion, say)
};

/// Runs `work` in a forked child and returns what it returned. The child writes nothing to the
/// parent's standard output, ends with _exit (no atexit handlers, no stream flushes), and is killed
/// (SIGKILL) once `time_limit` seconds of wall clock have passed (0 or infinity: no limit). `work`
/// must only use memory the calling thread owns and libraries that keep no lock across the fork
/// (it runs in a copy of the process with one thread). Throws ReconstructionError when no child can
/// be started (fork or pipe refused).
ChildResult run_in_child(const std::function<std::string()>& work, double time_limit);

/// CPU seconds (user + system) used by the children that run_in_child started from this thread.
double children_cpu_seconds();

}  // namespace city3d::detail
