// explain_more's variant for points a LoD2 model leaves out (issue 10's "a roof level per height
// cluster", "smaller planes for small upper parts"). Given which points the rung's model leaves
// farther than 1 m away, the rung is rebuilt with
//  - a horizontal roof level for every group of such points that lie in no plane (an upper part
//    whose few or scattered returns form no plane: a crown of returns above a shed, AHN3 large/09083),
//    and the planes through triples of a small group's points (a gable's other slope at 2 points per
//    m2, under the one slope extended over the whole house), and
//  - a cell of their own for the roof planes whose points are mostly left out, levels included: the
//    rectangle around those points joins the arrangement's lines after the regularisation, which
//    would merge a part narrower than its cluster distance into the wall beside it (a parapet along
//    an eave, AHN3 large/19772). Only on the full LoD2 rung: the footprint-walls rung has no inner
//    lines by design, so there the levels only compete for the footprint's cells.
// The selection then decides, with the paper's energy, whether those parts are roof.
#pragma once

#include <cstddef>
#include <vector>

#include "city3d/pipeline.hpp"
#include "city3d/planes.hpp"
#include "city3d/regularise.hpp"
#include "city3d/types.hpp"

namespace city3d::detail {

/// The horizontal roof levels of the left-out points (`unexplained[i]`) that are in no segment:
/// points linked in plan (`params.level_link_spacings` x `spacing`) and height
/// (`params.level_link_height`) form a group; links chain, so a group can span more height than that
/// (a crown of scattered returns) and is one level all the same: the selection and the rebuilds' keep
/// rule decide whether it explains the points. Each group of at least `min_points` is a roof segment
/// at the median height of its points (the upper median of an even count).
/// Ordered by the groups' smallest point index. Deterministic.
std::vector<PlanarSegment> left_out_levels(const std::vector<Point3>& points, const std::vector<PlanarSegment>& segments,
                                           const std::vector<bool>& unexplained, double spacing,
                                           std::size_t min_points, const RebuildParams& params);

/// The roof planes of the left-out points that are in no segment: points linked in plan as for the
/// levels (at any height) form a group, and a group of `min_points` (at least 4) to
/// `params.max_left_out_plane_points` points gets the planes through triples of its points that hold
/// at least half of it, and at least 4 (detect_planes_of_few_points with `plane_params`; roof planes
/// only; a group that is mostly no plane is left to its level; `min_points` is a level's count, and a
/// slope left out beside a plane extended over it is often fewer: its points near the extension are
/// not left out): the other slope of a gable roof, or a sloped annex, whose few returns region growing
/// did not make a plane of. Ordered by group, then as detect_planes_of_few_points orders them.
/// Deterministic.
std::vector<PlanarSegment> left_out_planes(const std::vector<Point3>& points,
                                           const std::vector<PlanarSegment>& segments,
                                           const std::vector<bool>& unexplained, double spacing,
                                           std::size_t min_points, const PlaneParams& plane_params,
                                           const RebuildParams& params);

/// The lines of a cell of its own for every roof plane of which at least `params.left_out_cell_share`
/// of the points are left out: the four sides of the rectangle around those points, in the direction of an
/// outline edge (parallel or orthogonal to the walls) for which it is smallest. Planes with fewer than 3 such
/// points, or whose rectangle is thinner than `params.min_left_out_width`, get none.
std::vector<Segment2> left_out_plane_lines(const std::vector<Point3>& points, const std::vector<PlanarSegment>& roofs,
                                           const std::vector<bool>& unexplained, const std::vector<Polygon2>& outline,
                                           const RebuildParams& params);

}  // namespace city3d::detail
