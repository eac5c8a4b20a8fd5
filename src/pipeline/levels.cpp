// The report's figures of a building and its levels of detail (levels.hpp).
#include "pipeline/levels.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <utility>

#include "city3d/error.hpp"
#include "city3d/evaluation.hpp"
#include "city3d/mesh_check.hpp"
#include "city3d/repair.hpp"
#include "city3d/stage_profile.hpp"
#include "city3d/surface_support.hpp"
#include "core/mesh_faces.hpp"

namespace city3d::detail {
namespace {

// Roof type of an LoD2.2 model as 3DBAG names them: every roof face within flat_angle of horizontal
// and all at one height (within level_gap): "horizontal"; horizontal at several heights: "multiple
// horizontal"; otherwise "slanted".
std::string roof_type_of(const BuildingModel& model, const RoofTypeParams& params) {
  const std::vector<SurfaceType> types = surface_types(model);
  std::vector<double> heights;
  bool slanted = false;
  for (std::size_t f = 0; f < model.mesh.faces.size(); ++f) {
    if (types[f] != SurfaceType::roof) continue;
    const auto& face = model.mesh.faces[f];
    const Vec n = newell_normal(model.mesh.vertices, face);
    double zsum = 0;
    for (std::uint32_t v : face) zsum += model.mesh.vertices[v].z;
    const double len = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
    if (!(len > 0)) continue;
    if (n.z / len < std::cos(params.flat_angle * kPi / 180.0)) slanted = true;
    heights.push_back(zsum / face.size());
  }
  if (heights.empty()) return "could not be detected";
  if (slanted) return "slanted";
  std::sort(heights.begin(), heights.end());
  for (std::size_t k = 1; k < heights.size(); ++k)
    if (heights[k] - heights[k - 1] > params.level_gap) return "multiple horizontal";
  return "horizontal";
}

// Whether two models are the same, exactly: vertices, faces, origin and surface types.
bool same_model(const BuildingModel& a, const BuildingModel& b) {
  return a.mesh.faces == b.mesh.faces && a.surfaces == b.surfaces && same_point(a.origin, b.origin) &&
         std::equal(a.mesh.vertices.begin(), a.mesh.vertices.end(), b.mesh.vertices.begin(), b.mesh.vertices.end(),
                    same_point);
}

// A level's blocks as make_lod13_blocks made them and as they will be written (rounded to the output
// grid, repaired), when the latter pass validation.
struct ValidBlocks {
  BuildingModel made;
  BuildingModel written;
};

std::optional<ValidBlocks> validated(BuildingModel blocks, const ReconstructionParams& params) {
  ValidBlocks b{blocks, std::move(blocks)};
  if (!validate_as_written(b.written, params.output_grid, params.validity).remaining.empty())
    return std::nullopt;
  return b;
}

// The blocks of a level (LoD1.2: an infinite step) whose blocks of `parts` are no valid solid, with
// no more than two walls over each other on a vertex's column: of the roof parts joined within
// lod1.join_distance (a sliver between two parts, `joined`), else of `parts` themselves (joining can
// fold a part that is itself a sliver); LoD1.3 then as one block, as LoD1.2 is; for a cloud, the
// floor of its LoD2.2 model `lod22` (its inferred outline, valid as the model is) extruded as the
// LoD1 rung's block is; at last the LoD1 rung's block (the footprint, or a cloud's convex hull,
// extruded). `how` says which, when coarser than asked.
std::optional<ValidBlocks> remade_blocks(const BuildingInput& input, const ReconstructionParams& params,
                                         const BuildingModel& lod22, const Lod13Parts& parts,
                                         const Lod13Parts& joined, double step, std::string& how) {
  for (const Lod13Parts* roof : {&joined, &parts})
    if (auto b = validated(make_lod13_blocks(*roof, input.ground_z, step, params.lod1.roof_percentile,
                                             params.lod1.min_height, true),
                           params))
      return b;
  if (std::isfinite(step)) {
    if (auto b = validated(make_lod13_blocks(parts, input.ground_z, std::numeric_limits<double>::infinity(),
                                             params.lod1.roof_percentile, params.lod1.min_height),
                           params)) {
      how = " as one block, as LoD1.2";
      return b;
    }
  }
  if (!input.footprint_given) {
    // The convex hull would add ground the building does not stand on (an L-shaped house's corner).
    std::vector<Polygon2> floor;
    const std::vector<SurfaceType> types = surface_types(lod22);
    for (std::size_t f = 0; f < lod22.mesh.faces.size(); ++f) {
      if (types[f] != SurfaceType::ground) continue;
      Polygon2& face = floor.emplace_back();
      for (std::uint32_t v : lod22.mesh.faces[f])
        face.outer.push_back({lod22.mesh.vertices[v].x, lod22.mesh.vertices[v].y});
    }
    try {
      const Lod1Heights heights = lod1_heights(input, params.lod1);
      BuildingModel block;
      block.id = input.id;
      block.origin = input.origin;
      block.mesh = extrude_polygons(floor, heights.floor_z, heights.roof_z, input.id);
      if (auto b = validated(std::move(block), params)) {
        how = " as the block of the LoD2.2 model's floor";
        return b;
      }
    } catch (const ReconstructionError&) {
      // A floor ring extrude_polygons cannot take: the convex hull's block below.
    }
  }
  if (auto b = validated(make_lod1_block(input, params.lod1), params)) {
    how = input.footprint_given ? " as the footprint's block" : " as the block of the points' convex hull";
    return b;
  }
  return std::nullopt;
}

}  // namespace

void describe_points(const BuildingInput& input, const ReconstructionParams& params, double footprint_area,
                     BuildingReport& r) {
  const double area = footprint_area;
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
  // Points that do not stand above the ground measured around the footprint (heights in another datum
  // than the ground's, a flattened cloud, a footprint of something at ground level): the blocks are
  // raised to lod1.min_height, and the report says why.
  const double ground = input.ground_z + input.origin.z;
  if (input.footprint_given && input.ground_measured && r.h_roof_70p < ground + params.lod1.min_height) {
    std::ostringstream note;
    note << "the building's points stand less than " << params.lod1.min_height << " m above its ground ("
         << params.lod1.roof_percentile << "th percentile " << r.h_roof_70p << " m, ground " << ground
         << " m, " << input.ground_method << ")";
    add_note(r, note.str());
  }
}

void add_levels_of_detail(const BuildingInput& input, const ReconstructionParams& params,
                          const std::optional<ModelFit>& lod2_fit, BuildingResult& result) {
  BuildingReport& r = result.report;
  const BuildingModel primary = *result.model;
  std::vector<LodModel> made;  // in order 1.2, 1.3, 2.2
  std::vector<std::string> real;
  const bool lod2 = r.level == ModelLevel::lod22 || r.level == ModelLevel::lod22_footprint_walls;
  // A building of one height level has the same blocks at LoD1.3 as at LoD1.2: they are validated
  // (and below measured) once.
  std::optional<std::pair<BuildingModel, BuildingModel>> derived;  // the last blocks, as made and as validated
  std::optional<Lod13Parts> roof_parts;                            // made once for both levels
  std::optional<Lod13Parts> joined_parts;  // the same, joined within lod1.join_distance, when needed
  const auto derive = [&](const char* lod, double step) {
    try {
      if (!roof_parts) roof_parts = lod13_parts(primary, input.points);
      BuildingModel blocks = make_lod13_blocks(*roof_parts, input.ground_z, step, params.lod1.roof_percentile,
                                               params.lod1.min_height);
      if (derived && same_model(blocks, derived->first)) {
        made.push_back({lod, derived->second});
        real.push_back(lod);
        return;
      }
      BuildingModel made_blocks = blocks;
      const WrittenValidity v = validate_as_written(blocks, params.output_grid, params.validity);
      if (!v.remaining.empty()) {
        if (!joined_parts) joined_parts = lod13_parts(primary, input.points, params.lod1.join_distance);
        std::string how;
        std::optional<ValidBlocks> remade =
            remade_blocks(input, params, primary, *roof_parts, *joined_parts, step, how);
        const std::string why = v.remaining.front().text();
        if (!remade) {
          add_note(r, std::string("LoD") + lod + " not made: not valid as written: " + why);
          return;
        }
        if (!how.empty()) {
          std::ostringstream text;
          text << "LoD" << lod << how << ": ";
          if (std::isfinite(step)) text << "at " << step << " m ";
          text << "its blocks are not valid as written: " << why;
          add_note(r, text.str());
        }
        made_blocks = std::move(remade->made);
        blocks = std::move(remade->written);
      }
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
    r.roof_type = roof_type_of(primary, params.roof_type);
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
  std::optional<std::pair<const BuildingModel*, ModelFit>> measured;  // the last level measured
  for (const LodModel& m : kept) {
    const double volume = signed_volume(m.model.mesh);
    if (!(lod2 && m.lod == "2.2" && lod2_fit) && !(measured && same_model(m.model, *measured->first)))
      measured.emplace(&m.model, [&] {
        const StageTimer stage(Stage::measure);
        return fit_of_points(m.model.mesh, input.points);
      }());
    const ModelFit fit = lod2 && m.lod == "2.2" && lod2_fit ? *lod2_fit : measured->second;
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

double highest_level_rmse(const BuildingReport& r) {
  const std::string highest = r.lods.substr(r.lods.rfind(',') == std::string::npos ? 0 : r.lods.rfind(',') + 1);
  return highest == "1.2" ? r.rmse_lod12 : highest == "1.3" ? r.rmse_lod13 : r.rmse_lod22;
}

}  // namespace city3d::detail
