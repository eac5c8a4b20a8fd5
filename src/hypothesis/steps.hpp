// The steps of the face hypothesis (paper section 3.3, include/city3d/hypothesis.hpp describes the
// whole construction), one source file each, and the plain data passed between them. Private to
// src/hypothesis; generate_candidates() in hypothesis.cpp calls them in order:
//
//   curves.cpp               the input curves: footprint rings, inner walls, clipped roof-roof lines
//                            (merged when nearly coincident), dangling ends extended
//   arrangement.cpp          the exact 2D arrangement (the only CGAL code): antennas, inside/outside,
//                            thin cells merged, holes bridged, collinear classes -> PlainArrangement
//   arrangement_cleanup.cpp  short edges contracted, small detached parts dropped
//   cell_planes.cpp          the roof planes lifted onto each cell, and the floor height below them
//   faces.cpp                roof, floor and wall faces over the cells and edges, welded by vertex
//                            identity; faces that could never close are pruned
//   support.cpp              the selection problem: support (data term), edges, face prior, overlaps
//   start.cpp                a closed start assignment for the solvers
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "city3d/hypothesis.hpp"
#include "city3d/surface_support.hpp"
#include "hypothesis/geometry.hpp"

namespace city3d::detail {

// The signed area of a cell's loop (shoelace), m2; inline in the arrangement's loops (through rings.hpp's
// signed_area, a call per cell, the whole-block footprint's hypothesis took 30% longer).
inline double loop_area(const std::vector<Point2>& polygon) {
  double area = 0.0;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const auto& p = polygon[i];
    const auto& q = polygon[(i + 1) % polygon.size()];
    area += p.x * q.y - q.x * p.y;
  }
  return 0.5 * area;
}

// ---------------------------------------------------------------------------------------------
// The 2D arrangement, as plain data.

enum class CurveKind { footprint, inner_wall, roof_line, bridge };

struct InputCurve {
  Point2 a, b;
  CurveKind kind;
  int source;  // inner wall: index into walls; others -1
};

struct PlainArrangement {
  std::vector<Point2> vertices;
  struct Edge {
    std::uint32_t u = 0, w = 0;  // u < w
    int left = -1, right = -1;   // inside cell on the left / right of u -> w, or -1 (outside)
    std::uint32_t line = 0;      // collinearity class of the curves it lies on
    int wall_source = -1;        // smallest inner-wall index among its curves
  };
  std::vector<Edge> edges;
  struct Cell {
    std::vector<std::pair<std::uint32_t, bool>> loop;  // (edge, walked u -> w), counter-clockwise
    std::vector<Point2> polygon;                       // loop vertices, counter-clockwise
    double area = 0.0;
  };
  std::vector<Cell> cells;
};

// Levels: the roof planes 0..R-1 and the floor R, as heights over xy.
struct Levels {
  const std::vector<PlanarSegment>* roofs;
  double ground_z;
  int floor() const { return static_cast<int>(roofs->size()); }
  double height(int level, double x, double y) const {
    if (level == floor()) return ground_z;
    return roof_height((*roofs)[static_cast<std::size_t>(level)], x, y);
  }
};

// ---------------------------------------------------------------------------------------------
// 1. The input curves (curves.cpp): the footprint rings, the inner walls (extended by
// line_support_margin), the roof-roof intersection lines clipped to where both planes have points
// (nearly coincident ones merged), and dangling ends inside the footprint extended to the next curve.
// `line_count` receives the number of roof lines. Throws ReconstructionError on an empty footprint.
std::vector<InputCurve> arrangement_curves(const std::vector<Point3>& points, const std::vector<PlanarSegment>& roofs,
                                           const std::vector<VerticalPlane>& walls,
                                           const std::vector<Polygon2>& footprint_local,
                                           const HypothesisParams& params, std::size_t& line_count);

