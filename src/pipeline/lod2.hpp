// The rungs of one building's fallback ladder (pipeline.cpp walks them): a LoD2 rung's face hypothesis
// (lod2_hypothesis: planes, outline, vertical planes, candidate faces; paper sections 3.1-3.3) and its
// model (lod2_model: the selection and the assembled faces), the LoD1 rung's block, and the check every
// model passes before it may be written (checked_model).
#pragma once

#include <chrono>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "city3d/debug_output.hpp"
#include "city3d/error.hpp"
#include "city3d/pipeline.hpp"

namespace city3d::detail {

using Clock = std::chrono::steady_clock;

/// Throws ReconstructionError when the rung's time is used up after `stage`, so the ladder moves on
/// (only with the opt-in --time-limit; without it the deadline is time_point::max()).
void check_time(Clock::time_point deadline, ReconstructionStage stage);

/// Whether two points are the same, exactly.
inline bool same_point(const Point3& p, const Point3& q) { return p.x == q.x && p.y == q.y && p.z == q.z; }

/// What a rung's hypotheses share: the heightmap of the points, its edges and their polylines depend
/// on the points and on their own parameters only, which explain_more's variants do not change (they
/// change the planes, the outline's gap and the left-out points): the variants reuse the rung's. So
/// do the planes' neighbour searches, normals and seed order, which depend on the points and k only.
struct SharedRaster {
  std::shared_ptr<const Heightmap> heightmap;
  std::shared_ptr<const std::vector<Point2>> edges;          ///< null on the footprint-walls rung
  std::shared_ptr<const std::vector<Polyline2>> polylines;   ///< of the edges, before the step lines join them
  std::shared_ptr<const PlaneDetector> planes;                ///< the points' neighbours, normals and seed order
};

/// The candidate faces of a LoD2 rung, one problem per part (a footprint is one part, whatever its
/// polygons; an inferred outline has a part per region modelled, the largest first).
struct Lod2Hypothesis {
  std::vector<CandidateFaces> parts;
  std::vector<std::size_t> part_numbers;  ///< each part's number among the outline's parts (for notes)
  SharedRaster raster;                    ///< what it was built from, for the variants of explain_more
};

/// How a LoD2 rung builds its hypothesis: the rung's own way, or one of explain_more's variants.
struct Lod2Variant {
  /// The second rung: the footprint's walls only, no inferred inner walls.
  bool footprint_walls_only = false;
  /// Without a footprint, the outline is inferred closing gaps of OutlineParams::wide_gap_spacings
  /// point spacings instead of gap_spacings (for roofs whose returns have gaps).
  bool wide_outline = false;
  /// When given, the points a model of this rung left farther than 1 m: they get roof levels, and on
  /// the full rung cells of their own (pipeline/left_out.hpp).
  const std::vector<bool>* unexplained = nullptr;
  /// The rung's hypothesis' raster, reused where it holds a stage's result.
  const SharedRaster* shared = nullptr;
};

/// A LoD2 rung up to its face hypothesis: roof planes, the outline, the vertical planes and the
/// candidate faces of each part. Throws Error naming the stage when a stage fails for the largest part;
/// a further part that fails is left out and said in the report's note.
Lod2Hypothesis lod2_hypothesis(const BuildingInput& input, const ReconstructionParams& params,
                               const Lod2Variant& variant, Clock::time_point deadline, DebugTrace* trace,
                               BuildingReport& report);

/// A LoD2 rung's selection (paper section 3.3) and model: each part's faces selected and assembled, the
/// parts' solids joined in one model. Throws Error when the largest part has no selection; a further
/// part without one is left out and said. `without_prior` (when given) tells whether every part's
/// selection had to drop the face prior (its program was infeasible with it).
BuildingModel lod2_model(const BuildingInput& input, const Lod2Hypothesis& hypothesis,
                         const ReconstructionParams& params, Clock::time_point deadline, DebugTrace* trace,
                         BuildingReport& report, bool* without_prior = nullptr);

/// The LoD1 rung: always possible when the building has points and a usable footprint.
BuildingModel lod1_rung(const BuildingInput& input, const ReconstructionParams& params, BuildingReport& report);

/// A rung's model as the writers will write it (rounded to the output grid), passing every val3dity
/// rule: a model that does not is repaired (spikes cut, warped faces split), or this throws and the
/// ladder moves on: an invalid model is never written (the trace keeps it).
BuildingModel checked_model(const ReconstructionParams& params, ModelLevel level, bool footprint_walls_only,
                            BuildingModel model, DebugTrace* trace, BuildingReport& report);

}  // namespace city3d::detail
