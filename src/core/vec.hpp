// 3D vector arithmetic on plain doubles, for the geometry that needs no CGAL kernel (validity, repair,
// evaluation, mesh checks, model assembly). Private to the library.
#pragma once

#include <cmath>

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

}  // namespace city3d::detail
