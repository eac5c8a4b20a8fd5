// What the validity check (validity.cpp) and the repair (src/repair/repair.cpp) share: a measurement as
// text with fixed decimals, and val3dity's vertex snapping; and the check's test of a shell's triangles,
// for tests/test_validity.cpp. Private to these.
#pragma once

#include <array>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "city3d/evaluation.hpp"
#include "city3d/types.hpp"

namespace city3d::detail {

inline std::string format(double v, int decimals) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(decimals);
  s << v;
  return s.str();
}

// Merges vertices closer than `tolerance` (val3dity's snap_tol) into the first of them, in index
// order. Returns, for each vertex, the vertex it becomes (itself when none is near).
std::vector<std::uint32_t> snap_vertices(const std::vector<Point3>& vertices, double tolerance);

// validate_solid() of the shells over `vertices` with their snap map given (snap_vertices(vertices,
// params.snap_tolerance), made once by a caller that validates many polygons over one vertex list).
std::vector<ValidityError> validate_snapped_solid(const std::vector<Point3>& vertices,
                                                  const std::vector<std::vector<SolidPolygon>>& shells,
                                                  const std::vector<std::uint32_t>& snapped,
                                                  const ValidityParams& params);

// Whether triangles (vertex ids) form a surface CGAL can hold: no triangle with a vertex twice, no
// directed edge twice, and the triangles around each vertex one umbrella (joined through the edges they
// share). The same answer as CGAL's is_polygon_soup_a_polygon_mesh, from sorted vectors instead of sets.
bool triangles_form_a_surface(const std::vector<std::array<std::uint32_t, 3>>& triangles);

}  // namespace city3d::detail
