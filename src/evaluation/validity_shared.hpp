// What the validity check (validity.cpp) and the repair (src/repair/repair.cpp) share: a measurement as
// text with fixed decimals, and val3dity's vertex snapping. Private to the two.
#pragma once

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

}  // namespace city3d::detail
