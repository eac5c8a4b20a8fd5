// The pipeline: one building from points to model (reconstruct_building), and the batch job around
// it (run_batch): footprints, tiles, cropping, parallel reconstruction, ordered output, report.
#include "city3d/pipeline.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <numeric>
#include <sstream>
#include <thread>

#include "city3d/error.hpp"
#include "city3d/evaluation.hpp"
#include "city3d/log.hpp"
#include "city3d/mesh_check.hpp"
#include "city3d/model_io.hpp"
#include "city3d/point_cloud_io.hpp"
#include "pipeline/journal.hpp"
#include "pipeline/report.hpp"

namespace city3d {
namespace fs = std::filesystem;

const char* to_string(BuildingStatus status) {
  switch (status) {
    case BuildingStatus::ok: return "ok";
    case BuildingStatus::fallback: return "fallback";
    case BuildingStatus::skipped: return "skipped";
    case BuildingStatus::failed: return "failed";
  }
  return "failed";
}

const char* to_string(ModelLevel level) {
  switch (level) {
    case ModelLevel::none: return "none";
    case ModelLevel::lod22: return "LoD2.2";
    case ModelLevel::lod22_footprint_walls: return "LoD2.2 footprint walls";
    case ModelLevel::lod12: return "LoD1.2";
  }
  return "none";
}

const char* cityjson_lod(ModelLevel level) {
  switch (level) {
    case ModelLevel::lod22:
    case ModelLevel::lod22_footprint_walls: return "2.2";
    case ModelLevel::lod12: return "1.2";
    case ModelLevel::none: return "";
  }
  return "";
}

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
  check([&] { hypothesis.validate(); });
  check([&] { selection.validate(); });
  check([&] { assemble.validate(); });
  check([&] { lod1.validate(); });
  if (!(time_limit > 0)) problems += (problems.empty() ? "" : "; ") + std::string("time_limit must be positive");
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
  put("selection.lambda_data", p.selection.lambda_data);
  put("selection.lambda_complexity", p.selection.lambda_complexity);
  put("selection.lambda_roof", p.selection.lambda_roof);
  put("selection.solver", p.selection.solver);
  put("selection.auto_cbc_variables", p.selection.auto_cbc_variables);
  put("selection.time_limit", p.selection.time_limit);
  put("selection.node_limit", p.selection.node_limit);
  put("selection.use_face_prior", p.selection.use_face_prior);
  put("selection.use_single_layer", p.selection.use_single_layer);
  put("assemble.collinear_tolerance", p.assemble.collinear_tolerance);
  put("assemble.merge_coplanar", p.assemble.merge_coplanar);
  put("lod1.roof_percentile", p.lod1.roof_percentile);
  put("lod1.min_height", p.lod1.min_height);
  put("max_level", to_string(p.max_level));
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

// Throws when the rung's time is used up after `stage`, so the ladder moves on.
void check_time(Clock::time_point deadline, const char* stage) {
  if (Clock::now() > deadline)
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

// <debug_dir>/<id made file-safe>/<name>, creating the folder.
std::string debug_path(const ReconstructionParams& params, const BuildingId& id, const std::string& name) {
  const fs::path dir = fs::path(params.debug_dir) / fs::path(model_file_name(id, MeshFormat::obj)).stem();
  fs::create_directories(dir);
  return (dir / name).string();
}

// Writes the planar segments as a PLY point cloud coloured by segment (grey: no segment).
void write_planes_ply(const std::string& path, const std::vector<Point3>& points,
                      const std::vector<PlanarSegment>& segments) {
  std::vector<int> label(points.size(), -1);
  for (std::size_t s = 0; s < segments.size(); ++s)
    for (std::uint32_t i : segments[s].points) label[i] = static_cast<int>(s);
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw IoError("debug: cannot write " + path);
  std::fprintf(f, "ply\nformat ascii 1.0\nelement vertex %zu\nproperty double x\nproperty double y\nproperty double z\n"
               "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty int segment\nend_header\n",
               points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    // A fixed pseudo-random colour per segment.
    const unsigned h = label[i] < 0 ? 0u : static_cast<unsigned>(label[i] + 1) * 2654435761u;
    const int r = label[i] < 0 ? 160 : 40 + (h >> 8) % 200, g = label[i] < 0 ? 160 : 40 + (h >> 16) % 200,
              b = label[i] < 0 ? 160 : 40 + (h >> 24) % 200;
    std::fprintf(f, "%.4f %.4f %.4f %d %d %d %d\n", points[i].x, points[i].y, points[i].z, r, g, b, label[i]);
  }
  std::fclose(f);
}

// A LoD2 rung: planes, walls, hypothesis, selection, model. `footprint_walls_only` skips the
// inferred inner walls (the second rung). Throws Error naming the stage when a stage fails.
BuildingModel lod2_rung(const BuildingInput& input, const ReconstructionParams& params, bool footprint_walls_only,
                        Clock::time_point deadline, BuildingReport& report) {
  const bool debug = !params.debug_dir.empty();
  const auto& points = input.points;

  // Roof planes (and wall planes, if the cloud sees walls).
  std::vector<PlanarSegment> segments = detect_planes(points, params.planes);
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
      segments = detect_planes(points, small);
      const std::string note = "small building: planes of at least " + std::to_string(small.min_points) + " points";
      if (has_roof(segments) && report.note.find(note) == std::string::npos)
        report.note += (report.note.empty() ? "" : "; ") + note;
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
  if (debug) write_planes_ply(debug_path(params, input.id, "planes.ply"), points, segments);
  if (roofs.empty())
    throw ReconstructionError("planes: no roof plane among " + std::to_string(points.size()) + " points (min_points " +
                              std::to_string(params.planes.min_points) + ")");

  check_time(deadline, "planes");

  // Heightmap, edges, polylines, regular lines: the inferred vertical planes (paper section 3.2).
  const Heightmap heightmap = rasterise_tin(points, params.heightmap);
  std::vector<Polygon2> outline = input.footprint.polygons;
  if (!input.footprint_given) {
    outline.clear();
    for (const Polygon2& p : infer_outline(heightmap, points, params.polylines.max_hausdorff))
      outline.push_back(fit_outline_to_points(regularise_outline(p, params.regularise.angle_threshold), points));
    if (outline.empty() && !input.footprint.polygons.empty()) {
      // Too small for the heightmap to hold an outline (under infer_outline's 2 m2): the convex
      // hull of the points (building_from_cloud), regularised like an inferred outline.
      outline.push_back(
          regularise_outline(input.footprint.polygons.front(), params.regularise.angle_threshold));
      const std::string note = "outline: convex hull of the points";
      if (report.note.find(note) == std::string::npos) report.note += (report.note.empty() ? "" : "; ") + note;
    }
    if (outline.empty()) throw ReconstructionError("walls: no outline could be inferred from the points");
    outline.resize(1);  // the largest part only: other parts are not modelled (README, known limits)
  }
  RegularisationResult lines;
  if (!footprint_walls_only) {
    const std::vector<Point2> edges = detect_edges(heightmap, params.heightmap);
    const std::vector<Polyline2> polylines = extract_polylines(edges, params.polylines);
    lines = regularise(polylines, &outline, params.regularise);
    if (debug) {
      write_heightmap_png(heightmap, debug_path(params, input.id, "heightmap.png"));
      write_edges_png(heightmap, edges, debug_path(params, input.id, "edges.png"));
      write_polylines_obj(debug_path(params, input.id, "polylines.obj"), polylines, input.ground_z);
      write_segments_obj(debug_path(params, input.id, "regularised.obj"), lines.segments, input.ground_z);
    }
  }
  WallParams wall_params = params.walls;
  if (wall_params.mode == WallMode::automatic) wall_params.mode = WallMode::footprint;
  const std::vector<VerticalPlane> walls =
      infer_walls(lines, &outline, footprint_walls_only ? std::vector<std::pair<Point2, Point2>>{} : detected_walls,
                  wall_params);
  report.walls = walls.size();
  check_time(deadline, "walls");
  if (debug) write_walls_obj(debug_path(params, input.id, "walls.obj"), walls, input.ground_z, input.ground_z + 20.0);

  // Face hypothesis and selection (paper section 3.3).
  const CandidateFaces candidates =
      generate_candidates(points, roofs, walls, outline, input.ground_z, input.ground_measured, params.hypothesis);
  report.candidate_faces = candidates.faces.size();
  check_time(deadline, "hypothesis");
  if (debug) write_candidates_obj(debug_path(params, input.id, "candidates.obj"), candidates);
  SelectionParams selection_params = params.selection;
  const double left = std::chrono::duration<double>(deadline - Clock::now()).count();
  selection_params.time_limit = std::max(0.1, std::min(selection_params.time_limit, left));
  SelectionResult selection = solve_selection(candidates.problem, selection_params);
  if (selection.status == SelectionStatus::infeasible && selection_params.use_face_prior) {
    // The face prior is a preference of the paper's, not a necessity: retry without it.
    selection_params.use_face_prior = false;
    selection = solve_selection(candidates.problem, selection_params);
  }
  if (selection.status != SelectionStatus::optimal && selection.status != SelectionStatus::feasible)
    throw ReconstructionError(std::string(selection.status == SelectionStatus::infeasible
                                              ? "selection: infeasible"
                                              : "selection: no solution within the limits") +
                              " (" + std::to_string(selection.variables) + " variables): " + selection.message);

  BuildingModel model;
  model.id = input.id;
  model.origin = input.origin;
  model.mesh = assemble_model(candidates, selection.selected, params.assemble, &model.surfaces);
  return model;
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

}  // namespace

BuildingInput building_from_cloud(const BuildingId& id, const std::vector<Point3>& world_points,
                                  std::optional<double> ground_z) {
  BuildingInput input;
  input.id = id;
  input.footprint.id = id;
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

BuildingResult reconstruct_building(const BuildingInput& input, const ReconstructionParams& params) {
  const auto start = Clock::now();
  BuildingResult result;
  BuildingReport& r = result.report;
  r.id = input.id;
  r.points = input.points.size();
  r.ground_points = input.ground_points.size();
  r.ground_z = input.ground_z + input.origin.z;
  r.ground_method = input.ground_method;
  r.note = input.footprint.note;
  if (!input.points.empty()) {
    try {
      r.roof_z = lod1_heights(input, params.lod1).roof_z + input.origin.z;
    } catch (const Error&) {
      // Reported by the LoD1 rung if it comes to that.
    }
  }
  if (input.footprint.polygons.empty()) {
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
    for (const Rung& rung : rungs) {
      if (rung.level == requested) started = true;
      if (!started) continue;
      try {
        // The full rung may use 60% of the building's time, the footprint-walls rung the rest.
        const double share = rung.level == ModelLevel::lod22 ? kFullRungShare : 1.0;
        const auto deadline = start + std::chrono::duration_cast<Clock::duration>(
                                          std::chrono::duration<double>(share * params.time_limit));
        BuildingModel model = rung.level == ModelLevel::lod12
                                  ? lod1_rung(input, params, r)
                                  : lod2_rung(input, params, rung.footprint_walls_only, deadline, r);
        // Closed, 2-manifold, outward, planar faces, no self-intersection: anything less is a bug
        // of a rung, never a result. The LoD1 block is the last resort: there only the topology is
        // required, because a repaired multipolygon can have parts that touch at a point (separate
        // shells, each valid, that the self-intersection test reports as touching).
        if (rung.level == ModelLevel::lod12) {
          const MeshCheck check = check_mesh(model.mesh);
          if (!check.valid()) throw ReconstructionError("model: LoD1 block is not a valid solid");
        } else {
          const MeshValidity validity = check_validity(model.mesh);
          if (!validity.valid()) {
            if (!params.debug_dir.empty()) {
              ModelWriteOptions local;
              local.local_coordinates = true;
              write_model(debug_path(params, input.id,
                                     std::string("rejected_") +
                                         (rung.footprint_walls_only ? "footprint_walls" : "lod22") + ".obj"),
                          model, local);
            }
            throw ReconstructionError("model: not a valid solid: " + validity.problem);
          }
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
    if (result.model) r.rmse = rmse(result.model->mesh, input.points);
    if (r.status == BuildingStatus::ok) r.stage.clear(), r.reason.clear();
  }

  r.seconds = seconds_since(start);
  return result;
}

namespace {

bool is_point_cloud_file(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".las" || ext == ".laz" || ext == ".ply";
}

// Files as given, folders expanded to their LAS/LAZ/PLY files sorted by name (deterministic).
std::vector<std::string> expand_inputs(const std::vector<std::string>& inputs) {
  std::vector<std::string> files;
  for (const std::string& in : inputs) {
    std::error_code ec;
    if (fs::is_directory(in, ec)) {
      std::vector<std::string> found;
      for (const auto& entry : fs::directory_iterator(in, ec))
        if (entry.is_regular_file() && is_point_cloud_file(entry.path())) found.push_back(entry.path().string());
      if (ec) throw IoError("input: cannot list folder " + in + ": " + ec.message());
      if (found.empty()) throw IoError("input: folder " + in + " holds no .las, .laz or .ply file");
      std::sort(found.begin(), found.end());
      files.insert(files.end(), found.begin(), found.end());
    } else if (fs::exists(in, ec)) {
      files.push_back(in);
    } else {
      throw IoError("input: cannot open " + in + ": no such file or folder");
    }
  }
  if (files.empty()) throw ConfigError("input: no point-cloud file given");
  return files;
}

std::vector<Point3> read_all_points(const std::string& path) {
  PointCloud cloud = read_point_cloud(path, kFieldXyz);
  return std::move(cloud.points);
}

// Streams every tile that overlaps the footprints into the cropper.
void crop_tiles(const std::vector<std::string>& files, const std::vector<Footprint>& footprints,
                const CropParams& params, unsigned threads, Cropper& cropper) {
  Box2 extent;
  for (const Footprint& f : footprints)
    for (const Polygon2& p : f.polygons)
      for (const Point2& v : p.outer) extent.add(v);
  // The cropper's wide ground buffer, and a metre to spare.
  const double margin = params.ground_buffer * params.wide_buffer_factor + 1.0;
  extent.min = {extent.min.x - margin, extent.min.y - margin};
  extent.max = {extent.max.x + margin, extent.max.y + margin};
  for (const std::string& file : files) {
    // Cropping runs between reconstructions, so every thread can decode LAZ chunks meanwhile.
    auto reader = open_point_cloud(file, kFieldClassification, threads);
    const PointCloudInfo& info = reader->info();
    if (!info.bounds.empty()) {
      Box2 tile;
      tile.add({info.bounds.min.x, info.bounds.min.y});
      tile.add({info.bounds.max.x, info.bounds.max.y});
      if (!tile.intersects(extent)) {
        log_info("crop: " + file + " does not overlap the footprints, skipped");
        continue;
      }
    }
    PointCloud chunk;
    std::uint64_t n = 0;
    for (;;) {
      chunk.clear();
      const std::size_t got = reader->read(chunk, 1 << 20);
      if (got == 0) break;
      n += got;
      cropper.add(chunk);
    }
    log_info("crop: " + file + ": " + std::to_string(n) + " points streamed");
  }
}

std::vector<std::pair<std::string, AttributeValue>> cityjson_attributes(const BuildingReport& r, bool timings) {
  std::vector<std::pair<std::string, AttributeValue>> a = {
      {"status", std::string(to_string(r.status))},
      {"level", std::string(to_string(r.level))},
      {"reason", r.reason.empty() ? AttributeValue{} : AttributeValue{r.reason}},
      {"note", r.note.empty() ? AttributeValue{} : AttributeValue{r.note}},
      {"ground_z", r.ground_z},
      {"ground_method", r.ground_method},
      {"roof_z_p70", r.roof_z},
      {"points", static_cast<std::int64_t>(r.points)},
      {"planes", static_cast<std::int64_t>(r.planes)},
      {"faces", static_cast<std::int64_t>(r.faces)},
      {"rmse", r.rmse >= 0 ? AttributeValue{r.rmse} : AttributeValue{}},
  };
  if (timings) a.emplace_back("seconds", r.seconds);
  return a;
}

// Writes each building's outputs as soon as it and every building before it are done, so output
// order (and bytes) never depend on the thread count, and finished work is on disk early.
class OrderedWriter {
 public:
  OrderedWriter(const BatchOptions& options, std::size_t total, const Point3& translate, const std::string& crs)
      : options_(options), results_(total), ready_(total, false) {
    if (options.per_building_files) fs::create_directories(fs::path(options.output_dir) / "models");
    if (options.cityjson_seq)
      seq_ = std::make_unique<CityJsonSeqWriter>((fs::path(options.output_dir) / "buildings.city.jsonl").string(),
                                                 CityJsonOptions{crs, 0.001, ""}, translate);
  }

  void submit(std::size_t index, BuildingResult result) {
    std::lock_guard<std::mutex> lock(mutex_);
    results_[index] = std::move(result);
    ready_[index] = true;
    while (next_ < results_.size() && ready_[next_]) write(results_[next_++]);
  }

  void finish(const std::string& crs) {
    if (seq_) seq_->close();
    const fs::path out(options_.output_dir);
    if (options_.cityjson) write_cityjson((out / "buildings.city.json").string(), objects_, {crs, 0.001, ""});
    if (options_.merged_file) {
      std::vector<BuildingModel> models;
      for (CityObject& o : objects_) models.push_back(o.model);
      write_models((out / ("models" + mesh_extension(options_.format))).string(), models,
                   {options_.format, options_.local_coordinates});
    }
  }

  std::vector<BuildingReport> reports() const {
    std::vector<BuildingReport> rows;
    for (const BuildingResult& r : results_) rows.push_back(r.report);
    return rows;
  }

 private:
  void write(BuildingResult& result) {
    if (!result.model) return;
    if (options_.per_building_files) {
      const fs::path file = fs::path(options_.output_dir) / "models" / model_file_name(result.model->id, options_.format);
      write_model(file.string(), *result.model, {options_.format, options_.local_coordinates});
    }
    CityObject object{std::move(*result.model), cityjson_lod(result.report.level),
                      cityjson_attributes(result.report, options_.timings_in_cityjson)};
    result.model.reset();
    if (seq_) seq_->add(object);
    if (options_.cityjson || options_.merged_file) objects_.push_back(std::move(object));
  }

  const BatchOptions& options_;
  std::mutex mutex_;
  std::vector<BuildingResult> results_;
  std::vector<bool> ready_;
  std::size_t next_ = 0;
  std::unique_ptr<CityJsonSeqWriter> seq_;
  std::vector<CityObject> objects_;
};

void print_progress(std::size_t done, std::size_t total, Clock::time_point start) {
  const double elapsed = seconds_since(start);
  const double rate = elapsed > 0 ? done / elapsed : 0.0;
  const double left = rate > 0 ? (total - done) / rate : 0.0;
  std::fprintf(stderr, "\rbuildings %zu/%zu  %.1f/s  %.0f s left   ", done, total, rate, left);
  if (done == total) std::fputc('\n', stderr);
  std::fflush(stderr);
}

}  // namespace

namespace {

// Footprints grouped into square blocks of `extent` metres by their bounding-box centres, blocks in
// row-major order, footprints in input order within a block. extent <= 0: one block.
std::vector<std::vector<std::size_t>> spatial_blocks(const std::vector<Footprint>& footprints, double extent) {
  std::map<std::pair<long long, long long>, std::vector<std::size_t>> cells;
  for (std::size_t i = 0; i < footprints.size(); ++i) {
    Box2 box;
    for (const Polygon2& p : footprints[i].polygons)
      for (const Point2& v : p.outer) box.add(v);
    std::pair<long long, long long> key{0, 0};
    if (extent > 0 && !box.empty())
      key = {static_cast<long long>(std::floor((box.min.y + box.max.y) / 2 / extent)),
             static_cast<long long>(std::floor((box.min.x + box.max.x) / 2 / extent))};
    cells[key].push_back(i);
  }
  std::vector<std::vector<std::size_t>> blocks;
  for (auto& [key, indices] : cells) blocks.push_back(std::move(indices));
  return blocks;
}

// The footprints a block must crop with: its own, and every other footprint that can reach into
// their ground buffers (ground points inside any footprint never count as ground), so that a
// building's input does not depend on how footprints are blocked.
std::vector<std::size_t> with_neighbours(const std::vector<Footprint>& footprints, const std::vector<std::size_t>& block,
                                         double reach) {
  Box2 extent;
  for (std::size_t i : block)
    for (const Polygon2& p : footprints[i].polygons)
      for (const Point2& v : p.outer) extent.add(v);
  extent.min = {extent.min.x - reach, extent.min.y - reach};
  extent.max = {extent.max.x + reach, extent.max.y + reach};
  std::vector<bool> in_block(footprints.size(), false);
  for (std::size_t i : block) in_block[i] = true;
  std::vector<std::size_t> result = block;
  for (std::size_t i = 0; i < footprints.size(); ++i) {
    if (in_block[i]) continue;
    Box2 box;
    for (const Polygon2& p : footprints[i].polygons)
      for (const Point2& v : p.outer) box.add(v);
    if (!box.empty() && box.intersects(extent)) result.push_back(i);
  }
  return result;
}

}  // namespace

BatchSummary run_batch(const BatchOptions& options) {
  const auto start = Clock::now();
  options.reconstruction.validate();
  options.crop.validate();
  if (options.threads < 1) throw ConfigError("batch: threads must be at least 1");
  const std::vector<std::string> files = expand_inputs(options.point_clouds);
  log_info("parameters:\n" + parameters_text(options.reconstruction));
  fs::create_directories(options.output_dir);
  detail::Journal journal((fs::path(options.output_dir) / "resume.journal").string(),
                          detail::batch_fingerprint(options, files), options.resume);

  // What to reconstruct: the footprints (cropped from the tiles block by block), or one building
  // per single-building cloud (read when its turn comes).
  FootprintSet set;
  std::vector<BuildingReport> skipped_rows;
  std::string crs;
  Box2 extent;
  if (!options.footprints.empty()) {
    set = read_footprints(options.footprints, options.footprint);
    crs = set.srs.rfind("EPSG:", 0) == 0 ? set.srs : "";
    for (const SkippedFootprint& s : set.skipped) {
      BuildingReport row;
      row.id = s.id;
      row.status = BuildingStatus::skipped;
      row.stage = "footprints";
      row.reason = s.reason;
      skipped_rows.push_back(row);
    }
    for (const Footprint& f : set.footprints)
      for (const Polygon2& p : f.polygons)
        for (const Point2& v : p.outer) extent.add(v);
  }
  const std::size_t total = options.footprints.empty() ? files.size() : set.footprints.size();
  // The CityJSONSeq transform must be known before the first building: the footprints' corner, or
  // for clouds their first header's corner.
  Point3 translate{0, 0, 0};
  if (options.footprints.empty() && !files.empty()) {
    const PointCloudInfo info = read_point_cloud_info(files.front());
    if (!info.bounds.empty()) extent.add({info.bounds.min.x, info.bounds.min.y});
  }
  if (!extent.empty()) translate = {std::floor(extent.min.x), std::floor(extent.min.y), 0.0};
  OrderedWriter writer(options, total, translate, crs);

  // Reconstructs buildings `indices` (global, input order) in parallel; make_input(k) gives the
  // input of indices[k] and is called by the worker that reconstructs it.
  std::atomic<std::size_t> done{0};
  auto reconstruct_all = [&](const std::vector<std::size_t>& indices,
                             const std::function<BuildingInput(std::size_t)>& make_input) {
    std::atomic<std::size_t> next{0};
    std::exception_ptr failure;
    std::mutex failure_mutex;
    auto worker = [&]() {
      for (;;) {
        const std::size_t k = next++;
        if (k >= indices.size()) return;
        {
          std::lock_guard<std::mutex> lock(failure_mutex);
          if (failure) return;
        }
        try {
          BuildingResult result;
          const BuildingId& id = options.footprints.empty() ? fs::path(files[indices[k]]).stem().string()
                                                            : set.footprints[indices[k]].id;
          if (const BuildingResult* finished = journal.find(id)) {
            result = *finished;
          } else {
            result = reconstruct_building(make_input(k), options.reconstruction);
            journal.append(result);
          }
          writer.submit(indices[k], std::move(result));
        } catch (...) {
          // Only input and output errors reach here (reconstruct_building never throws for a bad
          // building): the run cannot go on.
          std::lock_guard<std::mutex> lock(failure_mutex);
          if (!failure) failure = std::current_exception();
          return;
        }
        const std::size_t d = ++done;
        if (options.progress) print_progress(d, total, start);
      }
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < options.threads; ++t) pool.emplace_back(worker);
    worker();
    for (std::thread& t : pool) t.join();
    if (failure) std::rethrow_exception(failure);
  };

  if (options.footprints.empty()) {
    std::vector<std::size_t> indices(files.size());
    std::iota(indices.begin(), indices.end(), 0);
    reconstruct_all(indices, [&](std::size_t k) {
      return building_from_cloud(fs::path(files[k]).stem().string(), read_all_points(files[k]), options.ground_z);
    });
  } else {
    const double reach = options.crop.ground_buffer * options.crop.wide_buffer_factor + 1.0;
    for (const std::vector<std::size_t>& block : spatial_blocks(set.footprints, options.block_size)) {
      const bool all_done = std::all_of(block.begin(), block.end(),
                                        [&](std::size_t i) { return journal.find(set.footprints[i].id) != nullptr; });
      std::vector<BuildingInput> inputs;
      if (!all_done) {
        // Crop with the neighbours too; keep the block's own inputs (the first block.size()).
        const std::vector<std::size_t> members = with_neighbours(set.footprints, block, reach);
        std::vector<Footprint> footprints;
        for (std::size_t i : members) footprints.push_back(set.footprints[i]);
        Cropper cropper(footprints, options.crop);
        crop_tiles(files, footprints, options.crop, static_cast<unsigned>(options.threads), cropper);
        inputs = cropper.finish();
        inputs.resize(block.size());
        for (BuildingInput& in : inputs)
          if (in.footprint.ground_z) {
            // The footprint source knows the floor: it overrides the ground points.
            in.ground_z = *in.footprint.ground_z - in.origin.z;
            in.ground_method = "footprint attribute";
            in.ground_measured = true;
          }
      }
      reconstruct_all(block, [&](std::size_t k) { return std::move(inputs[k]); });
    }
  }
  writer.finish(crs);

  std::vector<BuildingReport> rows = writer.reports();
  rows.insert(rows.end(), skipped_rows.begin(), skipped_rows.end());
  BatchSummary summary;
  summary.buildings = rows.size();
  for (const BuildingReport& r : rows) {
    summary.ok += r.status == BuildingStatus::ok;
    summary.fallback += r.status == BuildingStatus::fallback;
    summary.skipped += r.status == BuildingStatus::skipped;
    summary.failed += r.status == BuildingStatus::failed;
  }
  summary.seconds = seconds_since(start);
  summary.report_path = (fs::path(options.output_dir) / "report.csv").string();
  detail::write_report_csv(summary.report_path, rows);
  detail::write_report_json((fs::path(options.output_dir) / "report.json").string(), rows, summary);
  return summary;
}

}  // namespace city3d
