// The pipeline of one building, from points to model (reconstruct_building): the paper's stages in
// order (lod2_hypothesis, then lod2_model), the rebuilds of a model that leaves points unexplained
// (explain_more) and the fallback ladder. The batch job around it is in batch.cpp.
#include "city3d/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

#include "city3d/debug_output.hpp"
#include "city3d/error.hpp"
#include "city3d/evaluation.hpp"
#include "city3d/footprint_io.hpp"
#include "city3d/log.hpp"
#include "city3d/mesh_check.hpp"
#include "city3d/model_io.hpp"
#include "city3d/stage_profile.hpp"
#include "city3d/surface_support.hpp"
#include "pipeline/left_out.hpp"

namespace city3d {
namespace fs = std::filesystem;

void ReconstructionParams::validate() const {
  // Each stage collects its own problems; gather them all into one message.
  std::string problems;
  auto check = [&](auto&& validate_stage) {
    try {
      validate_stage();
    } catch (const ConfigError& e) {
      problems += (problems.empty() ? "" : "; ") + std::string(e.what());
    }
  };
  check([&] { planes.validate(); });
  check([&] { heightmap.validate(); });
  check([&] { polylines.validate(); });
  check([&] { regularise.validate(); });
  check([&] { walls.validate(); });
  check([&] { step_lines.validate(); });
  check([&] { hypothesis.validate(); });
  check([&] { selection.validate(); });
  check([&] { assemble.validate(); });
  check([&] { lod1.validate(); });
  check([&] { validity.validate(); });
  if (!lods.any()) problems += (problems.empty() ? "" : "; ") + std::string("lods: no level of detail asked for");
  if (!(lod13_step_height > 0)) problems += (problems.empty() ? "" : "; ") + std::string("lod13_step_height must be > 0 (metres)");
  if (!(output_grid >= 0) || !std::isfinite(output_grid))
    problems += (problems.empty() ? "" : "; ") + std::string("output_grid must be >= 0 (metres)");
  if (max_footprint_vertices < 3)
    problems += (problems.empty() ? "" : "; ") + std::string("max_footprint_vertices must be >= 3");
  if (!(retry_unexplained_share >= 0) || !std::isfinite(retry_unexplained_share))
    problems += (problems.empty() ? "" : "; ") + std::string("retry_unexplained_share must be a share >= 0 (1: never retry)");
  if (!(retry_unsupported_area >= 0) || std::isnan(retry_unsupported_area))
    problems += (problems.empty() ? "" : "; ") + std::string("retry_unsupported_area must be >= 0 (m2)");
  if (!(time_limit >= 0) || !std::isfinite(time_limit))
    problems += (problems.empty() ? "" : "; ") + std::string("time_limit must be >= 0 seconds (0: none)");
  if (!problems.empty()) throw ConfigError(problems);
}

std::string parameters_text(const ReconstructionParams& p) {
  std::ostringstream s;
  s.precision(17);
  auto put = [&](const char* name, auto value) { s << name << " = " << value << "\n"; };
  put("planes.k_neighbors", p.planes.k_neighbors);
  put("planes.min_points", p.planes.min_points);
  put("planes.max_distance", p.planes.max_distance);
  put("planes.max_angle", p.planes.max_angle);
  put("planes.absorb_rounds", p.planes.absorb_rounds);
  put("planes.wall_max_normal_z", p.planes.wall_max_normal_z);
  put("heightmap.resolution", p.heightmap.resolution);
  put("heightmap.max_edge_length", p.heightmap.max_edge_length);
  put("heightmap.closing_size", p.heightmap.closing_size);
  put("heightmap.canny_low", p.heightmap.canny_low);
  put("heightmap.canny_high", p.heightmap.canny_high);
  put("polylines.max_hausdorff", p.polylines.max_hausdorff);
  put("polylines.max_cost", p.polylines.max_cost);
  put("polylines.resolution", p.polylines.resolution);
  put("polylines.link_pixels", p.polylines.link_pixels);
  put("polylines.min_polyline_length", p.polylines.min_polyline_length);
  put("polylines.relocate", p.polylines.relocate);
  put("regularise.angle_threshold", p.regularise.angle_threshold);
  put("regularise.cluster_distance", p.regularise.cluster_distance);
  put("regularise.cluster_angle", p.regularise.cluster_angle);
  put("regularise.min_cluster", p.regularise.min_cluster);
  put("regularise.merge_gap", p.regularise.merge_gap);
  put("regularise.min_footprint_edge", p.regularise.min_footprint_edge);
  put("regularise.min_segment_length", p.regularise.min_segment_length);
  put("walls.mode", static_cast<int>(p.walls.mode));
  put("walls.min_wall_length", p.walls.min_wall_length);
  put("walls.footprint_margin", p.walls.footprint_margin);
  put("walls.min_detected_lines", p.walls.min_detected_lines);
  put("walls.detected_length_ratio", p.walls.detected_length_ratio);
  put("step_lines.enabled", p.step_lines.enabled);
  put("step_lines.min_step", p.step_lines.min_step);
  put("step_lines.search_spacings", p.step_lines.search_spacings);
  put("step_lines.line_tolerance", p.step_lines.line_tolerance);
  put("step_lines.min_length", p.step_lines.min_length);
  put("step_lines.min_samples", p.step_lines.min_samples);
  put("step_lines.min_separation", p.step_lines.min_separation);
  put("hypothesis.support_distance", p.hypothesis.support_distance);
  put("hypothesis.min_face_area", p.hypothesis.min_face_area);
  put("hypothesis.line_support_margin", p.hypothesis.line_support_margin);
  put("hypothesis.cell_support_margin", p.hypothesis.cell_support_margin);
  put("hypothesis.min_support_points", p.hypothesis.min_support_points);
  put("hypothesis.vertex_merge_tolerance", p.hypothesis.vertex_merge_tolerance);
  put("hypothesis.parallel_tolerance", p.hypothesis.parallel_tolerance);
  put("hypothesis.min_edge_length", p.hypothesis.min_edge_length);
  put("hypothesis.max_planes_per_cell", p.hypothesis.max_planes_per_cell);
  put("hypothesis.floor_clearance", p.hypothesis.floor_clearance);
  put("hypothesis.unmeasured_floor_drop", p.hypothesis.unmeasured_floor_drop);
  put("hypothesis.min_part_area", p.hypothesis.min_part_area);
  put("hypothesis.min_cell_width", p.hypothesis.min_cell_width);
  put("hypothesis.line_merge_distance", p.hypothesis.line_merge_distance);
  put("hypothesis.min_line_overlap", p.hypothesis.min_line_overlap);
  put("hypothesis.large_cell_count", p.hypothesis.large_cell_count);
  put("hypothesis.max_planes_per_large_cell", p.hypothesis.max_planes_per_large_cell);
  put("hypothesis.max_unsupported_area", p.hypothesis.max_unsupported_area);
  put("hypothesis.support_cut_height", p.hypothesis.support_cut_height);
  put("hypothesis.support_cut_rise", p.hypothesis.support_cut_rise);
  put("hypothesis.support_cut_area", p.hypothesis.support_cut_area);
  put("hypothesis.surface_support.sample_spacing", p.hypothesis.surface_support.sample_spacing);
  put("hypothesis.surface_support.radius", p.hypothesis.surface_support.radius);
  put("hypothesis.surface_support.tolerance", p.hypothesis.surface_support.tolerance);
  put("selection.lambda_data", p.selection.lambda_data);
  put("selection.lambda_complexity", p.selection.lambda_complexity);
  put("selection.lambda_roof", p.selection.lambda_roof);
  put("selection.lambda_unsupported", p.selection.lambda_unsupported);
  put("selection.solver", p.selection.solver);
  put("selection.time_limit", p.selection.time_limit);
  put("selection.node_limit", p.selection.node_limit);
  put("selection.max_exact_variables", p.selection.max_exact_variables);
  put("selection.window_variables", p.selection.window_variables);
  put("selection.window_rounds", p.selection.window_rounds);
  put("selection.use_face_prior", p.selection.use_face_prior);
  put("selection.use_single_layer", p.selection.use_single_layer);
  put("assemble.collinear_tolerance", p.assemble.collinear_tolerance);
  put("assemble.merge_coplanar", p.assemble.merge_coplanar);
  put("lod1.roof_percentile", p.lod1.roof_percentile);
  put("lod1.min_height", p.lod1.min_height);
  put("output_grid", p.output_grid);
  put("lods", lod_set_text(p.lods));
  put("lod13_step_height", p.lod13_step_height);
  put("validity.snap_tolerance", p.validity.snap_tolerance);
  put("validity.planarity_distance", p.validity.planarity_distance);
  put("validity.planarity_normals", p.validity.planarity_normals);
  put("max_level", to_string(p.max_level));
  put("max_footprint_vertices", p.max_footprint_vertices);
  put("retry_unexplained_share", p.retry_unexplained_share);
  put("retry_unsupported_area", p.retry_unsupported_area);
  put("time_limit", p.time_limit);
  return s.str();
}

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The LoD1 rung: always possible when the building has points and a usable footprint.
BuildingModel lod1_rung(const BuildingInput& input, const ReconstructionParams& params, BuildingReport& report) {
  const StageTimer stage(Stage::lod1);
  const Lod1Heights heights = lod1_heights(input, params.lod1);
  report.roof_z = heights.roof_z + input.origin.z;
  BuildingModel model = make_lod1_block(input, params.lod1);
  const MeshCheck check = check_mesh(model.mesh);
  if (!check.valid())
    throw ReconstructionError("lod1: building " + input.id + ": block is not a valid solid (" +
                              std::to_string(check.boundary_edges) + " boundary edges, " +
                              std::to_string(check.non_manifold_edges) + " non-manifold edges, volume " +
                              std::to_string(check.signed_volume) + ")");
  return model;
}

// Share of a building's time limit the full LoD2 rung may use; the second rung gets the rest.
constexpr double kFullRungShare = 0.6;

// Fewest points a roof plane may have on the retry for small buildings.
constexpr std::size_t kMinPointsForSmallRoof = 10;

// Adds `note` to the report's notes unless it is there already (a rung can run twice).
void add_note(BuildingReport& report, const std::string& note) {
  if (report.note.find(note) == std::string::npos) report.note += (report.note.empty() ? "" : "; ") + note;
}

// Throws when the rung's time is used up after `stage`, so the ladder moves on (only with the opt-in
// --time-limit; without it the deadline is time_point::max()).
void check_time(Clock::time_point deadline, const char* stage) {
  if (deadline != Clock::time_point::max() && Clock::now() > deadline)
    throw ReconstructionError(std::string(stage) + ": the building's time limit is used up (see --time-limit)");
}

// The horizontal line of a detected wall segment: its points projected on the wall's horizontal
// direction, from the lowest to the highest projection.
std::pair<Point2, Point2> wall_line(const PlanarSegment& wall, const std::vector<Point3>& points) {
  const double nx = wall.plane.a, ny = wall.plane.b;
  const double len = std::hypot(nx, ny);
  const double dx = -ny / len, dy = nx / len;  // along the wall
  double lo = 1e300, hi = -1e300, cx = 0, cy = 0;
  for (std::uint32_t i : wall.points) {
    const double t = points[i].x * dx + points[i].y * dy;
    lo = std::min(lo, t);
    hi = std::max(hi, t);
    cx += points[i].x;
    cy += points[i].y;
  }
  cx /= wall.points.size();
  cy /= wall.points.size();
  const double tc = cx * dx + cy * dy;
  return {{cx + (lo - tc) * dx, cy + (lo - tc) * dy}, {cx + (hi - tc) * dx, cy + (hi - tc) * dy}};
}


// Gaps in a roof's returns (dark or wet roofing, glass) that explain_more's wide outline closes: the
// occupancy is closed with a disc of this many point spacings in radius, which fills gaps and
// concavities up to twice as wide (about 3 m at AHN3's 8 points per m2) and keeps wider ones.
constexpr double kWideGapSpacings = 4.0;

// Smallest area of an inferred outline part other than the largest that is modelled, m2: a garden
// shed or a silo (infer_outline keeps regions of 2 m2 and more, but a part needs a roof plane).
constexpr double kMinExtraPartArea = 4.0;

double ring_area(const Ring2& ring) {
  double twice = 0;
  for (std::size_t k = 0; k < ring.size(); ++k) {
    const Point2 &a = ring[k], &b = ring[(k + 1) % ring.size()];
    twice += a.x * b.y - b.x * a.y;
  }
  return std::fabs(twice) / 2;
}

// Area of polygons with holes, m2.
double polygons_area(const std::vector<Polygon2>& polygons) {
  double area = 0.0;
  for (const Polygon2& p : polygons) {
    area += ring_area(p.outer);
    for (const Ring2& h : p.holes) area -= ring_area(h);
  }
  return area;
}

bool inside_ring(const Ring2& ring, const Point2& p) {
  bool in = false;
  for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++)
    if ((ring[i].y > p.y) != (ring[j].y > p.y) &&
        p.x < (ring[j].x - ring[i].x) * (p.y - ring[i].y) / (ring[j].y - ring[i].y) + ring[i].x)
      in = !in;
  return in;
}

