// Face hypothesis (paper section 3.3): candidate faces of one building from its roof planes, its
// vertical planes and its floor, and the integer program (SelectionProblem) that selects among them.
//
// Construction: a 2.5D arrangement, built in the local xy frame. The code is in src/hypothesis/, one
// file per step (src/hypothesis/steps.hpp lists them); only the 2D arrangement uses CGAL.
//
//  1. A 2D arrangement (CGAL Arrangement_2, exact predicates and constructions; coordinates are
//     rounded to double only at the end) of
//       (a) the footprint rings (the outer walls; holes are courtyards),
//       (b) the inner walls (VerticalPlane with outer == false), extended by line_support_margin at
//           both ends so that walls ending just short of another line still split the cell,
//       (c) the xy projections of the pairwise intersection lines of the ROOF planes only (the paper's
//           change to PolyFit), each clipped to where both planes have points nearby: the points of a
//           plane within line_support_margin (xy) of the line are projected onto it, the two
//           intervals are intersected, and the result is extended by line_support_margin at both
//           ends. A pair with no such overlap, or an overlap shorter than min_line_overlap, gives
//           no line. Without this rule every pair of planes would cut the whole footprint and the
//           arrangement would explode. Nearly coincident lines (both ends of one within
//           line_merge_distance of a longer one's line, overlapping it) are merged: the longer one
//           is extended over both (longest first, ties in pair order).
//     Thin cells (area < min_cell_width / 2 x perimeter) are merged into the inside neighbour that
//     shares their longest boundary (the shared edges are removed), when the union stays a simple
//     polygon (the shared edges form one chain and the cells touch nowhere else); one merge at a
//     time, in arrangement order, until no thin cell can be merged; this runs before holes are
//     bridged (below), so a union that still encloses something is split like any cell with a hole.
//     Nearly coincident lines otherwise leave strips whose faces are degenerate and inflate the
//     problem.
//     Edges shorter than min_edge_length are contracted (nearly concurrent lines otherwise make
//     cells without area). Dangling edges (an end that reaches no other line) are removed, because a cell
//     with an "antenna" is not a simple polygon. A cell with a hole is split by a horizontal line across the
//     footprint at the hole's middle height, so every cell is a simple polygon. Dangling ends of roof lines
//     and inner walls that lie inside the footprint, with no crossing within 2 x line_support_margin, are
//     first extended to the next line ahead. The outer VerticalPlanes are not used: the footprint rings are
//     the outer walls. Contracting short edges can make a cell's loop visit a vertex twice (a sliver part
//     collapsed onto a point): the loop is split there into simple loops; two-vertex pieces vanish, the
//     others are cells (even when snapping turned them clockwise: dropping one would open a crack). Detached
//     parts of the inside cells (connected across inner edges) smaller than min_part_area are dropped, never
//     the largest part: a self-touching outline leaves lobes of a few cm2.
//  2. Roof faces: every bounded cell inside the footprint, lifted onto the roof planes that have at
//     least min_support_points of their points within cell_support_margin (xy) of the cell (when no
//     plane qualifies, the plane(s) whose points come nearest), at most max_planes_per_cell of them
//     (at most max_planes_per_large_cell when there are more than large_cell_count cells):
//     the ones with most points inside the cell, then most points within the margin, then the lower
//     plane index (planes whose face over the cell would have more than max_unsupported_area of surface
//     no point supports come after the others). A cell whose one plane is such a blade over it also
//     gets the planes whose points come nearest that are none there, nearest first, up to
//     max_planes_per_cell: the part of a steep plane beyond its support cut (below) would otherwise
//     keep only the blade. Vertically overlapping roof faces are exactly the faces over the same cell.
//     Support cuts: a plane with at least min_support_points of its points inside a cell whose face
//     there would rise more than support_cut_rise above its points' top plus support_cut_height, over
//     no point (surface_support.hpp), is a blade: the plane's contour at that height, clipped to the
//     cell, joins the curves and the arrangement is built again (once), so that the plane's face can
//     end where its points end. The contour often stands in for a line the arrangement lacks: the
//     hip of a steep plane around a corner, the ridge beyond a plane's last points.
//     The floor lies below every roof face: when the ground is measured, over a cell, a plane that
//     comes lower than ground_z + floor_clearance at a cell vertex is dropped when another of the
//     cell's planes stays above that. Without ground points ground_z is the lowest building point,
//     only an upper bound of the ground (a roof-only cloud has it at the eaves, where the roof planes
//     extended to the outline come lower): then a plane is dropped only where it comes lower than
//     ground_z - unmeasured_floor_drop + floor_clearance (a steep plane extended over a far cell
//     would otherwise drag the floor tens of metres down). Either way the floor is then lowered
//     (never raised) to floor_clearance below the lowest remaining roof vertex.
//  3. Vertical faces: over every arrangement edge, the "levels" are the roof planes of the cells on
//     both sides (plus the floor on the footprint boundary). The vertical strip over the edge is cut
//     by the level lines; every cell of that 1D line arrangement (between two consecutive levels) is
//     a candidate. Where two levels cross inside an edge, the crossing becomes a vertex (a station)
//     of every face along the edge, so no face is a bow-tie and edges weld exactly.
//  4. Floor faces: every inside cell at the floor height (ground_z, or lower, see 2), forced on.
//  5. A start for the solvers (SelectionProblem::start): one roof face per cell (its segment's face
//     prior, else its best-supported face), the floors, and over every edge the wall faces between
//     the roofs chosen on its two sides. A checkerboard of high and low cells around a vertex puts
//     four walls on one vertical edge; a local search changes one cell's roof at a time until every
//     edge has 0 or 2 faces (or leaves the start empty when no change helps). Then the start descends
//     the selection energy (the weights `energy` passed in): one cell's roof at a time, the change
//     that lowers the energy most on each cell, keeping every edge at 0 or 2 faces and every cell
//     holding its face prior, until no change helps. Large programs that the solver cannot finish
//     within its limits then still give a full LoD2 model, and a good one; the solver starts from it.
//
// Vertex identity: a vertex is (arrangement vertex or station on an edge, height cluster). The xy
// part comes from the exact arrangement; at one xy position the heights of the levels through it
// are sorted and levels closer than vertex_merge_tolerance share a vertex (this is how the two
// planes of a ridge meet in one vertex). 3D coordinates are never compared across positions.
//
// Support (data term): the number of points within support_distance of the face's plane whose
// projection falls inside the face polygon. For a roof face only the points of its own planar
// segment count (as in PolyFit); for walls and the floor every point counts. Points are not weighted
// by distance and no coverage (alpha-shape) term is used, as in City3D's formulation.
// Unsupported area (E_u of selection.hpp): the area of each roof and wall face more than
// surface_support.tolerance above the highest point within surface_support.radius of it in plan; the
// face prior of a segment is its best-supported face among those whose data term outweighs that.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "city3d/planes.hpp"
#include "city3d/selection.hpp"
#include "city3d/surface_support.hpp"
#include "city3d/types.hpp"
#include "city3d/walls.hpp"

