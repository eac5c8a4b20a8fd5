// CPU per stage (include/city3d/stage_profile.hpp): per thread, the stage running and the CPU clock when
// it last changed; on every change the time since goes to the stage that ran, in global counters of
// nanoseconds (atomic: threads add to them without a lock).
#include "city3d/stage_profile.hpp"

#include <time.h>

#include <atomic>
#include <cstdint>

#include "city3d/selection.hpp"

namespace city3d {
namespace {

std::array<std::atomic<std::uint64_t>, kStageCount> first_ns{};
std::array<std::atomic<std::uint64_t>, kStageCount> rebuild_ns{};

struct ThreadState {
  Stage stage = Stage::other;
  bool rebuilding = false;
  int depth = 0;
  double mark = 0.0;  // CPU seconds at the last change
};
thread_local ThreadState state;

// Gives the time since the last change to the stage that ran, and restarts the clock.
void settle() {
  const double now = building_cpu_seconds();
  const double spent = now - state.mark;
  state.mark = now;
  if (state.depth == 0 || !(spent > 0.0)) return;
  auto& counters = state.rebuilding ? rebuild_ns : first_ns;
  counters[static_cast<std::size_t>(state.stage)].fetch_add(static_cast<std::uint64_t>(spent * 1e9),
                                                            std::memory_order_relaxed);
}

}  // namespace

double building_cpu_seconds() {
  timespec t{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec) + solver_process_cpu_seconds();
}

const char* stage_name(Stage stage) {
  switch (stage) {
    case Stage::other: return "other";
    case Stage::describe: return "describe";
    case Stage::planes: return "planes";
    case Stage::heightmap: return "heightmap";
    case Stage::outline: return "outline";
    case Stage::edges: return "edges";
    case Stage::polylines: return "polylines";
    case Stage::step_lines: return "step_lines";
    case Stage::regularise: return "regularise";
    case Stage::walls: return "walls";
    case Stage::hypothesis: return "hypothesis";
    case Stage::selection: return "selection";
    case Stage::assemble: return "assemble";
    case Stage::validity: return "validity";
    case Stage::measure: return "measure";
    case Stage::lod1: return "lod1";
    case Stage::count: break;
  }
  return "?";
}

double StageProfile::total() const {
  double sum = 0.0;
  for (std::size_t i = 0; i < kStageCount; ++i) sum += first[i] + rebuild[i];
  return sum;
}

StageProfile stage_profile() {
  StageProfile p;
  for (std::size_t i = 0; i < kStageCount; ++i) {
    p.first[i] = 1e-9 * static_cast<double>(first_ns[i].load(std::memory_order_relaxed));
    p.rebuild[i] = 1e-9 * static_cast<double>(rebuild_ns[i].load(std::memory_order_relaxed));
  }
  return p;
}

void reset_stage_profile() {
  for (std::size_t i = 0; i < kStageCount; ++i) {
    first_ns[i].store(0, std::memory_order_relaxed);
    rebuild_ns[i].store(0, std::memory_order_relaxed);
  }
}

StageTimer::StageTimer(Stage stage) : outer_(state.stage) {
  settle();
  state.stage = stage;
  ++state.depth;
}

StageTimer::~StageTimer() {
  settle();
  state.stage = outer_;
  --state.depth;
}

RebuildScope::RebuildScope() : outer_(state.rebuilding) {
  settle();
  state.rebuilding = true;
}

RebuildScope::~RebuildScope() {
  settle();
  state.rebuilding = outer_;
}

}  // namespace city3d