double segment_distance(const Point2& p, const Point2& a, const Point2& b) {
  const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
  const double t = len2 > 0 ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / len2, 0.0, 1.0) : 0.0;
  return std::hypot(p.x - a.x - t * dx, p.y - a.y - t * dy);
}

// Two rings closer than `gap` anywhere (crossing, one inside the other, or a vertex near an edge).
bool rings_near(const Ring2& a, const Ring2& b, double gap) {
  if (inside_ring(b, a.front()) || inside_ring(a, b.front())) return true;
  for (const auto& [p, q] : {std::pair{&a, &b}, std::pair{&b, &a}})
    for (const Point2& v : *p)
      for (std::size_t k = 0; k < q->size(); ++k)
        if (segment_distance(v, (*q)[k], (*q)[(k + 1) % q->size()]) < gap) return true;
  // Crossing edges without a vertex near the other ring cannot happen at this gap unless an edge
  // passes through; test the crossings too.
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) {
      const Point2 &p = a[i], &p2 = a[(i + 1) % a.size()], &q = b[j], &q2 = b[(j + 1) % b.size()];
      const auto side = [](const Point2& o, const Point2& u, const Point2& w) {
        return (u.x - o.x) * (w.y - o.y) - (u.y - o.y) * (w.x - o.x);
      };
      if (side(p, p2, q) * side(p, p2, q2) < 0 && side(q, q2, p) * side(q, q2, p2) < 0) return true;
    }
  return false;
}

// The parts of an inferred outline to model (largest first): the largest, and every further part of
// kMinExtraPartArea or more that holds most of the points of some roof plane and keeps clear of the
// parts already kept (fitting an outline to its points can push two parts into each other: then the
// part as inferred, and if that touches too, it is left out rather than made to touch). Leaving a part out shows in unexplained_points.
std::vector<Polygon2> separate_parts(const std::vector<Polygon2>& parts, const std::vector<Polygon2>& as_inferred,
                                     const std::vector<PlanarSegment>& roofs, const std::vector<Point3>& points) {
  constexpr double kGap = 0.1;  // metres between kept parts
  std::vector<std::size_t> kept_index{0};
  std::vector<Polygon2> kept{parts.front()};
  const auto near_kept = [&](const Polygon2& part) {
    std::vector<std::size_t> near;
    for (std::size_t j = 0; j < kept.size(); ++j)
      if (rings_near(part.outer, kept[j].outer, kGap)) near.push_back(j);
    return near;
  };
  for (std::size_t k = 1; k < parts.size(); ++k) {
    if (ring_area(parts[k].outer) < kMinExtraPartArea) continue;
    const bool has_plane = std::any_of(roofs.begin(), roofs.end(), [&](const PlanarSegment& s) {
      std::size_t in = 0;
      for (std::uint32_t i : s.points) in += inside_ring(parts[k].outer, {points[i].x, points[i].y});
      return 2 * in > s.points.size();
    });
    if (!has_plane) continue;
    // The part as regularised and fitted to its points; else as inferred (the regions of the
    // occupancy raster lie apart, but fitting moves edges out by up to 1.5 m), with the parts it
    // would touch taken as inferred too.
    if (near_kept(parts[k]).empty()) {
      kept.push_back(parts[k]);
      kept_index.push_back(k);
      continue;
    }
    const std::vector<std::size_t> near = near_kept(as_inferred[k]);
    std::vector<Polygon2> trial = kept;
    for (std::size_t j : near) trial[j] = as_inferred[kept_index[j]];
    bool clear = true;
    for (std::size_t i = 0; i < trial.size() && clear; ++i) {
      clear = !rings_near(as_inferred[k].outer, trial[i].outer, kGap);
      for (std::size_t j : near)
        if (j != i && rings_near(trial[j].outer, trial[i].outer, kGap)) clear = false;
    }
    if (!clear) continue;
    kept = std::move(trial);
    kept.push_back(as_inferred[k]);
    kept_index.push_back(k);
  }
  log_debug("outline: " + std::to_string(parts.size()) + " parts inferred, " + std::to_string(kept.size()) + " modelled");
  return kept;
}