namespace city3d {

/// Parameters of generate_candidates(). Distances in metres.
struct HypothesisParams {
  double support_distance = 0.3;     ///< epsilon: point-to-face distance for support, > 0
  double min_face_area = 0.05;       ///< m2; roof faces smaller than this are never chosen as a segment's face
                                     ///< prior (they stay candidates: removing them could open the model); >= 0
  double line_support_margin = 1.0;  ///< xy distance of points from a roof intersection line that supports it,
                                     ///< and the extension of clipped lines and inner walls at both ends, > 0
  double cell_support_margin = 1.0;  ///< xy distance of a plane's points from a cell that makes the plane a
                                     ///< candidate on that cell, >= 0
  int min_support_points = 3;        ///< points a plane needs near a cell (fewer if the segment is smaller), >= 1
  double vertex_merge_tolerance = 1e-3;  ///< heights at one xy position closer than this share a vertex, > 0
  double parallel_tolerance = 1e-3;  ///< |n_i x n_j| below this: roof planes treated as parallel (no line), > 0
  int max_planes_per_cell = 3;        ///< roof planes lifted onto one cell: the best-supported ones (most of
                                     ///< their points inside the cell, then near it), >= 1. 3, not 4: with
                                     ///< planes of 20 points, 4 cost 2.3x the time on the Delft block for
                                     ///< 3 mm of median RMSE on the dev set (docs/BENCHMARKS.md)
  int large_cell_count = 64;         ///< an arrangement with more inside cells than this is "large", >= 0
  int max_planes_per_large_cell = 2; ///< max_planes_per_cell of a large arrangement (the smaller of the two
                                     ///< applies): keeps the integer program of big buildings solvable, >= 1
  double floor_clearance = 0.1;      ///< least height of a roof vertex above the floor; the floor is lowered
                                     ///< (never raised) to keep it, > 0
  double unmeasured_floor_drop = 1.0;  ///< without measured ground, how far below ground_z a roof plane may
                                       ///< reach over a cell before it is dropped there (see 2), >= 0
  double min_part_area = 1.0;        ///< m2; detached parts of the inside cells smaller than this are dropped
                                     ///< (never the largest part), >= 0
  double min_edge_length = 0.01;     ///< arrangement edges shorter than this are contracted (their end
                                     ///< vertices snap together; sliver cells vanish), >= 0
  double min_cell_width = 0.1;       ///< a cell with area < min_cell_width / 2 x perimeter (a strip narrower
                                     ///< than this, a sliver) is merged into a neighbour; 0 = never, >= 0
  double min_line_overlap = 0.0;     ///< roof intersection lines whose supported overlap (before the
                                     ///< extension by line_support_margin) is shorter are skipped, >= 0.
                                     ///< Off by default: a skipped line lets other lines' dangling ends
                                     ///< run on to the next line, which made more cells, not fewer.
  double line_merge_distance = 0.1;  ///< a roof line with both ends within this xy distance of a longer
                                     ///< one, overlapping it, is merged into it; 0 = never, >= 0
  /// Where more than max_planes_per_cell roof planes qualify for a cell, those whose face over it would
  /// have more than max_unsupported_area (m2) more than surface_support.tolerance above the highest point
  /// within surface_support.radius in plan (surface_support.hpp) come last (see 2), >= 0
  double max_unsupported_area = 0.25;
  /// A plane lifted onto a cell that rises there more than support_cut_rise above its highest point plus
  /// support_cut_height, with more than max_unsupported_area unsupported, is cut at its contour at that
  /// height (see 2), metres, >= 0
  double support_cut_height = 0.5;
  double support_cut_rise = 2.0;
  /// A plane's face over a cell that overhangs lower ground (more than this many m2 of it unsupported,
  /// without rising beyond its points) is cut along the line, in a direction of the cell's edges, that
  /// separates its points in the cell from that part (see 2), >= 0
  double support_cut_area = 1.0;
  /// That line is drawn only when it leaves at most this share of either set on the wrong side (the
  /// two are otherwise interleaved: no line ends the face where its points end), in [0, 1)
  double support_cut_mixed = 0.05;
  /// The directions it tries are those of the cell's edges longer than support_cut_min_edge (metres,
  /// >= 0), one of each set whose directions' cross product is below support_cut_same_direction (the
  /// sine of the angle between them, about 1 degree; in [0, 1)).
  double support_cut_min_edge = 0.05;
  double support_cut_same_direction = 0.017;
  /// The solvers' start (one roof per cell, then a descent of the selection energy) stops after this
  /// many passes over the cells even when the last one still lowered the energy (a work limit: it
  /// rarely takes more than a handful), >= 1
  std::size_t start_descent_passes = 50;
  /// The measure of surface no point supports: each candidate face's unsupported area (E_u of
  /// selection.hpp) and the ranking above.
  SurfaceSupportParams surface_support;

