// LoD1 block model: the footprint extruded from the ground height to a robust roof height (the last
// rung of the fallback ladder, and a baseline).
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "city3d/crop.hpp"
#include "city3d/types.hpp"

namespace city3d {

/// Parameters of the LoD1 block.
struct Lod1Params {
  /// Roof height = this percentile (0-100) of the building points' z, as 3DBAG's LoD1.2 "70p": robust
  /// to chimneys and to wall points.
  double roof_percentile = 70.0;
  /// Minimum block height in metres (> 0): a roof below ground_z + min_height is raised to it, so a
  /// flat or sunken object still gives a valid solid.
  double min_height = 1.0;
  /// Metres, > 0. The LoD2 model's roof faces can meet in plan with a vertex a few millimetres off
  /// its neighbour's edge (two walls nearly in line); blocks made from them then leave a sliver
  /// between the parts, walled on both sides, and are not a valid solid. Such blocks are made again
  /// with the parts joined where a vertex lies within this distance of another part's edge.
  double join_distance = 0.01;

  /// Throws ConfigError listing every invalid field.
  void validate() const;
};

/// The heights of a block and what was adjusted.
struct Lod1Heights {
  double floor_z = 0.0;  ///< local, = BuildingInput::ground_z
  double roof_z = 0.0;   ///< local, after the minimum-height rule
  std::string note;      ///< empty, or why roof_z differs from the percentile
};

/// Floor and roof heights of `input`'s block. Throws ReconstructionError "lod1: building <id> has no
/// points" when there are no building points, ConfigError when `params` is invalid.
Lod1Heights lod1_heights(const BuildingInput& input, const Lod1Params& params = {});

/// Extrudes polygons (outer rings and holes, any orientation; normalised here) from floor_z to roof_z
/// into a closed, 2-manifold, outward-oriented mesh: one quad per ring edge, the floor and the roof
/// as one polygon each per polygon without holes; a polygon with holes has its floor and roof split
/// into convex pieces (ear-clipping after bridging the holes, then merging triangles back) sharing
/// only ring vertices, so there are no T-junctions. Several polygons give several shells.
/// Throws ReconstructionError naming `id` when a ring has fewer than 3 vertices, no area, or a roof
/// with holes cannot be split (self-intersecting rings), or when roof_z <= floor_z.
PolygonMesh extrude_polygons(const std::vector<Polygon2>& polygons, double floor_z, double roof_z,
                             const BuildingId& id = {});

/// The roof parts of an LoD2 model in plan view, with the building points above each: what
/// make_lod13_blocks clusters. They do not depend on the step height, so LoD1.2 and LoD1.3 are made
/// from one of them.
struct Lod13Parts {
  BuildingId id;
  Point3 origin;                                   ///< the model's
  std::vector<Point2> pts;                         ///< plan-view vertices (equal x, y are one)
  std::vector<std::vector<std::uint32_t>> parts;   ///< each roof face as a counter-clockwise loop of pts
  std::vector<double> mean_z;                      ///< per part, its face's mean vertex height
  std::vector<double> area;                        ///< per part, in plan view
  std::vector<std::vector<double>> part_z;         ///< per part, the z of the points above it
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::size_t> part_of_edge;  ///< directed edge -> part
  std::set<std::pair<std::size_t, std::size_t>> adjacent;                        ///< parts sharing an edge
};

/// The roof parts of `lod22` (see make_lod13_blocks). A plan-view vertex within `join_distance`
/// metres of another part's edge splits that edge, so neighbouring parts share whole edges; the
/// default, half a millimetre, joins what the 0.1 mm output grid keeps apart. Throws
/// ReconstructionError when the model has no roof face.
Lod13Parts lod13_parts(const BuildingModel& lod22, const std::vector<Point3>& points,
                       double join_distance = 5e-4);

/// make_lod13_blocks from parts made once (LoD1.2 and LoD1.3 of one model differ only in the step).
/// With `no_overlapping_walls`, where more than two walls overlap on a vertex's column (heights A, B,
/// A, B around it, or high, low, higher, low: an edge of more than two faces, no 2-manifold solid), the
/// part across the least of those walls joins the taller part's cluster, until no column has such walls.
BuildingModel make_lod13_blocks(const Lod13Parts& roof, double floor_z, double step_height,
                                double roof_percentile = 70.0, double min_height = 1.0,
                                bool no_overlapping_walls = false);

/// Blocks per roof-height cluster from an LoD2 model (3DBAG's LoD1.3; LoD1.2 with an infinite
/// step): the model's roof faces, projected to the ground, are the roof parts; each part's height is
/// the `roof_percentile` of the building points above it (its vertices' mean height when none);
/// adjacent parts whose heights differ by less than `step_height` metres are merged, smallest
/// difference first, and each cluster is extruded from floor_z to its height (the percentile of all
/// its points), at least `min_height` above the floor. The result is one closed solid per connected
/// roof (step walls where clusters meet, no T-junctions), in the model's frame, with semantic
/// surfaces. `lod22` should be rounded to the output grid (round_to_grid) so that vertices that are
/// one place in plan view are equal. Throws ReconstructionError when the model has no roof face.
BuildingModel make_lod13_blocks(const BuildingModel& lod22, const std::vector<Point3>& points, double floor_z,
                                double step_height, double roof_percentile = 70.0, double min_height = 1.0);

/// The LoD1 block of a building, in its local frame (model.origin = input.origin): the footprint
/// extruded from input.ground_z to lod1_heights().roof_z. Throws as lod1_heights() and
/// extrude_polygons() do.
BuildingModel make_lod1_block(const BuildingInput& input, const Lod1Params& params = {});

}  // namespace city3d
