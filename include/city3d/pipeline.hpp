// The pipeline of one building: reconstruct_building() runs the stages in order and walks the
// fallback ladder. The batch job around it (tiles, footprints, threads, outputs) is in batch.hpp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "city3d/building_report.hpp"
#include "city3d/crop.hpp"
#include "city3d/evaluation.hpp"
#include "city3d/footprint_io.hpp"
#include "city3d/heightmap.hpp"
#include "city3d/hypothesis.hpp"
#include "city3d/lod1.hpp"
#include "city3d/model.hpp"
#include "city3d/model_io.hpp"
#include "city3d/planes.hpp"
#include "city3d/polylines.hpp"
#include "city3d/regularise.hpp"
#include "city3d/rings.hpp"
#include "city3d/selection.hpp"
#include "city3d/types.hpp"
#include "city3d/walls.hpp"

namespace city3d {

/// Which levels of detail a run produces. CityJSON holds each per building; OBJ/PLY get the highest.
struct LodSet {
  bool lod12 = true;  ///< LoD1.2: one block, the outline extruded to the roof percentile
  bool lod13 = true;  ///< LoD1.3: one block per roof-height cluster (3DBAG's definition)
  bool lod22 = true;  ///< LoD2.2: the reconstructed roof
  bool any() const { return lod12 || lod13 || lod22; }
};

/// Parses "1.2,1.3,2.2" (any non-empty subset, comma-separated; "all"); throws ConfigError.
LodSet parse_lod_set(const std::string& text);
/// "1.2,1.3,2.2" for a set.
std::string lod_set_text(const LodSet& lods);

/// The outline of a building without footprint (City3D's second mode, pipeline/outline.hpp): inferred
/// from the occupancy raster of its points, regularised, fitted to the points and cut into the parts
/// that are modelled.
struct OutlineParams {
  /// Smallest region of the occupancy raster kept as an outline part, m2.
  double min_region_area = 2.0;
  /// Gaps in the points the outline closes, in point spacings (the radius of the occupancy's closing).
  double gap_spacings = 1.5;
  /// Gaps in a roof's returns (dark or wet roofing, glass) that explain_more's wide outline closes,
  /// in point spacings: the closing with a disc of this radius fills gaps and concavities up to twice
  /// as wide (about 3 m at AHN3's 8 points per m2) and keeps wider ones.
  double wide_gap_spacings = 4.0;
  /// Smallest area of a part other than the largest that is modelled, m2: a garden shed or a silo.
  double min_extra_part_area = 4.0;
  /// A part other than the largest is modelled only when it holds more than this share of the points
  /// of some roof plane, in [0, 1).
  double extra_part_plane_share = 0.5;
  /// A roof plane is a roof of an inferred part when at least this share of its points lies inside
  /// the part, in (0, 1]: a plane of points elsewhere (another part, ground returns around a tree)
  /// would put a roof where none of its points are.
  double part_roof_share = 0.25;
  /// Parts nearer to each other than this are taken to touch, metres (a part is kept apart or left out).
  double part_gap = 0.1;
  /// How an inferred outline is regularised (with regularise.angle_threshold)...
  OutlineSnapParams snap;
  /// ...and then moved onto its outermost points.
  OutlineFitParams fit;
};

/// The rebuilds of a LoD2 model that leaves points unexplained or carries surface no point supports
/// (explain_more, pipeline/rebuild.hpp), beyond the two thresholds that start them
/// (ReconstructionParams::retry_unexplained_share and retry_unsupported_area).
struct RebuildParams {
  /// A variant hypothesis of more candidate faces than this is not selected (a work limit: the
  /// program of each variant grows with them); the report's note says which were not tried.
  std::size_t max_candidate_faces = 3000;
  /// A roof level of left-out points (pipeline/left_out.hpp) links points within this many point
  /// spacings of each other in plan (the step lines' search radius)...
  double level_link_spacings = 3.0;
  /// ...and within this of each other in height, metres (the step lines' min_step: a larger difference
  /// is a step between two levels). Links chain: a level can span more height than this.
  double level_link_height = 0.5;
  /// A roof level or plane of left-out points needs as many points as cover this much area at the
  /// building's density, where that is fewer than the smaller planes' count (at least 3), square
  /// metres; 0: always the smaller planes' count.
  double min_level_area = 4.0;
  /// A group of left-out points is searched for planes through triples of its points only up to this
  /// many points (the triples grow with the cube of the count); a larger group is left to the region
  /// growing of the rebuild's other variants and makes no left-out plane.
  std::size_t max_left_out_plane_points = 60;
  /// A left-out plane holds at least the group's points / left_out_plane_divisor (rounded up: half of
  /// them; the group is mostly that plane, or it is left to its level) and at least
  /// left_out_plane_min_points (>= 3). The divisor >= 1.
  std::size_t left_out_plane_divisor = 2;
  std::size_t left_out_plane_min_points = 4;
  /// A roof plane gets a cell of its own when at least this share of its points is left out, in (0, 1].
  double left_out_cell_share = 0.5;
  /// A left-out plane's rectangle thinner than this is no cell of its own (a row of returns), metres.
  double min_left_out_width = 0.1;
};

/// The roof type of a LoD2.2 model as 3DBAG names it (b3_dak_type): "horizontal", "multiple
/// horizontal" or "slanted".
struct RoofTypeParams {
  /// A roof face within this many degrees of horizontal is flat.
  double flat_angle = 3.0;
  /// Flat roof faces whose mean heights differ by more than this are on different levels, metres.
  double level_gap = 0.3;
};

/// Parameters of every per-building stage.
struct ReconstructionParams {
  PlaneParams planes;
  HeightmapParams heightmap;
  PolylineParams polylines;
  RegulariseParams regularise;
  WallParams walls;
  StepLineParams step_lines;
  HypothesisParams hypothesis;
  SelectionParams selection;
  AssembleParams assemble;
  Lod1Params lod1;
  OutlineParams outline;
  RebuildParams rebuild;
  RoofTypeParams roof_type;
  /// Every model is rounded to this grid (metres) as the CityJSON transform and the OBJ/PLY
  /// writers write it (0.0001 = 0.1 mm, the writers' default), and checked for validity as rounded.
  double output_grid = 0.0001;
  /// Tolerances of the validity check every model must pass (val3dity's defaults).
  ValidityParams validity;
  /// Highest rung to try: lod22 (full), lod22_footprint_walls, or lod12 (LoD1 blocks only).
  ModelLevel max_level = ModelLevel::lod22;
  /// Levels of detail to produce (LoD1.3 and LoD1.2 are derived from the LoD2.2 model when there is
  /// one; with only LoD1.2 asked for, no LoD2 is attempted: set max_level to lod12).
  LodSet lods;
  /// LoD1.3: adjacent roof parts whose heights differ by less than this (metres) become one block,
  /// as 3DBAG's lod13_step_height.
  double lod13_step_height = 3.0;
  /// Footprints of more vertices than this (holes included) are simplified before reconstruction,
  /// within a tolerance from 0.01 m doubled until they fit (simplify_footprint); the report's note
  /// says so. A deterministic work limit: the walls, the arrangement and the program grow with the
  /// footprint's edges (a 10,000-vertex circle took 25 s). Real footprints have far fewer.
  std::size_t max_footprint_vertices = 1000;
  /// Rings of a footprint that touch or come closer than half of this (a hole touching its outer ring
  /// at a point, two parts meeting at a corner) are moved apart to this distance, metres, at the
  /// vertex that touches (open_pinches in rings.hpp); the note says where. Every solid extruded from
  /// a footprint that touches itself has an edge of four faces, so no model of it was valid.
  double footprint_clearance = 0.01;
  /// A building of more points per m2 than this (of its footprint, or of a cloud's box in plan) is
  /// thinned first to one point per cell of 1 / sqrt(max_point_density) (5 cm) in plan and
  /// thinning_height_cells cells in height, the first in input order; the note says so. A work limit,
  /// and the scale the method's neighbourhoods are made for: at 13,000 points per m2 the k nearest
  /// neighbours span 2 cm, region growing split a two-plane roof into 6,786 planes, and the run ran out
  /// of memory. Airborne surveys hold 10 to 60.
  double max_point_density = 400.0;
  /// A thinned cell is this many of its plan widths tall: a roof's noise stays within one cell, and a
  /// wall keeps a point every half metre up its cells (at 5 cm). >= 1.
  double thinning_height_cells = 10.0;
  /// A LoD2 model that leaves more than this share of the building's points unexplained (farther
  /// than kUnexplainedDistance) is rebuilt with the variants of explain_more(): smaller roof planes,
  /// a wider inferred outline, roofs for the points left out, and selections without the face prior
  /// and with half the complexity weight; a variant is kept when it is more faithful both ways and fits
  /// better both ways (see explain_more()). 1 (or more): never rebuilt.
  double retry_unexplained_share = 0.05;
  /// A LoD2 model with more than this much surface no point supports (m2 more than 1 m above the
  /// highest point within 1.5 m in plan, surface_support.hpp) is rebuilt with the same variants, the
  /// points beneath that surface counted as left out; a variant is kept when it is more faithful both
  /// ways (see explain_more()). A large value: never rebuilt for it.
  double retry_unsupported_area = 1.0;
  /// Opt-in wall-clock safety net for one building's LoD2 attempts, seconds; 0 (the default): none.
  /// The full rung gets full_rung_time_share of it, the footprint-walls rung the rest, and each
  /// selection what is left of its rung's share. When it fires the output depends on the machine's speed and load;
  /// without it, every limit counts work (nodes, faces, points) and the output is a function of
  /// the inputs and parameters alone.
  double time_limit = 0.0;
  /// The full LoD2 rung's share of time_limit, in (0, 1].
  double full_rung_time_share = 0.6;
  /// When not empty: per-building intermediate results (heightmap and edge PNGs, polylines before
  /// and after regularisation, walls, planes, candidate faces) are written into <debug_dir>/<id>/.
  std::string debug_dir;
  /// Throws ConfigError listing every invalid field of every stage.
  void validate() const;
};

/// Every parameter of every stage as "name = value" lines: logged at the start of a run and part of
/// the resume fingerprint.
std::string parameters_text(const ReconstructionParams& params);

/// One level of detail of a building's model.
struct LodModel {
  std::string lod;        ///< "1.2", "1.3", "2.2"
  BuildingModel model;    ///< validated as written
};

/// A building's outcome: the report row and, unless skipped or failed, its model.
struct BuildingResult {
  BuildingReport report;
  std::optional<BuildingModel> model;  ///< the highest level produced (OBJ/PLY write this one)
  std::vector<LodModel> lods;          ///< every level produced, "1.2" < "1.3" < "2.2" (CityJSON)
};

/// What prepare_footprint() did to a footprint's rings.
struct FootprintPreparation {
  TidiedFootprint tidied;          ///< vertices a validator takes for one, hairline spikes
  std::vector<Point2> opened;      ///< where touching rings were opened (the vertices' places before)
  std::optional<Point2> unopened;  ///< where rings touch and cannot be opened (a ring that crosses)
  /// The report's note ("" when nothing was found), the places given in the frame of the polygons
  /// plus `origin` (world coordinates).
  std::string note(const ReconstructionParams& params, const Point3& origin) const;
};

/// What reconstruct_building() does to every footprint before its stages, after a simplification:
/// drops each vertex within twice validity.snap_tolerance of the one before it (rounding to the output
/// grid can bring two vertices nearer) and the tip of each spike narrower than footprint_clearance
/// (tidy_footprint), then opens the rings that touch (open_pinches). Every block extruded from the
/// footprint as it was would be invalid. `city3d info` counts the footprints it changes.
FootprintPreparation prepare_footprint(std::vector<Polygon2>& polygons, const ReconstructionParams& params);

/// Reconstructs one building, walking the ladder LoD2 -> LoD2 with footprint walls -> LoD1 until a
/// rung gives a valid closed model. Never throws for a bad building: the result says what happened.
BuildingResult reconstruct_building(const BuildingInput& input, const ReconstructionParams& params);

/// A single-building cloud without footprint (City3D's second mode): all points are the building,
/// the local origin is the centre of their bounding box, the floor is `ground_z` when given, else
/// the lowest point, and the outline (for the LoD1 rung) is the convex hull of the points.
BuildingInput building_from_cloud(const BuildingId& id, const std::vector<Point3>& world_points,
                                  std::optional<double> ground_z = std::nullopt);

}  // namespace city3d