  /// Throws ConfigError listing every invalid field.
  void validate() const;
};

/// What a candidate face is.
enum class FaceKind : std::uint8_t { roof, wall, floor };

/// One candidate face. Its polygon is the loop `vertices` (indices into CandidateFaces::vertices):
/// simple, planar, counter-clockwise seen from outside where that is meaningful (roofs face up,
/// floors down, walls on the footprint boundary outwards; inner walls face the right side of their
/// arrangement edge).
/// Every field is compared by same_hypothesis() (src/pipeline/rebuild.cpp): a field added here must be
/// compared there too.
struct CandidateFace {
  FaceKind kind = FaceKind::roof;
  /// roof: index into roof_planes; wall: index into walls when the face lies on an inner wall, else -1;
  /// floor: -1.
  int source = -1;
  /// Coplanarity key: two faces lie in the same plane exactly when their plane_id is equal (a roof
  /// plane, the floor, or one vertical line of the arrangement).
  std::uint32_t plane_id = 0;
  /// roof/floor: the arrangement cell it lies over; wall: the arrangement edge it stands on.
  std::uint32_t cell_or_edge = 0;
  std::vector<std::uint32_t> vertices;
  double area = 0.0;  ///< m2
};

/// The candidate faces of one building and the selection problem over them. Face i of `faces`,
/// `polygons` and `problem` is the same face.
struct CandidateFaces {
  std::vector<Point3> vertices;                 ///< local frame; shared by faces (welded by identity)
  std::vector<CandidateFace> faces;
  std::vector<std::vector<Point3>> polygons;    ///< faces[i].vertices resolved, for export and tests
  SelectionProblem problem;

