// CPU per stage of the reconstruction, summed over every building of a run (issue 27): where the time
// goes, so that a change can see what it costs. A StageTimer marks the stage its scope runs; time is
// counted exclusive (a stage nested in another, as the stages of a rebuild, is taken out of the outer
// one) and split by whether it was spent building a rung's first model or rebuilding it (explain_more).
// Costs two clock reads per scope; always on, read with `city3d reconstruct --profile`.
#pragma once

#include <array>
#include <cstddef>

namespace city3d {

enum class Stage : int {
  other,       ///< a building's time in no stage below (report, notes, copies)
  describe,    ///< heights and figures of the points for the report (LoD1 heights, percentiles, density)
  planes,      ///< roof planes: normals, region growing, planes of few points
  heightmap,   ///< the TIN heightmap
  outline,     ///< an inferred outline (clouds without footprint), its regularisation and parts
  edges,       ///< Canny edges of the heightmap
  polylines,   ///< optimal-transport polylines
  step_lines,  ///< step lines between roof planes
  regularise,  ///< regularisation of the lines
  walls,       ///< vertical planes
  hypothesis,  ///< candidate faces: the arrangement, support cuts, the selection problem's terms
  selection,   ///< the integer program (GLPK in the thread, CBC's processes included)
  assemble,    ///< the selected faces as a mesh
  validity,    ///< checks and repairs of a model
  measure,     ///< distances of the points to a model, and its unsupported surface
  lod1,        ///< the LoD1.2 and LoD1.3 blocks and their measures
  count
};

constexpr std::size_t kStageCount = static_cast<std::size_t>(Stage::count);

const char* stage_name(Stage stage);

/// CPU seconds of the calling thread (user + system) and of the solver processes it waited for: the
/// clock of the stages, and of each building's cpu_seconds in the report.
double building_cpu_seconds();

/// CPU seconds (thread CPU, plus the solver processes a thread waited for) per stage, for a rung's
/// first model and for its rebuilds, summed over every thread since the start (or the last reset).
struct StageProfile {
  std::array<double, kStageCount> first{};
  std::array<double, kStageCount> rebuild{};
  double total() const;
};

/// The profile so far, every thread's (a thread's stages are added when its scopes end).
StageProfile stage_profile();
void reset_stage_profile();

/// Marks the calling thread's time as `stage` for its scope. Scopes nest; the outermost one of a thread
/// starts the clock (the time before it is no stage's).
class StageTimer {
 public:
  explicit StageTimer(Stage stage);
  ~StageTimer();
  StageTimer(const StageTimer&) = delete;
  StageTimer& operator=(const StageTimer&) = delete;

 private:
  Stage outer_;
};

/// Marks the calling thread's stages within its scope as a rebuild's (explain_more).
class RebuildScope {
 public:
  RebuildScope();
  ~RebuildScope();
  RebuildScope(const RebuildScope&) = delete;
  RebuildScope& operator=(const RebuildScope&) = delete;

 private:
  bool outer_;
};

}  // namespace city3d