// 2. The arrangement of the curves (arrangement.cpp): exact, with thin cells merged and holes
// bridged, every inside cell a simple polygon; vertices, cells and edges in a deterministic order.
PlainArrangement build_arrangement(std::vector<InputCurve> curves, double min_cell_width);

// Its clean-up (arrangement_cleanup.cpp): edges shorter than min_length contracted (with smaller
// tolerances, or not at all, when that pinches a cell), and detached parts smaller than min_area
// dropped (never the largest).
PlainArrangement contract_robustly(const PlainArrangement& in, double min_length);
PlainArrangement drop_small_parts(const PlainArrangement& in, double min_area);

// 3. The roof planes lifted onto each cell (cell_planes.cpp), ascending plane indices per cell.
std::vector<std::vector<int>> cell_roof_planes(const std::vector<Point3>& points,
                                               const std::vector<PlanarSegment>& roofs,
                                               const PlainArrangement& arr, const LocalTopRaster& local_top,
                                               const HypothesisParams& params,
                                               std::vector<std::vector<std::size_t>>* points_inside = nullptr);

// Support cuts (cell_planes.cpp): where a plane lifted onto a cell rises within the cell more than
// support_cut_rise above the height support_cut_height above its highest point, and the face beyond that
// height rises over no point (more than max_unsupported_area of it, surface_support.hpp): the plane's
// contour at that height, clipped to the cell, a line that ends the face where its points end (a steep
// plane around a hip corner, a roof plane over a lower part beside it). Only planes with at least
// min_support_points of their points inside the cell (points_inside, as cell_roof_planes gives it) are cut.
std::vector<InputCurve> support_cuts(const std::vector<Point3>& points, const std::vector<PlanarSegment>& roofs,
                                     const PlainArrangement& arr, const std::vector<std::vector<int>>& cell_planes,
                                     const std::vector<std::vector<std::size_t>>& points_inside,
                                     const LocalTopRaster& local_top, const HypothesisParams& params);

// The floor below them: drops, per cell, planes that come too low (see hypothesis.hpp, 2) and returns
// the floor height (ground_z, or lower so that every remaining roof vertex keeps floor_clearance).
double place_floor(const std::vector<PlanarSegment>& roofs, const PlainArrangement& arr,
                   std::vector<std::vector<int>>& cell_planes, double ground_z, bool ground_measured,
                   const HypothesisParams& params);

// 4. The candidate faces (faces.cpp): roof faces over every cell on each of its planes, a floor face
// per cell, wall faces over every edge between consecutive levels; fills out.vertices, out.faces
// (with areas) and out.polygons, and returns, per edge of the faces' union (in vertex-pair order),
// the faces that use it. Faces that could never close are pruned.
std::vector<std::vector<std::uint32_t>> lift_cells(const PlainArrangement& arr,
                                                   const std::vector<std::vector<int>>& cell_planes,
                                                   const Levels& lv, double vertex_merge_tolerance,
                                                   CandidateFaces& out);

// 5. The selection problem over out's faces (support.cpp): support and unsupported area of every face,
// the edges and their sharp pairs, floors forced on, the face prior of every roof segment (its
// best-supported face among those whose support outweighs their unsupported area under `energy`),
// vertical overlaps.
void build_selection_problem(const std::vector<Point3>& points, const std::vector<PlanarSegment>& roofs,
                             const PlainArrangement& arr, double floor_z,
                             const std::vector<std::vector<std::uint32_t>>& edge_faces, const LocalTopRaster& local_top,
                             const HypothesisParams& params, const SelectionParams& energy, CandidateFaces& out);

// 6. A closed start assignment for the solvers (start.cpp), descended under the weights of `energy`
// for at most `max_passes` passes, or an empty vector when none was found.
std::vector<bool> start_assignment(const CandidateFaces& out, const PlainArrangement& arr, const Levels& lv,
                                   std::size_t cell_count, const SelectionParams& energy,
                                   std::size_t max_passes);

}  // namespace city3d::detail