  std::size_t cell_count = 0;   ///< bounded arrangement cells inside the footprint
  std::size_t edge_count = 0;   ///< arrangement edges bordering at least one inside cell
  std::size_t line_count = 0;   ///< roof intersection lines inserted (after clipping)
};

/// Builds the candidate faces (see the file comment) and their SelectionProblem.
///
/// `points`: all building points, local frame. `roof_planes`: roof segments (kind roof; walls are
/// ignored), their point indices refer to `points`. `walls`: only inner walls (outer == false) are
/// used. `footprint_local`: the outline polygons (outer CCW, holes CW, either orientation accepted),
/// local frame. `ground_z`: floor height; `ground_measured`: false when ground_z is only the lowest
/// building point (see the file comment, 2).
/// The problem's edges each list at least two faces (faces that could never close are pruned), its
/// floor faces are forced on, its face prior holds the best-supported face of each roof segment that
/// has support, vertical_overlaps lists every pair of roof faces over the same cell, and start holds
/// a closed selection when one was found (see 5 above), improved under the weights of `energy`;
/// exactly_one lists the roof faces over each cell.
/// Deterministic: the same input gives the same faces in the same order.
/// `checkpoint`, when given, is called after each of the longer steps (the arrangements, the planes
/// lifted onto the cells, the faces, the problem); it may throw to stop the work (a time limit), and
/// does not change the result otherwise.
/// Throws ConfigError (params) and ReconstructionError ("hypothesis: 0 planes, need at least 1 roof
/// plane", empty footprint, no inside cell).
CandidateFaces generate_candidates(const std::vector<Point3>& points,
                                   const std::vector<PlanarSegment>& roof_planes,
                                   const std::vector<VerticalPlane>& walls,
                                   const std::vector<Polygon2>& footprint_local, double ground_z,
                                   bool ground_measured, const HypothesisParams& params,
                                   const SelectionParams& energy = SelectionParams{},
                                   const std::function<void()>& checkpoint = {});

}  // namespace city3d
