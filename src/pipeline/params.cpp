// The parameters of the reconstruction: their check (ReconstructionParams::validate), their text
// (parameters_text, kept with a run so that a resume uses the same ones) and the set of levels of detail.
#include <cmath>
#include <sstream>

#include "city3d/error.hpp"
#include "city3d/pipeline.hpp"

namespace city3d {

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
  check([&] { outline.snap.validate(); });
  check([&] { outline.fit.validate(); });
  // The pipeline's own numbers, each named as parameters_text names it (NaN fails every comparison).
  const auto need = [&](bool ok, const char* what) {
    if (!ok) problems += (problems.empty() ? "" : "; ") + std::string(what);
  };
  const auto finite = [](double v) { return std::isfinite(v); };
  need(outline.min_region_area > 0 && finite(outline.min_region_area), "outline.min_region_area must be > 0 (m2)");
  need(outline.gap_spacings > 0 && finite(outline.gap_spacings), "outline.gap_spacings must be > 0");
  need(outline.wide_gap_spacings > 0 && finite(outline.wide_gap_spacings), "outline.wide_gap_spacings must be > 0");
  need(outline.min_extra_part_area >= 0 && finite(outline.min_extra_part_area),
       "outline.min_extra_part_area must be >= 0 (m2)");
  need(outline.part_gap >= 0 && finite(outline.part_gap), "outline.part_gap must be >= 0 (metres)");
  need(outline.extra_part_plane_share >= 0 && outline.extra_part_plane_share < 1,
       "outline.extra_part_plane_share must be in [0, 1)");
  need(outline.part_roof_share > 0 && outline.part_roof_share <= 1,
       "outline.part_roof_share must be in (0, 1]");
  need(rebuild.left_out_cell_share > 0 && rebuild.left_out_cell_share <= 1,
       "rebuild.left_out_cell_share must be in (0, 1]");
  need(rebuild.level_link_spacings > 0 && finite(rebuild.level_link_spacings),
       "rebuild.level_link_spacings must be > 0");
  need(rebuild.level_link_height >= 0 && finite(rebuild.level_link_height),
       "rebuild.level_link_height must be >= 0 (metres)");
  need(rebuild.min_left_out_width >= 0 && finite(rebuild.min_left_out_width),
       "rebuild.min_left_out_width must be >= 0 (metres)");
  need(rebuild.left_out_plane_divisor >= 1, "rebuild.left_out_plane_divisor must be >= 1");
  need(rebuild.left_out_plane_min_points >= 3, "rebuild.left_out_plane_min_points must be >= 3");
  need(rebuild.min_level_area >= 0 && finite(rebuild.min_level_area),
       "rebuild.min_level_area must be >= 0 (m2)");
  need(roof_type.flat_angle >= 0 && roof_type.flat_angle <= 90, "roof_type.flat_angle must be in [0, 90] (degrees)");
  need(roof_type.level_gap >= 0 && finite(roof_type.level_gap), "roof_type.level_gap must be >= 0 (metres)");
  need(full_rung_time_share > 0 && full_rung_time_share <= 1, "full_rung_time_share must be in (0, 1]");
  need(lods.any(), "lods: no level of detail asked for");
  need(lod13_step_height > 0, "lod13_step_height must be > 0 (metres)");
  need(output_grid >= 0 && finite(output_grid), "output_grid must be >= 0 (metres)");
  need(max_footprint_vertices >= 3, "max_footprint_vertices must be >= 3");
  need(footprint_clearance > 0 && footprint_clearance <= 1, "footprint_clearance must be in (0, 1] (metres)");
  need(max_point_density > 0 && finite(max_point_density), "max_point_density must be > 0 (points per m2)");
  need(thinning_height_cells >= 1 && finite(thinning_height_cells), "thinning_height_cells must be >= 1");
  need(retry_unexplained_share >= 0 && finite(retry_unexplained_share),
       "retry_unexplained_share must be a share >= 0 (1: never retry)");
  need(retry_unsupported_area >= 0, "retry_unsupported_area must be >= 0 (m2)");
  need(time_limit >= 0 && finite(time_limit), "time_limit must be >= 0 seconds (0: none)");
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
  put("planes.small_min_points", p.planes.small_min_points);
  put("planes.small_divisor", p.planes.small_divisor);
  put("planes.small_points_divisor", p.planes.small_points_divisor);
  put("planes.few_points_divisor", p.planes.few_points_divisor);
  put("planes.few_points_max_slope", p.planes.few_points_max_slope);
  put("planes.few_points_candidates", p.planes.few_points_candidates);
  put("planes.few_points_max_points", p.planes.few_points_max_points);
  put("heightmap.resolution", p.heightmap.resolution);
  put("heightmap.resolution_per_spacing", p.heightmap.resolution_per_spacing);
  put("heightmap.min_resolution", p.heightmap.min_resolution);
  put("heightmap.max_resolution", p.heightmap.max_resolution);
  put("heightmap.max_edge_length", p.heightmap.max_edge_length);
  put("heightmap.closing_size", p.heightmap.closing_size);
  put("heightmap.canny_low", p.heightmap.canny_low);
  put("heightmap.canny_high", p.heightmap.canny_high);
  put("heightmap.rim_pixels", p.heightmap.rim_pixels);
  put("polylines.max_hausdorff", p.polylines.max_hausdorff);
  put("polylines.max_cost", p.polylines.max_cost);
  put("polylines.resolution", p.polylines.resolution);
  put("polylines.link_pixels", p.polylines.link_pixels);
  put("polylines.min_polyline_length", p.polylines.min_polyline_length);
  put("polylines.relocate", p.polylines.relocate);
  put("polylines.relocate_pull", p.polylines.relocate_pull);
  put("polylines.corner_min_sine", p.polylines.corner_min_sine);
  put("polylines.relocate_rounds", p.polylines.relocate_rounds);
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
  put("walls.sample_step", p.walls.sample_step);
  put("walls.min_escaping_rays", p.walls.min_escaping_rays);
  put("walls.ray_fan_step", p.walls.ray_fan_step);
  put("walls.side_probe", p.walls.side_probe);
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
  put("hypothesis.support_cut_mixed", p.hypothesis.support_cut_mixed);
  put("hypothesis.support_cut_min_edge", p.hypothesis.support_cut_min_edge);
  put("hypothesis.support_cut_same_direction", p.hypothesis.support_cut_same_direction);
  put("hypothesis.start_descent_passes", p.hypothesis.start_descent_passes);
  put("hypothesis.surface_support.sample_spacing", p.hypothesis.surface_support.sample_spacing);
  put("hypothesis.surface_support.radius", p.hypothesis.surface_support.radius);
  put("hypothesis.surface_support.tolerance", p.hypothesis.surface_support.tolerance);
  put("hypothesis.surface_support.refine", p.hypothesis.surface_support.refine);
  put("selection.lambda_data", p.selection.lambda_data);
  put("selection.lambda_complexity", p.selection.lambda_complexity);
  put("selection.lambda_roof", p.selection.lambda_roof);
  put("selection.lambda_unsupported", p.selection.lambda_unsupported);
  put("selection.solver", p.selection.solver);
  put("selection.time_limit", p.selection.time_limit);
  put("selection.glpk_time_share", p.selection.glpk_time_share);
  put("selection.min_time_limit", p.selection.min_time_limit);
  put("selection.node_limit", p.selection.node_limit);
  put("selection.max_exact_variables", p.selection.max_exact_variables);
  put("selection.window_variables", p.selection.window_variables);
  put("selection.window_rounds", p.selection.window_rounds);
  put("selection.gomory_min_columns", p.selection.gomory_min_columns);
  put("selection.use_face_prior", p.selection.use_face_prior);
  put("selection.use_single_layer", p.selection.use_single_layer);
  put("assemble.collinear_tolerance", p.assemble.collinear_tolerance);
  put("assemble.planarity_tolerance", p.assemble.planarity_tolerance);
  put("assemble.merge_coplanar", p.assemble.merge_coplanar);
  put("lod1.roof_percentile", p.lod1.roof_percentile);
  put("lod1.min_height", p.lod1.min_height);
  put("lod1.join_distance", p.lod1.join_distance);
  put("outline.min_region_area", p.outline.min_region_area);
  put("outline.gap_spacings", p.outline.gap_spacings);
  put("outline.wide_gap_spacings", p.outline.wide_gap_spacings);
  put("outline.min_extra_part_area", p.outline.min_extra_part_area);
  put("outline.part_gap", p.outline.part_gap);
  put("outline.extra_part_plane_share", p.outline.extra_part_plane_share);
  put("outline.part_roof_share", p.outline.part_roof_share);
  put("outline.snap.dominant_window", p.outline.snap.dominant_window);
  put("outline.snap.min_corner_angle", p.outline.snap.min_corner_angle);
  put("outline.snap.max_shift", p.outline.snap.max_shift);
  put("outline.snap.max_area_change", p.outline.snap.max_area_change);
  put("outline.fit.band", p.outline.fit.band);
  put("outline.fit.end_margin", p.outline.fit.end_margin);
  put("outline.fit.min_points", p.outline.fit.min_points);
  put("outline.fit.outermost_share", p.outline.fit.outermost_share);
  put("outline.fit.max_shift", p.outline.fit.max_shift);
  put("outline.fit.max_area_change", p.outline.fit.max_area_change);
  put("rebuild.max_candidate_faces", p.rebuild.max_candidate_faces);
  put("rebuild.level_link_spacings", p.rebuild.level_link_spacings);
  put("rebuild.level_link_height", p.rebuild.level_link_height);
  put("rebuild.min_left_out_width", p.rebuild.min_left_out_width);
  put("rebuild.min_level_area", p.rebuild.min_level_area);
  put("rebuild.max_left_out_plane_points", p.rebuild.max_left_out_plane_points);
  put("rebuild.left_out_cell_share", p.rebuild.left_out_cell_share);
  put("rebuild.left_out_plane_divisor", p.rebuild.left_out_plane_divisor);
  put("rebuild.left_out_plane_min_points", p.rebuild.left_out_plane_min_points);
  put("roof_type.flat_angle", p.roof_type.flat_angle);
  put("roof_type.level_gap", p.roof_type.level_gap);
  put("output_grid", p.output_grid);
  put("lods", lod_set_text(p.lods));
  put("lod13_step_height", p.lod13_step_height);
  put("validity.snap_tolerance", p.validity.snap_tolerance);
  put("validity.planarity_distance", p.validity.planarity_distance);
  put("validity.planarity_normals", p.validity.planarity_normals);
  put("max_level", level_name(p.max_level));
  put("max_footprint_vertices", p.max_footprint_vertices);
  put("footprint_clearance", p.footprint_clearance);
  put("max_point_density", p.max_point_density);
  put("thinning_height_cells", p.thinning_height_cells);
  put("retry_unexplained_share", p.retry_unexplained_share);
  put("retry_unsupported_area", p.retry_unsupported_area);
  put("time_limit", p.time_limit);
  put("full_rung_time_share", p.full_rung_time_share);
  return s.str();
}

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

}  // namespace city3d
