// The outline a LoD2 rung builds on: the footprint when one is given, else an outline inferred from the
// points (City3D's second mode), cut into the parts that are modelled apart; and the plan-view facts of
// planes and parts the rung needs (a wall's line, a part's roof planes, the point spacing).
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

#include "city3d/pipeline.hpp"

namespace city3d::detail {

/// The outline of a building without footprint, inferred from the heightmap of its points
/// (infer_outline, closing gaps of `wide_outline` ? wide_gap_spacings : gap_spacings point spacings,
/// of `params.outline`), regularised and fitted to the points, and cut into the parts that are
/// modelled (separate parts of min_extra_part_area or more that hold most of a roof plane's points).
/// The footprint's polygons when the input has a footprint. Notes what it did in `report`; throws
/// ReconstructionError when no outline can be inferred.
std::vector<Polygon2> building_outline(const BuildingInput& input, const Heightmap& heightmap,
                                       const std::vector<PlanarSegment>& roofs, const ReconstructionParams& params,
                                       bool wide_outline, BuildingReport& report);

/// The horizontal line of a detected wall segment: its points projected on the wall's horizontal
/// direction, from the lowest to the highest projection.
std::pair<Point2, Point2> wall_line(const PlanarSegment& wall, const std::vector<Point3>& points);

/// The roof planes of an inferred outline part: those with at least `share` of their points inside it
/// (outline.part_roof_share).
std::vector<PlanarSegment> roofs_of_part(const std::vector<PlanarSegment>& roofs, const Polygon2& part,
                                         const std::vector<Point3>& points, double share);

/// Mean point spacing, metres: sqrt(outline area / points).
double point_spacing(const std::vector<Polygon2>& outline, std::size_t points);

}  // namespace city3d::detail
