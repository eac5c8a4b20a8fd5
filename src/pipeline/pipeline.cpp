// The pipeline of one building, from points to model (reconstruct_building): the input made ready,
// the report's first figures, the fallback ladder (LoD2 -> LoD2 with footprint walls -> LoD1 block;
// each rung in lod2.hpp, the rebuilds of a LoD2 model in rebuild.hpp) and the levels of detail made
// from the model the ladder gives (levels.hpp). The batch job around it is in src/batch/.
#include "city3d/pipeline.hpp"

#include <chrono>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <optional>
#include <sstream>
#include <string>
#include <unordered_set>

#include "city3d/debug_output.hpp"
#include "city3d/error.hpp"
#include "city3d/evaluation.hpp"
#include "city3d/rings.hpp"
#include "city3d/stage_profile.hpp"
#include "pipeline/levels.hpp"
#include "pipeline/lod2.hpp"
#include "pipeline/rebuild.hpp"

namespace city3d {
namespace {

using detail::Clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The input as the stages take it: a footprint of very many vertices is simplified first (a work
// limit: walls, arrangement and program grow with its edges), then prepared (prepare_footprint);
// `note` says what was done. The copy of the input is made only then.
std::optional<BuildingInput> footprint_ready_input(const BuildingInput& given,
                                                   const ReconstructionParams& params, std::string& note) {
  if (!given.footprint_given) return std::nullopt;
  std::size_t vertices = 0;
  for (const Polygon2& p : given.footprint.polygons) {
    vertices += p.outer.size();
    for (const Ring2& h : p.holes) vertices += h.size();
  }
  std::optional<BuildingInput> ready;
  if (vertices > params.max_footprint_vertices) {
    SimplifiedFootprint s = simplify_footprint(given.footprint.polygons, params.max_footprint_vertices);
    ready = given;
    ready->footprint.polygons = std::move(s.polygons);
    std::ostringstream text;
    text << "footprint: " << s.vertices_before << " vertices simplified to " << s.vertices_after
         << " (tolerance " << s.tolerance << " m; max_footprint_vertices " << params.max_footprint_vertices
         << ")";
    note = text.str();
  }
  std::vector<Polygon2> polygons = (ready ? *ready : given).footprint.polygons;
  const FootprintPreparation prepared = prepare_footprint(polygons, params);
  if (prepared.tidied.merged > 0 || prepared.tidied.spikes > 0 || !prepared.opened.empty()) {
    if (!ready) ready = given;
    ready->footprint.polygons = std::move(polygons);
  }
  const std::string text = prepared.note(params, given.origin);
  if (!text.empty()) note += (note.empty() ? "" : "; ") + text;
  return ready;
}

// The input with its points thinned to one per cell of 1 / sqrt(max_point_density) in plan (and per
// thinning_height_cells cells in height) when they are denser than that over the footprint (of
// `footprint_area`; a cloud: over its box in plan), and `note` says so; nothing otherwise (every airborne
// survey).
std::optional<BuildingInput> thinned_input(const BuildingInput& input, const ReconstructionParams& params,
                                           double footprint_area, std::string& note) {
  if (input.points.empty()) return std::nullopt;
  double area = 0.0;
  if (input.footprint_given) {
    area = footprint_area;
  } else {
    Box2 box;
    for (const Point3& p : input.points) box.add({p.x, p.y});
    area = (box.max.x - box.min.x) * (box.max.y - box.min.y);
  }
  if (!(area > 0.0) || static_cast<double>(input.points.size()) <= params.max_point_density * area)
    return std::nullopt;
  const double cell = 1.0 / std::sqrt(params.max_point_density);
  std::unordered_set<std::uint64_t> taken;  // 21 bits per axis: 100 km at 5 cm
  std::optional<BuildingInput> thinned = input;
  thinned->points.clear();
  for (const Point3& p : input.points) {
    const auto bits = [cell](double v) {
      return static_cast<std::uint64_t>(std::llround(std::floor(v / cell))) & 0x1FFFFF;
    };
    // One point per cell in plan and per thinning_height_cells cells in height.
    if (taken.insert(bits(p.x) | bits(p.y) << 21 | bits(p.z / params.thinning_height_cells) << 42).second)
      thinned->points.push_back(p);
  }
  std::ostringstream text;
  text << "points thinned from " << input.points.size() << " to " << thinned->points.size() << " ("
       << std::lround(static_cast<double>(input.points.size()) / area)
       << " per m2, more than max_point_density " << params.max_point_density << ": one per " << cell
       << " m cell in plan)";
  note = text.str();
  return thinned;
}

// The report's figures of the input, before any rung: its points, floor and notes, the heights of its
// points (3DBAG's b3_h_*) and the LoD1 roof height.
BuildingReport first_report(const BuildingInput& input, const ReconstructionParams& params,
                            const std::string& footprint_note, double footprint_area) {
  BuildingReport r;
  r.id = input.id;
  r.points = input.points.size();
  r.ground_points = input.ground_heights.size();
  r.ground_z = input.ground_z + input.origin.z;
  r.ground_method = input.ground_method;
  r.note = input.footprint.note;
  if (!footprint_note.empty()) add_note(r, footprint_note);
  const StageTimer stage(Stage::describe);
  detail::describe_points(input, params, footprint_area, r);
  if (!input.points.empty()) {
    try {
      r.roof_z = lod1_heights(input, params.lod1).roof_z + input.origin.z;
    } catch (const Error&) {
      // Reported by the LoD1 rung if it comes to that.
    }
  }
  return r;
}

// Whether there is nothing to reconstruct; if so the report says why (skipped).
bool nothing_to_reconstruct(const BuildingInput& input, BuildingReport& r) {
  if (input.points.empty() && !input.footprint_given) {
    // A single-building cloud without points has no outline either: say what is really missing.
    r.stage = "input";
    r.reason = "the point cloud has no points";
  } else if (input.footprint.polygons.empty()) {
    r.stage = "crop";
    r.reason = "footprint has no usable polygon";
  } else if (input.points.empty()) {
    r.stage = "crop";
    r.reason = "no building points inside the footprint";
  } else {
    return false;
  }
  r.status = BuildingStatus::skipped;
  return true;
}

// The report's stage of an error that ended a rung: the stage of a ReconstructionError. The stages do no
// file IO, so an IoError is the debug trace's (--debug), and a ConfigError is a parameter the building's
// stages cannot work with.
const char* failed_stage(const Error& e) {
  if (const auto* failure = dynamic_cast<const ReconstructionError*>(&e)) return stage_name(failure->stage());
  if (dynamic_cast<const IoError*>(&e)) return "debug";
  if (dynamic_cast<const ConfigError*>(&e)) return "parameters";
  return "reconstruction";
}

// A rung of the fallback ladder.
struct Rung {
  ModelLevel level;
  bool footprint_walls_only;
};

// One rung's model, valid as written. A LoD2 model that leaves points unexplained or carries surface
// no point supports is rebuilt (explain_more), which measures it: `lod2_fit`. Throws Error when the
// rung gives no model.
BuildingModel rung_model(const BuildingInput& input, const ReconstructionParams& params, const Rung& rung,
                         Clock::time_point deadline, DebugTrace* trace, BuildingReport& r,
                         std::optional<ModelFit>& lod2_fit) {
  using namespace detail;
  if (rung.level == ModelLevel::lod12)
    return checked_model(params, rung.level, false, lod1_rung(input, params, r), trace, r);
  Lod2Rung built;
  built.level = rung.level;
  built.footprint_walls_only = rung.footprint_walls_only;
  built.deadline = deadline;
  built.before_hypothesis = r;
  built.hypothesis = lod2_hypothesis(input, params, {rung.footprint_walls_only}, deadline, trace, r);
  built.before_selection = r;
  built.selected = lod2_model(input, built.hypothesis, params, deadline, trace, r, &built.without_prior);
  BuildingModel model =
      checked_model(params, rung.level, rung.footprint_walls_only, built.selected, trace, r);
  lod2_fit = explain_more(input, params, built, r, model);
  return model;
}

// The fallback ladder: full LoD2 -> LoD2 with footprint walls only -> LoD1 block, from the level
// asked for down. The first rung that gives a closed, 2-manifold, outward model wins; the report keeps
// the first failure. With --time-limit, the full rung may use full_rung_time_share of the building's
// time, the footprint-walls rung the rest.
std::optional<BuildingModel> walk_ladder(const BuildingInput& input, const ReconstructionParams& params,
                                         Clock::time_point start, BuildingReport& r,
                                         std::optional<ModelFit>& lod2_fit) {
  std::optional<DebugTrace> trace;  // with --debug: what each rung's stages leave, written as the rung ends
  if (!params.debug_dir.empty()) {
    trace.emplace();
    trace->dir = params.debug_dir;
    trace->id = input.id;
    trace->ground_z = input.ground_z;
    trace->points = &input.points;
  }
  DebugTrace* const tracing = trace ? &*trace : nullptr;
  const Rung rungs[] = {{ModelLevel::lod22, false}, {ModelLevel::lod22_footprint_walls, true}, {ModelLevel::lod12, false}};
  const ModelLevel requested = params.max_level == ModelLevel::none ? ModelLevel::lod22 : params.max_level;
  bool started = false;
  for (const Rung& rung : rungs) {
    if (rung.level == requested) started = true;
    if (!started) continue;
    try {
      const double share = rung.level == ModelLevel::lod22 ? params.full_rung_time_share : 1.0;
      const auto deadline = params.time_limit > 0
                                ? start + std::chrono::duration_cast<Clock::duration>(
                                              std::chrono::duration<double>(share * params.time_limit))
                                : Clock::time_point::max();
      BuildingModel model = rung_model(input, params, rung, deadline, tracing, r, lod2_fit);
      if (trace) write_debug_trace(*trace);
      r.level = rung.level;
      r.status = rung.level == requested ? BuildingStatus::ok : BuildingStatus::fallback;
      r.faces = model.mesh.faces.size();
      r.valid = true;
      return model;
    } catch (const Error& e) {
      if (r.reason.empty()) {
        r.reason = e.what();
        r.stage = failed_stage(e);
      }
      try {
        if (trace) write_debug_trace(*trace);  // what the stages before the failure left
      } catch (const Error& w) {
        add_note(r, w.what());
      }
    }
  }
  r.status = BuildingStatus::failed;
  return std::nullopt;
}

}  // namespace

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

FootprintPreparation prepare_footprint(std::vector<Polygon2>& polygons, const ReconstructionParams& params) {
  FootprintPreparation prepared;
  prepared.tidied = tidy_footprint(polygons, 2 * params.validity.snap_tolerance, params.footprint_clearance);
  Point2 unopened{std::nan(""), std::nan("")};
  prepared.opened = open_pinches(polygons, params.footprint_clearance, &unopened);
  if (!std::isnan(unopened.x)) prepared.unopened = unopened;
  return prepared;
}

std::string FootprintPreparation::note(const ReconstructionParams& params, const Point3& origin) const {
  std::vector<std::string> done;
  if (tidied.merged > 0) {
    std::ostringstream merged;
    merged << tidied.merged << (tidied.merged == 1 ? " vertex" : " vertices") << " within "
           << 2 * params.validity.snap_tolerance << " m of the one before dropped";
    done.push_back(merged.str());
  }
  if (tidied.spikes > 0) {
    std::ostringstream spikes;
    spikes << tidied.spikes << (tidied.spikes == 1 ? " spike" : " spikes") << " narrower than "
           << params.footprint_clearance << " m cut off";
    done.push_back(spikes.str());
  }
  std::ostringstream place;
  place << std::fixed << std::setprecision(3);
  if (!opened.empty()) {
    place << "its rings touched at " << opened.size() << (opened.size() == 1 ? " place" : " places")
          << " (at " << opened.front().x + origin.x << ", " << opened.front().y + origin.y << "), opened to "
          << std::defaultfloat << params.footprint_clearance << " m (footprint_clearance)";
    done.push_back(place.str());
  } else if (unopened) {
    place << "its rings touch at " << unopened->x + origin.x << ", " << unopened->y + origin.y
          << " and cannot be opened there";
    done.push_back(place.str());
  }
  if (done.empty()) return {};
  std::string text = "footprint: ";
  for (std::size_t k = 0; k < done.size(); ++k) text += (k ? ", " : "") + done[k];
  return text;
}

BuildingResult reconstruct_building(const BuildingInput& given, const ReconstructionParams& params) {
  const StageTimer building(Stage::other);
  const auto start = Clock::now();
  const double cpu_start = building_cpu_seconds();
  std::string footprint_note, simplify_failure;
  std::optional<BuildingInput> with_footprint_ready;
  try {
    with_footprint_ready = footprint_ready_input(given, params, footprint_note);
  } catch (const ReconstructionError& e) {  // a footprint no tolerance brings under the limit
    simplify_failure = std::string(e.what()) + " (--max-footprint-vertices)";
  }
  const BuildingInput& ready = with_footprint_ready ? *with_footprint_ready : given;
  const double footprint_area = polygons_area(ready.footprint.polygons);  // thinning keeps the footprint
  std::string thin_note;
  const std::optional<BuildingInput> thinned = thinned_input(ready, params, footprint_area, thin_note);
  const BuildingInput& input = thinned ? *thinned : ready;

  BuildingResult result;
  BuildingReport& r = result.report;
  r = first_report(input, params, footprint_note, footprint_area);
  if (!thin_note.empty()) add_note(r, thin_note);
  if (!simplify_failure.empty()) {
    r.status = BuildingStatus::skipped;
    r.stage = "footprint";
    r.reason = simplify_failure;
  } else if (!nothing_to_reconstruct(input, r)) {
    std::optional<ModelFit> lod2_fit;  // the LoD2 model's distances, as explain_more measured them
    result.model = walk_ladder(input, params, start, r, lod2_fit);
    if (result.model) {
      const StageTimer stage(Stage::lod1);
      detail::add_levels_of_detail(input, params, lod2_fit, result);
    }
    if (result.model) {
      const StageTimer stage(Stage::measure);
      r.rmse = r.lods.empty() ? rmse(result.model->mesh, input.points) : detail::highest_level_rmse(r);
    }
    if (r.status == BuildingStatus::ok) r.stage.clear(), r.reason.clear();
  }
  r.seconds = seconds_since(start);
  r.cpu_seconds = building_cpu_seconds() - cpu_start;
  return result;
}

}  // namespace city3d
