// The rungs of one building's fallback ladder (lod2.hpp): a LoD2 rung's hypothesis, stage by stage,
// and its model; the LoD1 block; the check of every model before it may be written.
#include "pipeline/lod2.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

#include "city3d/error.hpp"
#include "city3d/evaluation.hpp"
#include "city3d/mesh_check.hpp"
#include "city3d/repair.hpp"
#include "city3d/stage_profile.hpp"
#include "pipeline/left_out.hpp"
#include "pipeline/outline.hpp"

namespace city3d::detail {
namespace {

bool has_roof(const std::vector<PlanarSegment>& found) {
  return std::any_of(found.begin(), found.end(),
                     [](const PlanarSegment& s) { return s.kind == PlanarSegment::Kind::roof; });
}

// The planes of a building's points: its roof planes, and the lines of the walls the cloud sees.
struct BuildingPlanes {
  std::vector<PlanarSegment> segments;  // every plane found, roofs and walls
  std::vector<PlanarSegment> roofs;
  std::vector<std::pair<Point2, Point2>> detected_walls;
};

// Roof planes (and wall planes, if the cloud sees walls), by region growing (paper section 3.1), with
// two retries for buildings of few points. Throws ReconstructionError when no roof plane is found.
BuildingPlanes building_planes(const std::vector<Point3>& points, const ReconstructionParams& params,
                               const PlaneDetector& detector, DebugTrace* trace, BuildingReport& report) {
  std::vector<PlanarSegment> segments = detector.detect(params.planes);
  const int fewest = params.planes.small_min_points;
  if (!has_roof(segments) && points.size() >= static_cast<std::size_t>(fewest)) {
    // A shed or a garage can hold fewer points than min_points in all: rather than a block, try
    // one more time with planes of half min_points, or a third of its points when that is fewer
    // (at least small_min_points; planes.small_divisor and small_points_divisor).
    PlaneParams small = params.planes;
    small.min_points = std::max<int>(
        fewest,
        std::min<int>(
            params.planes.min_points / params.planes.small_divisor,
            static_cast<int>(points.size() / static_cast<std::size_t>(params.planes.small_points_divisor))));
    if (small.min_points < params.planes.min_points) {
      segments = detector.detect(small);
      const std::string note = "small building: planes of at least " + std::to_string(small.min_points) + " points";
      if (has_roof(segments)) add_note(report, note);
    }
  }
  if (!has_roof(segments)) {
    // Too few points, or too sparse, for region growing (k-neighbour normals then mix a roof's slopes:
    // every 4th point of the Delft tiles, about 2 per m2, left six houses of 7 to 28 points without a
    // plane; at every 8th, a house of 62 returns got none): planes through triples of the points (of
    // few_points_candidates of them, evenly spread, where there are more), each holding at least a
    // quarter of them (planes.few_points_divisor).
    const auto divisor = static_cast<std::size_t>(params.planes.few_points_divisor);
    const std::vector<PlanarSegment> few =
        detect_planes_of_few_points(points, params.planes, (points.size() + divisor - 1) / divisor,
                                    static_cast<std::size_t>(params.planes.few_points_max_points));
    if (has_roof(few)) {
      segments = few;
      add_note(report, "few points: planes fitted through triples of its " + std::to_string(points.size()) +
                           " points");
    }
  }
  BuildingPlanes planes;
  for (const PlanarSegment& s : segments) {
    if (s.kind == PlanarSegment::Kind::roof)
      planes.roofs.push_back(s);
    else
      planes.detected_walls.push_back(wall_line(s, points));
  }
  report.planes = planes.roofs.size();
  if (trace) trace->planes = segments;
  if (planes.roofs.empty())
    throw ReconstructionError(ReconstructionStage::planes, "no roof plane among " + std::to_string(points.size()) + " points (min_points " +
                              std::to_string(params.planes.min_points) + ")");
  planes.segments = std::move(segments);
  return planes;
}

// The lines of the inferred vertical planes (paper section 3.2): the heightmap's Canny edges as
// optimal-transport polylines, joined by the step lines between roof planes, regularised against the
// outline; with explain_more's left-out points, the lines of their cells too.
RegularisationResult vertical_lines(const BuildingInput& input, const std::vector<PlanarSegment>& roofs,
                                    const std::vector<Polygon2>& outline, const ReconstructionParams& params,
                                    const std::vector<bool>* unexplained, SharedRaster& raster,
                                    DebugTrace* trace) {
  const std::vector<Point3>& points = input.points;
  const Heightmap& heightmap = *raster.heightmap;
  std::optional<StageTimer> stage(Stage::edges);
  // Where the footprint's walls are the outline, the edges of the data's rim, which only repeat it, are
  // not made into polylines. (Walls inferred from the lines need them: they are the outer walls.)
  const bool footprint_walls = input.footprint_given && (params.walls.mode == WallMode::automatic ||
                                                         params.walls.mode == WallMode::footprint);
  if (!raster.edges) {
    std::vector<Point2> found = detect_edges(heightmap, params.heightmap);
    if (footprint_walls) found = edges_off_the_rim(heightmap, found, params.heightmap);
    raster.edges = std::make_shared<const std::vector<Point2>>(std::move(found));
  }
  const std::vector<Point2>& edges = *raster.edges;
  stage.emplace(Stage::polylines);
  if (!raster.polylines)
    raster.polylines = std::make_shared<const std::vector<Polyline2>>(extract_polylines(edges, params.polylines));
  std::vector<Polyline2> polylines = *raster.polylines;
  stage.emplace(Stage::step_lines);
  // Step lines between roof planes join the heightmap's lines (the same regularisation and walls).
  const std::vector<Polyline2> steps = detect_step_lines(points, roofs, point_spacing(outline, points.size()), params.step_lines);
  if (trace) trace->step_lines = steps;
  polylines.insert(polylines.end(), steps.begin(), steps.end());
  stage.emplace(Stage::regularise);
  RegularisationResult lines = regularise(polylines, &outline, params.regularise);
  if (unexplained) {
    // Their cells, after the regularisation, which would merge a narrow part's lines into the wall
    // beside it.
    const std::vector<Segment2> left_out = left_out_plane_lines(points, roofs, *unexplained, outline, params.rebuild);
    lines.segments.insert(lines.segments.end(), left_out.begin(), left_out.end());
    lines.segments_after = lines.segments.size();
  }
  if (trace) {
    trace->heightmap = raster.heightmap;
    trace->edges = raster.edges;
    trace->polylines = polylines;
    trace->regularised = lines.segments;
  }
  return lines;
}

// Each part's walls and candidate faces (paper section 3.3). A footprint is one problem, whatever its
// polygons; the parts of an inferred outline are one problem each (their own walls, arrangement and
// selection), and their solids are joined in one model: the parts of a cloud do not touch, and one
// arrangement over all of them could leave a part's floor edge without a partner (AHN3/02523).
Lod2Hypothesis part_hypotheses(const BuildingInput& input, const std::vector<Polygon2>& outline,
                               const BuildingPlanes& planes, const RegularisationResult& lines,
                               const ReconstructionParams& params, bool footprint_walls_only,
                               Clock::time_point deadline, DebugTrace* trace, BuildingReport& report) {
  const std::vector<Point3>& points = input.points;
  const std::vector<PlanarSegment>& roofs = planes.roofs;
  WallParams wall_params = params.walls;
  if (wall_params.mode == WallMode::automatic) wall_params.mode = WallMode::footprint;
  std::vector<std::vector<Polygon2>> problems;
  if (input.footprint_given)
    problems.push_back(outline);
  else
    for (const Polygon2& part : outline) problems.push_back({part});

  Lod2Hypothesis hypothesis;
  report.walls = report.candidate_faces = 0;
  std::optional<StageTimer> stage;
  for (std::size_t k = 0; k < problems.size(); ++k) {
    const std::vector<Polygon2>& part = problems[k];
    const std::string suffix = problems.size() > 1 ? "_part" + std::to_string(k) : "";
    try {
      stage.emplace(Stage::walls);
      const std::vector<VerticalPlane> walls = infer_walls(
          lines, &part, footprint_walls_only ? std::vector<std::pair<Point2, Point2>>{} : planes.detected_walls,
          wall_params);
      report.walls += walls.size();
      check_time(deadline, ReconstructionStage::walls);
      if (trace) trace->walls.emplace_back(suffix, walls);

      // An inferred part's roofs are the planes it holds a share of: a plane of points elsewhere
      // (another part, or ground returns around a tree, AHN3 large/06050) would put a roof where none
      // of its points are.
      const std::vector<PlanarSegment> part_roofs =
          input.footprint_given ? roofs
                                : roofs_of_part(roofs, part.front(), points, params.outline.part_roof_share);
      if (part_roofs.empty())
        throw ReconstructionError(ReconstructionStage::planes, "none of the " + std::to_string(roofs.size()) +
                                  " roof planes lies inside the inferred outline");
      stage.emplace(Stage::hypothesis);
      CandidateFaces candidates = generate_candidates(
          points, part_roofs, walls, part, input.ground_z, input.ground_measured, params.hypothesis,
          params.selection, [deadline] { check_time(deadline, ReconstructionStage::hypothesis); });
      report.candidate_faces += candidates.faces.size();
      check_time(deadline, ReconstructionStage::hypothesis);
      if (trace) trace->candidates.emplace_back(suffix, candidates);
      hypothesis.parts.push_back(std::move(candidates));
      hypothesis.part_numbers.push_back(k);
    } catch (const ReconstructionError& e) {
      // The largest part decides the rung; a further part that cannot be built is left out and said.
      if (k == 0) throw;
      add_note(report, "outline part " + std::to_string(k) + " left out: " + e.what());
    }
  }
  return hypothesis;
}

}  // namespace

void check_time(Clock::time_point deadline, ReconstructionStage stage) {
  if (deadline != Clock::time_point::max() && Clock::now() > deadline)
    throw ReconstructionError(stage, "the building's time limit is used up (see --time-limit)");
}

Lod2Hypothesis lod2_hypothesis(const BuildingInput& input, const ReconstructionParams& params,
                               const Lod2Variant& variant, Clock::time_point deadline, DebugTrace* trace,
                               BuildingReport& report) {
  SharedRaster raster = variant.shared ? *variant.shared : SharedRaster{};
  const std::vector<Point3>& points = input.points;
  std::optional<StageTimer> stage(Stage::planes);
  if (!raster.planes) raster.planes = std::make_shared<const PlaneDetector>(points, params.planes.k_neighbors);
  BuildingPlanes planes = building_planes(points, params, *raster.planes, trace, report);
  check_time(deadline, ReconstructionStage::planes);

  stage.emplace(Stage::heightmap);
  if (!raster.heightmap) raster.heightmap = std::make_shared<const Heightmap>(rasterise_tin(points, params.heightmap));
  stage.emplace(Stage::outline);
  const std::vector<Polygon2> outline =
      building_outline(input, *raster.heightmap, planes.roofs, params, variant.wide_outline, report);
  if (variant.unexplained) {
    // explain_more's variant for left-out points (pipeline/left_out.hpp): their roof levels and planes,
    // of the smaller planes' count of points, or of as many as cover min_level_area at the building's
    // density where that is fewer (at least 3): at 1 point per m2 a low annex holds a few returns.
    const double spacing = point_spacing(outline, points.size());
    std::size_t min_points = static_cast<std::size_t>(std::max<int>(
        params.planes.small_min_points, params.planes.min_points / params.planes.small_divisor));
    const double cover = spacing > 0 ? std::ceil(params.rebuild.min_level_area / (spacing * spacing)) : 0.0;
    if (cover > 0 && cover < static_cast<double>(min_points))
      min_points = std::max<std::size_t>(3, static_cast<std::size_t>(cover));
    const std::vector<PlanarSegment> levels =
        left_out_levels(points, planes.segments, *variant.unexplained, spacing, min_points, params.rebuild);
    const std::vector<PlanarSegment> sloped = left_out_planes(
        points, planes.segments, *variant.unexplained, spacing, min_points, params.planes, params.rebuild);
    planes.roofs.insert(planes.roofs.end(), levels.begin(), levels.end());
    planes.roofs.insert(planes.roofs.end(), sloped.begin(), sloped.end());
    report.planes = planes.roofs.size();
  }
  stage.reset();

  RegularisationResult lines;
  if (!variant.footprint_walls_only)
    lines = vertical_lines(input, planes.roofs, outline, params, variant.unexplained, raster, trace);
  Lod2Hypothesis hypothesis = part_hypotheses(input, outline, planes, lines, params, variant.footprint_walls_only,
                                              deadline, trace, report);
  hypothesis.raster = std::move(raster);
  return hypothesis;
}

BuildingModel lod2_model(const BuildingInput& input, const Lod2Hypothesis& hypothesis,
                         const ReconstructionParams& params, Clock::time_point deadline, DebugTrace* trace,
                         BuildingReport& report, bool* without_prior) {
  std::size_t dropped = 0;
  BuildingModel model;
  model.id = input.id;
  model.origin = input.origin;
  for (std::size_t k = 0; k < hypothesis.parts.size(); ++k) {
    const CandidateFaces& candidates = hypothesis.parts[k];
    try {
      SelectionParams selection_params = params.selection;
      if (deadline != Clock::time_point::max()) {
        const double left = std::chrono::duration<double>(deadline - Clock::now()).count();
        const double own = selection_params.time_limit > 0 ? selection_params.time_limit : left;
        selection_params.time_limit = std::max(selection_params.min_time_limit, std::min(own, left));
      }
      std::optional<StageTimer> stage(Stage::selection);
      SelectionResult selection = solve_selection(candidates.problem, selection_params);
      if (selection.status == SelectionStatus::infeasible && selection_params.use_face_prior) {
        // The face prior is a preference of the paper's, not a necessity: retry without it.
        selection_params.use_face_prior = false;
        selection = solve_selection(candidates.problem, selection_params);
        ++dropped;
      }
      // What the report says of the solve: a backend that broke, and a selection not proven optimal
      // because a limit stopped the search (the deterministic node limit, or the opt-in time limit).
      // (A feasible selection's message names the failures too.)
      if (selection.status == SelectionStatus::feasible)
        add_note(report, selection.message);
      else
        for (const std::string& failure : selection.backend_failures) add_note(report, failure);
      if (selection.status != SelectionStatus::optimal && selection.status != SelectionStatus::feasible)
        throw ReconstructionError(ReconstructionStage::selection,
                                  std::string(selection.status == SelectionStatus::infeasible
                                                  ? "infeasible"
                                                  : "no solution within the limits") +
                                      " (" + std::to_string(selection.variables) + " variables): " + selection.message);

      if (trace)
        trace->selections.push_back(
            {hypothesis.parts.size() > 1 ? "_part" + std::to_string(hypothesis.part_numbers[k]) : "", candidates,
             selection.selected, selection_params});
      stage.emplace(Stage::assemble);
      std::vector<SurfaceType> surfaces;
      const PolygonMesh mesh = assemble_model(candidates, selection.selected, params.assemble, &surfaces);
      const auto offset = static_cast<std::uint32_t>(model.mesh.vertices.size());
      model.mesh.vertices.insert(model.mesh.vertices.end(), mesh.vertices.begin(), mesh.vertices.end());
      for (auto face : mesh.faces) {
        for (auto& v : face) v += offset;
        model.mesh.faces.push_back(std::move(face));
      }
      model.surfaces.insert(model.surfaces.end(), surfaces.begin(), surfaces.end());
    } catch (const ReconstructionError& e) {
      if (hypothesis.part_numbers[k] == 0) throw;
      add_note(report, "outline part " + std::to_string(hypothesis.part_numbers[k]) + " left out: " + e.what());
    }
  }
  if (without_prior) *without_prior = dropped == hypothesis.parts.size();
  return model;
}

BuildingModel lod1_rung(const BuildingInput& input, const ReconstructionParams& params, BuildingReport& report) {
  const StageTimer stage(Stage::lod1);
  const Lod1Heights heights = lod1_heights(input, params.lod1);
  report.roof_z = heights.roof_z + input.origin.z;
  BuildingModel model = make_lod1_block(input, params.lod1);
  const MeshCheck check = check_mesh(model.mesh);
  if (!check.valid())
    throw ReconstructionError(ReconstructionStage::lod1, "building " + input.id + ": block is not a valid solid (" +
                              std::to_string(check.boundary_edges) + " boundary edges, " +
                              std::to_string(check.non_manifold_edges) + " non-manifold edges, volume " +
                              std::to_string(check.signed_volume) + ")");
  return model;
}

BuildingModel checked_model(const ReconstructionParams& params, ModelLevel level, bool footprint_walls_only,
                            BuildingModel model, DebugTrace* trace, BuildingReport& r) {
  const StageTimer stage(Stage::validity);
  const WrittenValidity validity = validate_as_written(model, params.output_grid, params.validity);
  if (!validity.found.empty()) {
    const std::string found = std::string(level_name(level)) + ": " + validity_codes(validity.found);
    r.validity_found += (r.validity_found.empty() ? "" : "; ") + found;
  }
  if (!validity.remaining.empty()) {
    if (trace)
      trace->rejected.emplace_back(
          level == ModelLevel::lod12 ? "lod12" : footprint_walls_only ? "footprint_walls" : "lod22", model);
    std::string problems;
    for (std::size_t k = 0; k < validity.remaining.size() && k < 3; ++k)
      problems += (k ? "; " : "") + validity.remaining[k].text();
    if (validity.remaining.size() > 3) problems += "; ...";
    throw ReconstructionError(ReconstructionStage::model, "not a valid solid as written: " + problems);
  }
  r.repairs = validity.repairs;
  return model;
}

}  // namespace city3d::detail
