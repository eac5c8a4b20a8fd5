// Face hypothesis (paper section 3.3): the candidate faces of one building and the selection problem
// over them; see hypothesis.hpp for the construction. This file calls the steps in order; each step is
// one file of src/hypothesis (listed in steps.hpp), and only arrangement.cpp uses CGAL.
#include "city3d/hypothesis.hpp"

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/log.hpp"
#include "hypothesis/steps.hpp"

namespace city3d {

void HypothesisParams::validate() const {
  // Each number with its lower bound, in the order the problems are listed; a strict bound is itself
  // refused. The negated comparison refuses NaN too.
  struct LowerBound {
    const char* name;
    double value;
    int bound;
    bool strict;
  };
  const LowerBound bounds[] = {
      {"support_distance", support_distance, 0, true},
      {"min_face_area", min_face_area, 0, false},
      {"line_support_margin", line_support_margin, 0, true},
      {"cell_support_margin", cell_support_margin, 0, false},
      {"min_support_points", static_cast<double>(min_support_points), 1, false},
      {"vertex_merge_tolerance", vertex_merge_tolerance, 0, true},
      {"parallel_tolerance", parallel_tolerance, 0, true},
      {"max_planes_per_cell", static_cast<double>(max_planes_per_cell), 1, false},
      {"floor_clearance", floor_clearance, 0, true},
      {"unmeasured_floor_drop", unmeasured_floor_drop, 0, false},
      {"min_part_area", min_part_area, 0, false},
      {"min_edge_length", min_edge_length, 0, false},
      {"min_cell_width", min_cell_width, 0, false},
      {"min_line_overlap", min_line_overlap, 0, false},
      {"line_merge_distance", line_merge_distance, 0, false},
      {"max_unsupported_area", max_unsupported_area, 0, false},
      {"support_cut_height", support_cut_height, 0, false},
      {"support_cut_rise", support_cut_rise, 0, false},
      {"support_cut_area", support_cut_area, 0, false},
      {"large_cell_count", static_cast<double>(large_cell_count), 0, false},
      {"max_planes_per_large_cell", static_cast<double>(max_planes_per_large_cell), 1, false},
      {"support_cut_min_edge", support_cut_min_edge, 0, false},
      {"start_descent_passes", static_cast<double>(start_descent_passes), 1, false},
  };
  std::vector<std::string> problems;
  for (const LowerBound& b : bounds)
    if (!(b.strict ? b.value > b.bound : b.value >= b.bound))
      problems.push_back(std::string(b.name) + (b.strict ? " must be > " : " must be >= ") +
                         std::to_string(b.bound));
  try {
    surface_support.validate();
  } catch (const ConfigError& e) {
    problems.push_back(e.what());
  }
  if (!(support_cut_mixed >= 0 && support_cut_mixed < 1)) problems.push_back("support_cut_mixed must be in [0, 1)");
  if (!(support_cut_same_direction >= 0 && support_cut_same_direction < 1))
    problems.push_back("support_cut_same_direction must be in [0, 1)");
  if (problems.empty()) return;
  std::string message = "hypothesis: invalid parameters: ";
  for (std::size_t i = 0; i < problems.size(); ++i) message += (i ? "; " : "") + problems[i];
  throw ConfigError(message);
}

CandidateFaces generate_candidates(const std::vector<Point3>& points,
                                   const std::vector<PlanarSegment>& roof_planes_in,
                                   const std::vector<VerticalPlane>& walls,
                                   const std::vector<Polygon2>& footprint_local, double ground_z,
                                   bool ground_measured, const HypothesisParams& params,
                                   const SelectionParams& energy, const std::function<void()>& checkpoint) {
  using namespace detail;
  params.validate();
  const auto check = [&checkpoint] {
    if (checkpoint) checkpoint();
  };

  std::vector<PlanarSegment> roofs;
  for (const auto& s : roof_planes_in)
    if (s.kind == PlanarSegment::Kind::roof && std::abs(s.plane.c) > 1e-6) roofs.push_back(s);
  if (roofs.empty())
    throw ReconstructionError(ReconstructionStage::hypothesis, "" + std::to_string(roof_planes_in.size()) +
                              " planes, need at least 1 roof plane");
  for (const auto& s : roofs)
    for (std::uint32_t i : s.points)
      if (i >= points.size())
        throw ReconstructionError(ReconstructionStage::hypothesis, "roof segment refers to point " + std::to_string(i) + " of " +
                                  std::to_string(points.size()));
  const std::size_t R = roofs.size();

  // 1. The input curves, 2. their arrangement, cleaned up.
  std::size_t line_count = 0;
  std::vector<InputCurve> curves = arrangement_curves(points, roofs, walls, footprint_local, params, line_count);
  const auto arrange = [&] {
    return drop_small_parts(contract_robustly(build_arrangement(curves, params.min_cell_width), params.min_edge_length),
                            params.min_part_area);
  };
  PlainArrangement arr = arrange();
  if (arr.cells.empty()) throw ReconstructionError(ReconstructionStage::hypothesis, "the footprint has no inside cell");
  check();

  // 3. The roof planes lifted onto each cell; where a plane's face would run beyond its points' height
  // range over no point, the cell is cut at the plane's contour (support cuts) and the arrangement
  // built again; then the floor below them.
  // The local top of the points on a raster of the sample spacing over the cells: the candidate faces
  // are many, and each sample then costs a lookup (surface_support.hpp).
  Box2 region;
  for (const Point2& v : arr.vertices) region.add(v);
  const LocalTop tops(points, params.surface_support.radius);
  const LocalTopRaster local_top(tops, region, params.surface_support.sample_spacing);
  std::vector<std::vector<std::size_t>> points_inside;
  std::vector<std::vector<int>> cell_planes = cell_roof_planes(points, roofs, arr, local_top, params, &points_inside);
  check();
  const std::vector<InputCurve> cuts = support_cuts(points, roofs, arr, cell_planes, points_inside, local_top, params);
  if (!cuts.empty()) {
    curves.insert(curves.end(), cuts.begin(), cuts.end());
    arr = arrange();
    if (arr.cells.empty()) throw ReconstructionError(ReconstructionStage::hypothesis, "the footprint has no inside cell");
    check();
    cell_planes = cell_roof_planes(points, roofs, arr, local_top, params);
    check();
    log_debug("hypothesis: " + std::to_string(cuts.size()) + " support cuts");
  }
  const std::size_t cell_count = arr.cells.size();
  const double floor_z = place_floor(roofs, arr, cell_planes, ground_z, ground_measured, params);
  const Levels lv{&roofs, floor_z};

  // 4. The candidate faces, 5. the selection problem over them, 6. a start for the solvers.
  CandidateFaces out;
  const auto edge_faces = lift_cells(arr, cell_planes, lv, params.vertex_merge_tolerance, out);
  check();
  build_selection_problem(points, roofs, arr, floor_z, edge_faces, local_top, params, energy, out);
  check();
  SelectionProblem& prob = out.problem;
  prob.start = start_assignment(out, arr, lv, cell_count, energy, params.start_descent_passes);

  out.cell_count = cell_count;
  out.edge_count = arr.edges.size();
  out.line_count = line_count;
  log_debug("hypothesis: " + std::to_string(R) + " roof planes, " + std::to_string(line_count) +
            " intersection lines, " + std::to_string(cell_count) + " cells, " + std::to_string(out.faces.size()) +
            " candidate faces, " + std::to_string(prob.edges.size()) + " edges");
  return out;
}

}  // namespace city3d