// The roof planes of an inferred outline part: those with at least a quarter of their points inside it.
std::vector<PlanarSegment> roofs_of_part(const std::vector<PlanarSegment>& roofs, const Polygon2& part,
                                         const std::vector<Point3>& points) {
  std::vector<PlanarSegment> held;
  for (const PlanarSegment& s : roofs) {
    std::size_t in = 0;
    for (std::uint32_t i : s.points) in += inside_ring(part.outer, {points[i].x, points[i].y});
    if (4 * in >= s.points.size()) held.push_back(s);
  }
  return held;
}

// Mean point spacing, metres: sqrt(outline area / points).
double point_spacing(const std::vector<Polygon2>& outline, std::size_t points) {
  const double area = polygons_area(outline);
  return points > 0 && area > 0 ? std::sqrt(area / static_cast<double>(points)) : 0.0;
}

// The candidate faces of a LoD2 rung, one problem per part (a footprint is one part, whatever its
// polygons; an inferred outline has a part per region modelled, the largest first).
// What a rung's hypotheses share: the heightmap of the points, its edges and their polylines depend on
// the points and on their own parameters only, which explain_more's variants do not change (they
// change the planes, the outline's gap and the left-out points): the variants reuse the rung's. So do
// the planes' neighbour searches, normals and seed order, which depend on the points and k only.
struct SharedRaster {
  std::shared_ptr<const Heightmap> heightmap;
  std::shared_ptr<const std::vector<Point2>> edges;          // null on the footprint-walls rung
  std::shared_ptr<const std::vector<Polyline2>> polylines;   // of the edges, before the step lines join them
  std::shared_ptr<const PlaneDetector> planes;                // the points' neighbours, normals and seed order
};

struct Lod2Hypothesis {
  std::vector<CandidateFaces> parts;
  std::vector<std::size_t> part_numbers;  // each part's number among the outline's parts (for notes)
  SharedRaster raster;                    // what it was built from, for the variants of explain_more
};

