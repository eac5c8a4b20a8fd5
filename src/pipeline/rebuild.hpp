// The rebuilds of a LoD2 model that leaves points unexplained or carries surface no point supports
// (explain_more); how faithful a model is to its points, both ways, is measured by evaluation
// (ModelFit, surface_support.hpp).
#pragma once

#include <cstddef>
#include <vector>

#include "city3d/surface_support.hpp"
#include "pipeline/lod2.hpp"

namespace city3d::detail {

/// A LoD2 rung as it was built, for explain_more: its level, its hypothesis, its deadline, whether its
/// selection had to drop the face prior, and the report as it was before the hypothesis and before
/// the selection (a variant's report starts from one of them).
struct Lod2Rung {
  ModelLevel level = ModelLevel::lod22;
  bool footprint_walls_only = false;
  Lod2Hypothesis hypothesis;
  /// The rung's model as its selection gave it, before checked_model: a variant whose selection gives
  /// the same is not measured again.
  BuildingModel selected;
  BuildingReport before_hypothesis;
  BuildingReport before_selection;
  bool without_prior = false;
  Clock::time_point deadline = Clock::time_point::max();
};

/// Issue 10's "every point explained, or reported" and issue 23's "no surface the points don't
/// support": when a LoD2 model leaves more than retry_unexplained_share of the points unexplained, or
/// carries more than retry_unsupported_area of surface no point supports, the rung is rebuilt with
/// variants that address what leaves points out, each a deterministic function of the input. The
/// points beneath unsupported surface count as left out (points_beneath_unsupported: a low annex whose
/// few points form no plane, under a roof plane extended over it, is near that roof's walls but
/// misrepresented all the same). Hypotheses:
///  - roof planes of half min_points: an upper part or a small tier whose few points form no plane of
///    min_points is otherwise covered by the roof below it;
///  - without a footprint, an outline closing wider gaps (OutlineParams::wide_gap_spacings): a roof whose
///  returns have
///    gaps (dark or wet roofing, glass) is otherwise cut at the gap, and a changed outline changes
///    the lines regularised against it; and both;
///  - roofs for the points left out (pipeline/left_out.hpp): a horizontal level for each group of
///    them in no plane, and a cell of its own for each plane they mostly make up.
/// Selections over each hypothesis (the first hypothesis is reused from the rung, so these cost a
/// selection each, not a rebuild):
///  - without the face prior: the paper's hard constraint keeps the best face of every roof plane, so
///    a plane fitted to ground or clutter points can force its face over a cell the roof above
///    explains (a flat roof modelled at ground level over a third of the building);
///  - half the complexity weight: a roof part of few points costs more edges than its points weigh;
///  - both.
/// A model rebuilt only for its unsupported surface is selected over each hypothesis without those
/// variants of the selection.
/// A variant replaces the model only if it is more faithful both ways (ModelFit::unfaithful: fewer
/// points left out plus less unsupported surface at the point density) and fits better both ways
/// (ModelFit::squares_both_ways: a smaller sum of squared distances, with a square metre of unsupported
/// surface counted as the points of a square metre 1 m off; without unsupported surface, the sum of the
/// points' squared distances). The report says which variant was kept, or that none helped.
/// A variant's selection that gives a model already measured (the rung's own, or an earlier variant's)
/// is not checked or measured again: it could not be kept, since the model kept only ever gets
/// strictly better both ways.
/// Debug files are written for the rung's own hypothesis only. Returns how well the model it leaves
/// explains the points (measured once: the report's figures reuse it).
ModelFit explain_more(const BuildingInput& input, const ReconstructionParams& params, const Lod2Rung& rung,
                       BuildingReport& report, BuildingModel& model);

}  // namespace city3d::detail
