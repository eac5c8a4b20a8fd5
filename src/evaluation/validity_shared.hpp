// What the validity check (validity.cpp) and the repair (src/repair/repair.cpp) share: 3D vector
// arithmetic, a measurement as text with fixed decimals, and val3dity's vertex snapping. Private to the two.
#pragma once

#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "city3d/types.hpp"

namespace city3d::detail {

struct Vec {
  double x, y, z;
};
inline Vec sub(const Point3& a, const Point3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec cross(const Vec& a, const Vec& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double dot(const Vec& a, const Vec& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline double norm(const Vec& a) { return std::sqrt(dot(a, a)); }

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

}  // namespace city3d::detail