// A LoD2 rung up to its face hypothesis: planes, walls, candidate faces (paper sections 3.1-3.3).
// `footprint_walls_only` skips the inferred inner walls (the second rung). `wide_outline`: without a
// footprint, the outline is inferred closing gaps of kWideGapSpacings point spacings instead of 1.5
// (explain_more's variant for roofs whose returns have gaps). `unexplained` (explain_more's variant
// for left-out points), when given, marks the points a model of this rung left farther than 1 m: they
// get roof levels, and on the full rung cells of their own (pipeline/left_out.hpp). `shared` (the
// rung's hypothesis' raster, for explain_more's variants) is reused where it holds a stage's result.
// Throws Error naming the stage when a stage fails for the largest part; a further part that fails is
// left out and said.
Lod2Hypothesis lod2_hypothesis(const BuildingInput& input, const ReconstructionParams& params,
                               bool footprint_walls_only, bool wide_outline, Clock::time_point deadline,
                               BuildingReport& report, const std::vector<bool>* unexplained = nullptr,
                               const SharedRaster* shared = nullptr) {
  SharedRaster raster = shared ? *shared : SharedRaster{};
  const bool debug = !params.debug_dir.empty();
  const auto& points = input.points;

  // Roof planes (and wall planes, if the cloud sees walls).
  std::optional<StageTimer> stage(Stage::planes);
  if (!raster.planes) raster.planes = std::make_shared<const PlaneDetector>(points, params.planes.k_neighbors);
  std::vector<PlanarSegment> segments = raster.planes->detect(params.planes);
  const auto has_roof = [](const std::vector<PlanarSegment>& found) {
    return std::any_of(found.begin(), found.end(),
                       [](const PlanarSegment& s) { return s.kind == PlanarSegment::Kind::roof; });
  };
  if (!has_roof(segments) && points.size() >= kMinPointsForSmallRoof) {
    // A shed or a garage can hold fewer points than min_points in all: rather than a block, try
    // one more time with planes of half min_points, or a third of its points when that is fewer
    // (at least kMinPointsForSmallRoof).
    PlaneParams small = params.planes;
    small.min_points =
        std::max<int>(kMinPointsForSmallRoof,
                      std::min<int>(params.planes.min_points / 2, static_cast<int>(points.size() / 3)));
    if (small.min_points < params.planes.min_points) {
      segments = raster.planes->detect(small);
      const std::string note = "small building: planes of at least " + std::to_string(small.min_points) + " points";
      if (has_roof(segments)) add_note(report, note);
    }
  }
  if (!has_roof(segments)) {
    // Too few points, or too sparse, for region growing (k-neighbour normals then mix a roof's slopes:
    // every 4th point of the Delft tiles, about 2 per m2, left six houses of 7 to 28 points without a
    // plane): planes through triples of the points, each holding at least a quarter of them.
    const std::vector<PlanarSegment> few = detect_planes_of_few_points(points, params.planes, (points.size() + 3) / 4);
    if (has_roof(few)) {
      segments = few;
      add_note(report, "few points: planes fitted through every three of its " + std::to_string(points.size()) + " points");
    }
  }
  std::vector<PlanarSegment> roofs;
  std::vector<std::pair<Point2, Point2>> detected_walls;
  for (const PlanarSegment& s : segments) {
    if (s.kind == PlanarSegment::Kind::roof)
      roofs.push_back(s);
    else
      detected_walls.push_back(wall_line(s, points));
  }
  report.planes = roofs.size();
  if (debug) write_planes_ply(debug_path(params.debug_dir, input.id, "planes.ply"), points, segments);
  if (roofs.empty())
    throw ReconstructionError("planes: no roof plane among " + std::to_string(points.size()) + " points (min_points " +
                              std::to_string(params.planes.min_points) + ")");

  check_time(deadline, "planes");

  // Heightmap, edges, polylines, regular lines: the inferred vertical planes (paper section 3.2).
  stage.emplace(Stage::heightmap);
  if (!raster.heightmap) raster.heightmap = std::make_shared<const Heightmap>(rasterise_tin(points, params.heightmap));
  const Heightmap& heightmap = *raster.heightmap;
  stage.emplace(Stage::outline);
  std::vector<Polygon2> outline = input.footprint.polygons;
  if (!input.footprint_given) {
    outline.clear();
    const std::vector<Polygon2> inferred =
        infer_outline(heightmap, points, params.polylines.max_hausdorff, 2.0, wide_outline ? kWideGapSpacings : 1.5);
    for (const Polygon2& p : inferred)
      outline.push_back(fit_outline_to_points(regularise_outline(p, params.regularise.angle_threshold), points));
    if (outline.empty() && !input.footprint.polygons.empty()) {
      // Too small for the heightmap to hold an outline (under infer_outline's 2 m2): the convex
      // hull of the points (building_from_cloud), regularised like an inferred outline.
      outline.push_back(
          regularise_outline(input.footprint.polygons.front(), params.regularise.angle_threshold));
      add_note(report, "outline: convex hull of the points");
    }
    if (outline.empty()) throw ReconstructionError("walls: no outline could be inferred from the points");
    if (outline.size() > 1) outline = separate_parts(outline, inferred, roofs, points);
    if (outline.size() > 1) add_note(report, "outline: " + std::to_string(outline.size()) + " parts");
  }
  if (unexplained) {
    // explain_more's variant for left-out points (pipeline/left_out.hpp): their roof levels.
    const std::size_t min_points =
        static_cast<std::size_t>(std::max<int>(kMinPointsForSmallRoof, params.planes.min_points / 2));
    const std::vector<PlanarSegment> levels =
        detail::left_out_levels(points, segments, *unexplained, point_spacing(outline, points.size()), min_points);
    roofs.insert(roofs.end(), levels.begin(), levels.end());
    report.planes = roofs.size();
  }
  RegularisationResult lines;
  if (!footprint_walls_only) {
    stage.emplace(Stage::edges);
    if (!raster.edges) raster.edges = std::make_shared<const std::vector<Point2>>(detect_edges(heightmap, params.heightmap));
    const std::vector<Point2>& edges = *raster.edges;
    stage.emplace(Stage::polylines);
    if (!raster.polylines)
      raster.polylines = std::make_shared<const std::vector<Polyline2>>(extract_polylines(edges, params.polylines));
    std::vector<Polyline2> polylines = *raster.polylines;
    stage.emplace(Stage::step_lines);
    // Step lines between roof planes join the heightmap's lines (the same regularisation and walls).
    const std::vector<Polyline2> steps = detect_step_lines(points, roofs, point_spacing(outline, points.size()), params.step_lines);
    if (debug) write_polylines_obj(debug_path(params.debug_dir, input.id, "step_lines.obj"), steps, input.ground_z);
    polylines.insert(polylines.end(), steps.begin(), steps.end());
    stage.emplace(Stage::regularise);
    lines = regularise(polylines, &outline, params.regularise);
    if (unexplained) {
      // Their cells, after the regularisation, which would merge a narrow part's lines into the wall
      // beside it.
      const std::vector<Segment2> left_out = detail::left_out_plane_lines(points, roofs, *unexplained, outline);
      lines.segments.insert(lines.segments.end(), left_out.begin(), left_out.end());
      lines.segments_after = lines.segments.size();
    }
    if (debug) {
      write_heightmap_png(heightmap, debug_path(params.debug_dir, input.id, "heightmap.png"));
      write_edges_png(heightmap, edges, debug_path(params.debug_dir, input.id, "edges.png"));
      write_polylines_obj(debug_path(params.debug_dir, input.id, "polylines.obj"), polylines, input.ground_z);
      write_segments_obj(debug_path(params.debug_dir, input.id, "regularised.obj"), lines.segments, input.ground_z);
    }
  }
  WallParams wall_params = params.walls;
  if (wall_params.mode == WallMode::automatic) wall_params.mode = WallMode::footprint;
  // A footprint is one problem, whatever its polygons; the parts of an inferred outline are one
  // problem each (their own walls, arrangement and selection), and their solids are joined in one
  // model: the parts of a cloud do not touch, and one arrangement over all of them could leave a
  // part's floor edge without a partner (AHN3/02523).
  std::vector<std::vector<Polygon2>> problems;
  if (input.footprint_given)
    problems.push_back(outline);
  else
    for (const Polygon2& part : outline) problems.push_back({part});

  Lod2Hypothesis hypothesis;
  hypothesis.raster = std::move(raster);
  report.walls = report.candidate_faces = 0;
  for (std::size_t k = 0; k < problems.size(); ++k) {
    const std::vector<Polygon2>& part = problems[k];
    const std::string suffix = problems.size() > 1 ? "_part" + std::to_string(k) : "";
    try {
      stage.emplace(Stage::walls);
      const std::vector<VerticalPlane> walls =
          infer_walls(lines, &part, footprint_walls_only ? std::vector<std::pair<Point2, Point2>>{} : detected_walls,
                      wall_params);
      report.walls += walls.size();
      check_time(deadline, "walls");
      if (debug)
        write_walls_obj(debug_path(params.debug_dir, input.id, "walls" + suffix + ".obj"), walls, input.ground_z,
                        input.ground_z + 20.0);

      // Face hypothesis (paper section 3.3). An inferred part's roofs are the planes it holds a
      // share of: a plane of points elsewhere (another part, or ground returns around a tree, AHN3
      // large/06050) would put a roof where none of its points are.
      const std::vector<PlanarSegment> part_roofs = input.footprint_given ? roofs : roofs_of_part(roofs, part.front(), points);
      if (part_roofs.empty())
        throw ReconstructionError("planes: none of the " + std::to_string(roofs.size()) +
                                  " roof planes lies inside the inferred outline");
      stage.emplace(Stage::hypothesis);
      CandidateFaces candidates =
          generate_candidates(points, part_roofs, walls, part, input.ground_z, input.ground_measured, params.hypothesis,
                              params.selection);
      report.candidate_faces += candidates.faces.size();
      check_time(deadline, "hypothesis");
      if (debug) write_candidates_obj(debug_path(params.debug_dir, input.id, "candidates" + suffix + ".obj"), candidates);
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

// A LoD2 rung's selection (paper section 3.3) and model: each part's faces selected and assembled,
// the parts' solids joined in one model. Throws Error when the largest part has no selection; a
// further part without one is left out and said. `without_prior` (when given) tells whether every
// part's selection had to drop the face prior (its program was infeasible with it).
BuildingModel lod2_model(const BuildingInput& input, const Lod2Hypothesis& hypothesis,
                         const ReconstructionParams& params, Clock::time_point deadline, BuildingReport& report,
                         bool* without_prior = nullptr) {
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
        selection_params.time_limit = std::max(0.1, std::min(own, left));
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
        throw ReconstructionError(std::string(selection.status == SelectionStatus::infeasible
                                                  ? "selection: infeasible"
                                                  : "selection: no solution within the limits") +
                                  " (" + std::to_string(selection.variables) + " variables): " + selection.message);

      if (!params.debug_dir.empty()) {
        const std::string suffix = hypothesis.parts.size() > 1 ? "_part" + std::to_string(hypothesis.part_numbers[k]) : "";
        write_selection_csv(debug_path(params.debug_dir, input.id, "selection" + suffix + ".csv"), candidates,
                            selection.selected, selection_params);
      }
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

// Whether two points are the same, exactly.
bool same_point(const Point3& p, const Point3& q) { return p.x == q.x && p.y == q.y && p.z == q.z; }

// Whether two hypotheses give the same model under the same selection parameters: the same
// candidate faces (vertices, faces) and the same selection problem, exactly. explain_more's variants
// often rebuild the rung's own hypothesis (smaller planes that find no new plane, a wide outline
// that closes no gap): their selections would only repeat ones already made.
bool same_hypothesis(const Lod2Hypothesis& a, const Lod2Hypothesis& b) {
  if (a.parts.size() != b.parts.size() || a.part_numbers != b.part_numbers) return false;
  const auto same_face = [](const CandidateFace& f, const CandidateFace& g) {
    return f.kind == g.kind && f.source == g.source && f.plane_id == g.plane_id && f.cell_or_edge == g.cell_or_edge &&
           f.vertices == g.vertices && f.area == g.area;
  };
  const auto same_edge = [](const SelectionProblem::Edge& e, const SelectionProblem::Edge& d) {
    return e.faces == d.faces && e.sharp_pairs == d.sharp_pairs;
  };
  for (std::size_t k = 0; k < a.parts.size(); ++k) {
    const CandidateFaces &x = a.parts[k], &y = b.parts[k];
    if (!std::equal(x.vertices.begin(), x.vertices.end(), y.vertices.begin(), y.vertices.end(), same_point) ||
        !std::equal(x.faces.begin(), x.faces.end(), y.faces.begin(), y.faces.end(), same_face))
      return false;
    const SelectionProblem &p = x.problem, &q = y.problem;
    if (p.face_count != q.face_count || p.support != q.support || p.centroid_z != q.centroid_z ||
        p.is_roof != q.is_roof || p.unsupported != q.unsupported || p.plan_area != q.plan_area ||
        p.point_count != q.point_count || p.z_min != q.z_min || p.z_max != q.z_max ||
        !std::equal(p.edges.begin(), p.edges.end(), q.edges.begin(), q.edges.end(), same_edge) ||
        p.vertical_overlaps != q.vertical_overlaps || p.exactly_one != q.exactly_one ||
        p.face_prior != q.face_prior || p.forced_on != q.forced_on || p.forced_off != q.forced_off ||
        p.start != q.start)
      return false;
  }
  return true;
}

// A rung's model as the writers will write it (rounded to the output grid), passing every val3dity
// rule: a model that does not is repaired (spikes cut, warped faces split), or this throws and the
// ladder moves on: an invalid model is never written.
BuildingModel checked_model(const BuildingInput& input, const ReconstructionParams& params, ModelLevel level,
                            bool footprint_walls_only, BuildingModel model, BuildingReport& r) {
  const StageTimer stage(Stage::validity);
  const WrittenValidity validity = validate_as_written(model, params.output_grid, params.validity);
  if (!validity.found.empty()) {
    const std::string found = std::string(to_string(level)) + ": " + validity_codes(validity.found);
    r.validity_found += (r.validity_found.empty() ? "" : "; ") + found;
  }
  if (!validity.remaining.empty()) {
    if (!params.debug_dir.empty()) {
      ModelWriteOptions local;
      local.local_coordinates = true;
      write_model(debug_path(params.debug_dir, input.id,
                             std::string("rejected_") +
                                 (level == ModelLevel::lod12 ? "lod12" : footprint_walls_only ? "footprint_walls" : "lod22") +
                                 ".obj"),
                  model, local);
    }
    std::string problems;
    for (std::size_t k = 0; k < validity.remaining.size() && k < 3; ++k)
      problems += (k ? "; " : "") + validity.remaining[k].text();
    if (validity.remaining.size() > 3) problems += "; ...";
    throw ReconstructionError("model: not a valid solid as written: " + problems);
  }
  r.repairs = validity.repairs;
  return model;
}

// How faithful a model is to the building's points, both ways: from the points to the model, how many
// lie farther than kUnexplainedDistance and the sum of the squared distances; from the model to the
// points, its surface no point supports (surface_support.hpp).
struct Explained {
  std::size_t far = 0;
  double squares = 0.0;
  SurfaceSupport support;
  /// Both directions in one figure, in points: the points left out, plus the unsupported area at
  /// the building's point density (`points_per_m2`): a square metre of surface no point asks for
  /// weighs as much as a square metre of points the model leaves out (the selection's E_u and E_d).
  double unfaithful(double points_per_m2) const {
    return static_cast<double>(far) + support.unsupported_area * points_per_m2;
  }
  /// The sum of the squared distances, both ways: each square metre of unsupported surface counted as
  /// the points of a square metre lying kUnexplainedDistance off it.
  double squares_both_ways(double points_per_m2) const {
    return squares + support.unsupported_area * points_per_m2 * kUnexplainedDistance * kUnexplainedDistance;
  }
};

// From the points to the model only.
Explained explained_points(const PolygonMesh& mesh, const std::vector<Point3>& points,
                           std::vector<double>* distances_out = nullptr) {
  const StageTimer stage(Stage::measure);
  Explained e;
  const std::vector<double> distances = point_distances(mesh, points);
  for (const double d : distances) {
    e.far += d > kUnexplainedDistance;
    e.squares += d * d;
  }
  if (distances_out) *distances_out = distances;
  return e;
}

// Both ways.
Explained explained(const BuildingModel& model, const std::vector<Point3>& points, const LocalTop& local_top,
                    const SurfaceSupportParams& support_params, std::vector<double>* distances_out = nullptr) {
  Explained e = explained_points(model.mesh, points, distances_out);
  const StageTimer stage(Stage::measure);
  e.support = surface_support(model.mesh, surface_types(model), local_top, support_params);
  return e;
}

std::string percent(std::size_t part, std::size_t whole) {
  std::ostringstream s;
  s.precision(1);
  s << std::fixed << 100.0 * static_cast<double>(part) / static_cast<double>(whole) << "%";
  return s.str();
}

// A work limit of explain_more: a building whose hypothesis has more candidate faces than this is not
// rebuilt, and a variant hypothesis with more is not selected. Each rebuild is a selection at least as
// large as the rung's, and the smaller planes make larger programs: the two 40,000-point clouds of
// city3d_dev (8,312 and 13,874 candidate faces) took 521 s and 110 s with their rebuilds, against 14 s
// and 10 s without, and AHN3/13894's smaller planes turned 1,933 candidate faces into 5,852 and 1 s
// into 38 s (docs/BENCHMARKS.md).
constexpr std::size_t kMaxRebuildFaces = 3000;

// Issue 10's "every point explained, or reported" and issue 23's "no surface the points don't
// support": when a LoD2 model leaves more than retry_unexplained_share of the points unexplained, or
// carries more than retry_unsupported_area of surface no point supports, the rung is rebuilt with
// variants that address what leaves points out, each a deterministic function of the input. The
// points beneath unsupported surface count as left out (points_beneath_unsupported: a low annex whose
// few points form no plane, under a roof plane extended over it, is near that roof's walls but
// misrepresented all the same). Hypotheses:
//  - roof planes of half min_points: an upper part or a small tier whose few points form no plane of
//    min_points is otherwise covered by the roof below it;
//  - without a footprint, an outline closing wider gaps (kWideGapSpacings): a roof whose returns have
//    gaps (dark or wet roofing, glass) is otherwise cut at the gap, and a changed outline changes
//    the lines regularised against it; and both;
//  - roofs for the points left out (pipeline/left_out.hpp): a horizontal level for each group of
//    them in no plane, and a cell of its own for each plane they mostly make up.
// Selections over each hypothesis (the first hypothesis is reused from the rung, so these cost a
// selection each, not a rebuild):
//  - without the face prior: the paper's hard constraint keeps the best face of every roof plane, so
//    a plane fitted to ground or clutter points can force its face over a cell the roof above
//    explains (a flat roof modelled at ground level over a third of the building);
//  - half the complexity weight: a roof part of few points costs more edges than its points weigh;
//  - both.
// A model rebuilt only for its unsupported surface is selected over each hypothesis without those
// variants of the selection.
// A variant replaces the model only if it is more faithful both ways (Explained::unfaithful: fewer
// points left out plus less unsupported surface at the point density) and fits better both ways
// (Explained::squares_both_ways: a smaller sum of squared distances, with a square metre of unsupported
// surface counted as the points of a square metre 1 m off; without unsupported surface, the sum of the
// points' squared distances). The report says which variant was kept, or that none helped.
// `before_hypothesis` and `before_selection` are the report as it was before the rung's hypothesis
// and before its selection; debug files are written for the rung's own hypothesis only. Returns how
// well the model it leaves explains the points (measured once: the report's figures reuse it).
Explained explain_more(const BuildingInput& input, const ReconstructionParams& params, ModelLevel level,
                  bool footprint_walls_only, const Lod2Hypothesis& hypothesis, const BuildingReport& before_hypothesis,
                  const BuildingReport& before_selection, bool own_without_prior, Clock::time_point deadline,
                  BuildingReport& r, BuildingModel& model) {
  const std::size_t n = input.points.size();
  if (n == 0) return {};
  const SurfaceSupportParams& support_params = params.hypothesis.surface_support;
  std::optional<StageTimer> measuring(Stage::measure);
  const LocalTop local_top(input.points, support_params.radius);
  measuring.reset();
  std::vector<double> distances;
  Explained best = explained(model, input.points, local_top, support_params, &distances);
  const bool too_many_left_out = static_cast<double>(best.far) > params.retry_unexplained_share * static_cast<double>(n);
  const bool unsupported = best.support.unsupported_area > params.retry_unsupported_area;
  if (!too_many_left_out && !unsupported) return best;
  std::vector<bool> unexplained = points_beneath_unsupported(best.support, input.points, support_params);
  for (std::size_t i = 0; i < n; ++i) unexplained[i] = unexplained[i] || distances[i] > kUnexplainedDistance;
  const double area = polygons_area(input.footprint.polygons);
  const double density = area > 0.0 ? static_cast<double>(n) / area : 0.0;
  const auto what = [&](const Explained& e) {
    std::string text;
    if (too_many_left_out) text = "unexplained points " + percent(e.far, n);
    if (unsupported) {
      std::ostringstream s;
      s.precision(1);
      s << std::fixed << e.support.unsupported_area << " m2";
      text += (text.empty() ? "" : ", ") + std::string("unsupported surface ") + s.str();
    }
    return text;
  };
  const auto candidate_faces = [](const Lod2Hypothesis& h) {
    std::size_t faces = 0;
    for (const CandidateFaces& part : h.parts) faces += part.faces.size();
    return faces;
  };
  const std::size_t faces = candidate_faces(hypothesis);
  const RebuildScope rebuilding;  // from here on, the stages count as the rebuild's
  if (faces > kMaxRebuildFaces) {
    add_note(r, what(best) + ": not rebuilt (" + std::to_string(faces) + " candidate faces, more than " +
                    std::to_string(kMaxRebuildFaces) + ")");
    return best;
  }
  const int small_points = std::max<int>(kMinPointsForSmallRoof, params.planes.min_points / 2);
  struct HypothesisVariant {
    bool smaller_planes;
    bool wide_outline;
    bool left_out;
  };
  std::vector<HypothesisVariant> hypotheses{{false, false, false}};
  if (small_points < params.planes.min_points) hypotheses.push_back({true, false, false});
  if (!input.footprint_given) {
    hypotheses.push_back({false, true, false});
    if (small_points < params.planes.min_points) hypotheses.push_back({true, true, false});
  }
  hypotheses.push_back({false, false, true});
  struct SelectionVariant {
    bool without_prior;
    bool half_complexity;
  };
  const SelectionVariant selections[] = {{false, false}, {true, false}, {false, true}, {true, true}};
  const auto name = [&](const HypothesisVariant& h, const SelectionVariant& v) {
    std::string text;
    const auto add = [&text](const std::string& part) { text += (text.empty() ? "" : ", ") + part; };
    if (h.smaller_planes) add("roof planes of at least " + std::to_string(small_points) + " points");
    if (h.left_out) add("roofs for the points left out");
    if (h.wide_outline)
      add("an outline closing gaps of " + std::to_string(static_cast<int>(kWideGapSpacings)) + " point spacings");
    if (v.without_prior) add("without the face prior");
    if (v.half_complexity) add("half the complexity weight");
    return text;
  };

  std::vector<Lod2Hypothesis> tried;  // the variant hypotheses selected over (the rung's own is `hypothesis`)
  const Explained before = best;
  std::string kept;
  std::string over_limit;  // variant hypotheses not selected: more than kMaxRebuildFaces candidate faces
  BuildingReport kept_report;
  // The opt-in --time-limit bounds the rebuilds too: once it is used up no further variant is begun,
  // and the best model so far is kept.
  const auto out_of_time = [&] { return deadline != Clock::time_point::max() && Clock::now() > deadline; };
  bool stopped = false;
  for (const HypothesisVariant& h : hypotheses) {
    if ((stopped = stopped || out_of_time())) break;
    const bool own = !h.smaller_planes && !h.wide_outline && !h.left_out;
    ReconstructionParams hp = params;
    hp.debug_dir.clear();
    if (h.smaller_planes) hp.planes.min_points = small_points;
    BuildingReport after_hypothesis = own ? before_selection : before_hypothesis;
    std::optional<Lod2Hypothesis> built;
    if (!own) {
      try {
        built = lod2_hypothesis(input, hp, footprint_walls_only, h.wide_outline, deadline, after_hypothesis,
                                h.left_out ? &unexplained : nullptr, &hypothesis.raster);
      } catch (const Error& e) {
        log_debug("explain: building " + input.id + ": " + name(h, {}) + ": " + e.what());
        continue;
      }
      if (candidate_faces(*built) > kMaxRebuildFaces) {
        over_limit += (over_limit.empty() ? "" : ", ") + name(h, {}) + ": " + std::to_string(candidate_faces(*built));
        continue;
      }
      // A hypothesis already selected over gives the same models again: none could be kept.
      if (same_hypothesis(*built, hypothesis) ||
          std::any_of(tried.begin(), tried.end(), [&](const Lod2Hypothesis& t) { return same_hypothesis(*built, t); })) {
        log_debug("explain: building " + input.id + ": " + name(h, {}) + ": the same hypothesis as one tried");
        continue;
      }
    }
    // Selections with the prior that had to drop it equal those without: those are skipped.
    bool prior_dropped = own && own_without_prior;
    for (const SelectionVariant& v : selections) {
      if ((stopped = out_of_time())) break;
      if (own && !v.without_prior && !v.half_complexity) continue;  // the rung's own model
      // Surface no point supports, with the points explained, is a matter of the hypothesis (a part
      // too small for a plane, a roof level missing): the selections that explain more points (without
      // the face prior, half the complexity weight) are not tried for it.
      if (!too_many_left_out && (v.without_prior || v.half_complexity)) continue;
      if (v.without_prior && prior_dropped) continue;
      ReconstructionParams p = hp;
      if (v.without_prior) p.selection.use_face_prior = false;
      if (v.half_complexity) p.selection.lambda_complexity /= 2;
      BuildingReport trial = after_hypothesis;
      try {
        bool dropped = false;
        BuildingModel m = checked_model(input, p, level, footprint_walls_only,
                                        lod2_model(input, own ? hypothesis : *built, p, deadline, trial, &dropped),
                                        trial);
        if (!v.without_prior && !v.half_complexity) prior_dropped = dropped;
        Explained e = explained(m, input.points, local_top, support_params);
        if (e.unfaithful(density) < best.unfaithful(density) &&
            e.squares_both_ways(density) < best.squares_both_ways(density)) {
          best = std::move(e);
          model = std::move(m);
          kept = name(h, v);
          kept_report = std::move(trial);
        }
      } catch (const Error& e) {
        // A variant that cannot be built leaves the model as it was.
        log_debug("explain: building " + input.id + ": " + name(h, v) + ": " + e.what());
      }
    }
    if (built) tried.push_back(std::move(*built));
  }
  if (!kept.empty()) {
    r = std::move(kept_report);
    std::string change;
    if (too_many_left_out) change = "unexplained points " + percent(before.far, n) + " -> " + percent(best.far, n);
    if (unsupported) {
      std::ostringstream s;
      s.precision(1);
      s << std::fixed << "unsupported surface " << before.support.unsupported_area << " -> "
        << best.support.unsupported_area << " m2";
      change += (change.empty() ? "" : ", ") + s.str();
    }
    add_note(r, "rebuilt (" + kept + "): " + change);
  } else {
    add_note(r, what(before) + ": no rebuild explained more");
  }
  if (!over_limit.empty())
    add_note(r, "not tried (more than " + std::to_string(kMaxRebuildFaces) + " candidate faces): " + over_limit);
  if (stopped) add_note(r, "rebuilds stopped at the time limit");
  return best;
}

// Monotone-chain convex hull, counter-clockwise, without collinear points.
Ring2 convex_hull(std::vector<Point2> pts) {
  std::sort(pts.begin(), pts.end(), [](const Point2& a, const Point2& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  pts.erase(std::unique(pts.begin(), pts.end(), [](const Point2& a, const Point2& b) { return a.x == b.x && a.y == b.y; }),
            pts.end());
  if (pts.size() < 3) return pts;
  auto cross = [](const Point2& o, const Point2& a, const Point2& b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
  };
  Ring2 hull(2 * pts.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  for (std::size_t i = pts.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], pts[i - 1]) <= 0) --k;
    hull[k++] = pts[i - 1];
  }
  hull.resize(k - 1);
  return hull;
}

// Heights, footprint area and point density of the report (3DBAG's b3_h_* attributes).
void describe_points(const BuildingInput& input, const ReconstructionParams& params, BuildingReport& r) {
  const double area = polygons_area(input.footprint.polygons);
  r.footprint_area = area;
  r.point_density = area > 0 ? input.points.size() / area : 0.0;
  if (input.points.empty()) {
    r.roof_type = "no points";
    return;
  }
  std::vector<double> z;
  z.reserve(input.points.size());
  for (const Point3& p : input.points) z.push_back(p.z + input.origin.z);
  r.h_roof_50p = percentile(z, 50.0);
  r.h_roof_70p = percentile(z, params.lod1.roof_percentile);
  r.h_roof_min = *std::min_element(z.begin(), z.end());
  r.h_roof_max = *std::max_element(z.begin(), z.end());
  r.roof_type = "could not be detected";
}

// Roof type of an LoD2.2 model as 3DBAG names them: every roof face within 3 degrees of horizontal
// and all at one height (within 0.3 m): "horizontal"; horizontal at several heights: "multiple
// horizontal"; otherwise "slanted".
std::string roof_type_of(const BuildingModel& model) {
  const std::vector<SurfaceType> types = surface_types(model);
  std::vector<double> heights;
  bool slanted = false;
  for (std::size_t f = 0; f < model.mesh.faces.size(); ++f) {
    if (types[f] != SurfaceType::roof) continue;
    const auto& face = model.mesh.faces[f];
    double nx = 0, ny = 0, nz = 0, zsum = 0;
    for (std::size_t k = 0; k < face.size(); ++k) {
      const Point3& a = model.mesh.vertices[face[k]];
      const Point3& b = model.mesh.vertices[face[(k + 1) % face.size()]];
      nx += (a.y - b.y) * (a.z + b.z);
      ny += (a.z - b.z) * (a.x + b.x);
      nz += (a.x - b.x) * (a.y + b.y);
      zsum += a.z;
    }
    const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
    if (!(len > 0)) continue;
    if (nz / len < std::cos(3.0 * 3.14159265358979 / 180.0)) slanted = true;
    heights.push_back(zsum / face.size());
  }
  if (heights.empty()) return "could not be detected";
  if (slanted) return "slanted";
  std::sort(heights.begin(), heights.end());
  for (std::size_t k = 1; k < heights.size(); ++k)
    if (heights[k] - heights[k - 1] > 0.3) return "multiple horizontal";
  return "horizontal";
}

// Whether two models are the same, exactly: vertices, faces, origin and surface types.
bool same_model(const BuildingModel& a, const BuildingModel& b) {
  return a.mesh.faces == b.mesh.faces && a.surfaces == b.surfaces && same_point(a.origin, b.origin) &&
         std::equal(a.mesh.vertices.begin(), a.mesh.vertices.end(), b.mesh.vertices.begin(), b.mesh.vertices.end(),
                    same_point);
}

// LoD1.2 and LoD1.3 derived from the LoD2.2 model (or only the LoD1.2 block when the ladder ended
// there), each valid as written; volumes and RMSE per level; the model OBJ/PLY get is the highest
// level asked for. `lod2_fit`: the LoD2 model's distances to the points, when already measured.
void add_levels_of_detail(const BuildingInput& input, const ReconstructionParams& params,
                          const std::optional<Explained>& lod2_fit, BuildingResult& result) {
  BuildingReport& r = result.report;
  const BuildingModel primary = *result.model;
  std::vector<LodModel> made;  // in order 1.2, 1.3, 2.2
  std::vector<std::string> real;
  const bool lod2 = r.level == ModelLevel::lod22 || r.level == ModelLevel::lod22_footprint_walls;
  // A building of one height level has the same blocks at LoD1.3 as at LoD1.2: they are validated
  // (and below measured) once.
  std::optional<std::pair<BuildingModel, BuildingModel>> derived;  // the last blocks, as made and as validated
  const auto derive = [&](const char* lod, double step) {
    try {
      BuildingModel blocks = make_lod13_blocks(primary, input.points, input.ground_z, step,
                                               params.lod1.roof_percentile, params.lod1.min_height);
      if (derived && same_model(blocks, derived->first)) {
        made.push_back({lod, derived->second});
        real.push_back(lod);
        return;
      }
      BuildingModel made_blocks = blocks;
      const WrittenValidity v = validate_as_written(blocks, params.output_grid, params.validity);
      if (!v.remaining.empty()) throw ReconstructionError("not valid as written: " + v.remaining.front().text());
      derived.emplace(std::move(made_blocks), blocks);
      made.push_back({lod, std::move(blocks)});
      real.push_back(lod);
    } catch (const Error& e) {
      r.note += (r.note.empty() ? "" : "; ") + std::string("LoD") + lod + " not made: " + e.what();
    }
  };
  if (lod2) {
    if (params.lods.lod12) derive("1.2", std::numeric_limits<double>::infinity());
    if (params.lods.lod13) derive("1.3", params.lod13_step_height);
    made.push_back({"2.2", primary});
    real.push_back("2.2");
    r.h_ridge = -std::numeric_limits<double>::infinity();
    const std::vector<SurfaceType> types = surface_types(primary);
    for (std::size_t f = 0; f < primary.mesh.faces.size(); ++f)
      if (types[f] == SurfaceType::roof)
        for (std::uint32_t v : primary.mesh.faces[f]) r.h_ridge = std::max(r.h_ridge, primary.mesh.vertices[v].z + primary.origin.z);
    r.roof_type = roof_type_of(primary);
  } else {
    made.push_back({"1.2", primary});
    real.push_back("1.2");
  }
  // Keep the levels asked for; when none of them could be made, the ladder's fallback is kept.
  std::vector<LodModel> kept;
  for (LodModel& m : made) {
    const bool asked = (m.lod == "1.2" && params.lods.lod12) || (m.lod == "1.3" && params.lods.lod13) ||
                       (m.lod == "2.2" && params.lods.lod22);
    if (asked) kept.push_back(std::move(m));
  }
  if (kept.empty()) kept.push_back({lod2 ? "2.2" : "1.2", primary});
  std::optional<std::pair<const BuildingModel*, Explained>> measured;  // the last level measured
  for (const LodModel& m : kept) {
    const double volume = check_mesh(m.model.mesh).signed_volume;
    if (!(lod2 && m.lod == "2.2" && lod2_fit) && !(measured && same_model(m.model, *measured->first)))
      measured.emplace(&m.model, explained_points(m.model.mesh, input.points));
    const Explained fit = lod2 && m.lod == "2.2" && lod2_fit ? *lod2_fit : measured->second;
    const std::size_t n = input.points.size();
    const double error = n == 0 ? 0.0 : std::sqrt(fit.squares / static_cast<double>(n));
    // The unexplained points of the model the OBJ/PLY files hold: the last level kept.
    r.unexplained_points = static_cast<double>(fit.far);
    r.unexplained_share = n == 0 ? 0.0 : static_cast<double>(fit.far) / static_cast<double>(n);
    (m.lod == "1.2" ? r.volume_lod12 : m.lod == "1.3" ? r.volume_lod13 : r.volume_lod22) = volume;
    (m.lod == "1.2" ? r.rmse_lod12 : m.lod == "1.3" ? r.rmse_lod13 : r.rmse_lod22) = error;
    r.lods += (r.lods.empty() ? "" : ",") + m.lod;
    if (std::find(real.begin(), real.end(), m.lod) != real.end())
      r.lods_reconstructed += (r.lods_reconstructed.empty() ? "" : ",") + m.lod;
  }
  result.model = kept.back().model;
  r.faces = result.model->mesh.faces.size();
  // The model written, from the model to the points (explain_more measured a LoD2.2 model already).
  if (!input.points.empty()) {
    const SurfaceSupportParams& support_params = params.hypothesis.surface_support;
    const SurfaceSupport support =
        lod2 && kept.back().lod == "2.2" && lod2_fit
            ? lod2_fit->support
            : surface_support(result.model->mesh, surface_types(*result.model),
                              LocalTop(input.points, support_params.radius), support_params);
    r.unsupported_area = support.unsupported_area;
    r.height_excess = support.height_excess;
  }
  result.lods = std::move(kept);
}

// The RMSE of the model the OBJ/PLY files hold (the highest level written), already measured for its
// level's attribute.
double highest_level_rmse(const BuildingReport& r) {
  const std::string highest = r.lods.substr(r.lods.rfind(',') == std::string::npos ? 0 : r.lods.rfind(',') + 1);
  return highest == "1.2" ? r.rmse_lod12 : highest == "1.3" ? r.rmse_lod13 : r.rmse_lod22;
}

}  // namespace

LodSet parse_lod_set(const std::string& text) {
  LodSet set{false, false, false};
  if (text == "all") return LodSet{};
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (item == "1.2") set.lod12 = true;
    else if (item == "1.3") set.lod13 = true;
    else if (item == "2.2" || item == "2") set.lod22 = true;
    else throw ConfigError("lod: '" + item + "' is not 1.2, 1.3 or 2.2 (give a comma-separated list, e.g. 1.2,2.2)");
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return set;
}

std::string lod_set_text(const LodSet& lods) {
  std::string s;
  if (lods.lod12) s += "1.2";
  if (lods.lod13) s += std::string(s.empty() ? "" : ",") + "1.3";
  if (lods.lod22) s += std::string(s.empty() ? "" : ",") + "2.2";
  return s;
}

BuildingInput building_from_cloud(const BuildingId& id, const std::vector<Point3>& world_points,
                                  std::optional<double> ground_z) {
  BuildingInput input;
  input.id = id;
  input.footprint.id = id;
  input.footprint_given = false;
  if (world_points.empty()) return input;
  Box3 box;
  for (const Point3& p : world_points) box.add(p);
  // An integer origin keeps local + origin exact in double (see crop.hpp).
  input.origin = {std::round((box.min.x + box.max.x) / 2), std::round((box.min.y + box.max.y) / 2), 0.0};
  input.points.reserve(world_points.size());
  std::vector<Point2> xy;
  xy.reserve(world_points.size());
  for (const Point3& p : world_points) {
    input.points.push_back({p.x - input.origin.x, p.y - input.origin.y, p.z});
    xy.push_back({p.x - input.origin.x, p.y - input.origin.y});
  }
  // The convex hull serves the LoD1 rung; the LoD2 rungs infer a real outline from the points.
  input.footprint.polygons.push_back({convex_hull(std::move(xy)), {}});
  input.footprint_given = false;
  if (ground_z) {
    input.ground_z = *ground_z;
    input.ground_method = "given";
    input.ground_measured = true;
  } else {
    input.ground_z = box.min.z;
    input.ground_method = "lowest building point";
  }
  return input;
}

BuildingResult reconstruct_building(const BuildingInput& given, const ReconstructionParams& params) {
  const StageTimer building(Stage::other);
  const auto start = Clock::now();
  const double cpu_start = building_cpu_seconds();
  // A footprint of very many vertices is simplified first (a work limit: walls, arrangement and
  // program grow with its edges); the copy of the input is made only then.
  std::optional<BuildingInput> simplified;
  std::string simplify_note;
  if (given.footprint_given) {
    std::size_t vertices = 0;
    for (const Polygon2& p : given.footprint.polygons) {
      vertices += p.outer.size();
      for (const Ring2& h : p.holes) vertices += h.size();
    }
    if (vertices > params.max_footprint_vertices) {
      SimplifiedFootprint s = simplify_footprint(given.footprint.polygons, params.max_footprint_vertices);
      simplified = given;
      simplified->footprint.polygons = std::move(s.polygons);
      std::ostringstream note;
      note << "footprint: " << s.vertices_before << " vertices simplified to " << s.vertices_after << " (tolerance "
           << s.tolerance << " m; max_footprint_vertices " << params.max_footprint_vertices << ")";
      simplify_note = note.str();
    }
  }
  const BuildingInput& input = simplified ? *simplified : given;
  BuildingResult result;
  BuildingReport& r = result.report;
  r.id = input.id;
  r.points = input.points.size();
  r.ground_points = input.ground_points.size();
  r.ground_z = input.ground_z + input.origin.z;
  r.ground_method = input.ground_method;
  r.note = input.footprint.note;
  if (!simplify_note.empty()) add_note(r, simplify_note);
  {
    const StageTimer stage(Stage::describe);
    describe_points(input, params, r);
    if (!input.points.empty()) {
      try {
        r.roof_z = lod1_heights(input, params.lod1).roof_z + input.origin.z;
      } catch (const Error&) {
        // Reported by the LoD1 rung if it comes to that.
      }
    }
  }
  if (input.points.empty() && !input.footprint_given) {
    // A single-building cloud without points has no outline either: say what is really missing.
    r.status = BuildingStatus::skipped;
    r.stage = "input";
    r.reason = "the point cloud has no points";
  } else if (input.footprint.polygons.empty()) {
    r.status = BuildingStatus::skipped;
    r.stage = "crop";
    r.reason = "footprint has no usable polygon";
  } else if (input.points.empty()) {
    r.status = BuildingStatus::skipped;
    r.stage = "crop";
    r.reason = "no building points inside the footprint";
  } else {
    // The fallback ladder: full LoD2 -> LoD2 with footprint walls only -> LoD1 block. The first rung
    // that gives a closed, 2-manifold, outward model wins; the report keeps the first failure.
    struct Rung {
      ModelLevel level;
      bool footprint_walls_only;
    };
    const Rung rungs[] = {{ModelLevel::lod22, false}, {ModelLevel::lod22_footprint_walls, true}, {ModelLevel::lod12, false}};
    const ModelLevel requested = params.max_level == ModelLevel::none ? ModelLevel::lod22 : params.max_level;
    bool started = false;
    std::optional<Explained> lod2_fit;  // the LoD2 model's distances, as explain_more measured them
    for (const Rung& rung : rungs) {
      if (rung.level == requested) started = true;
      if (!started) continue;
      try {
        // With --time-limit, the full rung may use 60% of the building's time, the footprint-walls
        // rung the rest.
        const double share = rung.level == ModelLevel::lod22 ? kFullRungShare : 1.0;
        const auto deadline = params.time_limit > 0
                                  ? start + std::chrono::duration_cast<Clock::duration>(
                                                std::chrono::duration<double>(share * params.time_limit))
                                  : Clock::time_point::max();
        BuildingModel model;
        if (rung.level == ModelLevel::lod12) {
          model = checked_model(input, params, rung.level, false, lod1_rung(input, params, r), r);
        } else {
          const BuildingReport before_hypothesis = r;
          const Lod2Hypothesis hypothesis = lod2_hypothesis(input, params, rung.footprint_walls_only, false, deadline, r);
          const BuildingReport before_selection = r;
          bool without_prior = false;
          model = checked_model(input, params, rung.level, rung.footprint_walls_only,
                                lod2_model(input, hypothesis, params, deadline, r, &without_prior), r);
          lod2_fit = explain_more(input, params, rung.level, rung.footprint_walls_only, hypothesis, before_hypothesis,
                                  before_selection, without_prior, deadline, r, model);
        }
        r.level = rung.level;
        r.status = rung.level == requested ? BuildingStatus::ok : BuildingStatus::fallback;
        r.faces = model.mesh.faces.size();
        r.valid = true;
        result.model = std::move(model);
        break;
      } catch (const Error& e) {
        if (r.reason.empty()) {
          r.reason = e.what();
          const std::string what = e.what();
          r.stage = what.substr(0, what.find(':'));
        }
      }
    }
    if (!result.model) r.status = BuildingStatus::failed;
    if (result.model) {
      const StageTimer stage(Stage::lod1);
      add_levels_of_detail(input, params, lod2_fit, result);
    }
    if (result.model) {
      const StageTimer stage(Stage::measure);
      r.rmse = r.lods.empty() ? rmse(result.model->mesh, input.points) : highest_level_rmse(r);
    }
    if (r.status == BuildingStatus::ok) r.stage.clear(), r.reason.clear();
  }

  r.seconds = seconds_since(start);
  r.cpu_seconds = building_cpu_seconds() - cpu_start;
  return result;
}

}  // namespace city3d
