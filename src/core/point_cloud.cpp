// PointCloud housekeeping: clear and append while keeping every attribute empty or as long as points.
#include "city3d/point_cloud.hpp"

namespace city3d {
namespace {

/// Appends `from` to `to` when both clouds have the attribute; otherwise the merged cloud cannot
/// have it for every point, so it is dropped. An empty `to` simply takes `from`'s attributes.
template <typename T>
void append_attribute(std::vector<T>& to, const std::vector<T>& from, std::size_t to_points,
                      std::size_t from_points) {
  const bool to_has = to_points == 0 || !to.empty();
  const bool from_has = from_points == 0 || !from.empty();
  if (to_has && from_has) {
    to.insert(to.end(), from.begin(), from.end());
  } else {
    to.clear();
  }
}

}  // namespace

void PointCloud::clear() {
  points.clear();
  intensity.clear();
  return_number.clear();
  number_of_returns.clear();
  classification.clear();
  gps_time.clear();
  rgb.clear();
  normals.clear();
}

void PointCloud::append(const PointCloud& other) {
  const std::size_t n = size();
  const std::size_t m = other.size();
  if (m == 0) return;
  append_attribute(intensity, other.intensity, n, m);
  append_attribute(return_number, other.return_number, n, m);
  append_attribute(number_of_returns, other.number_of_returns, n, m);
  append_attribute(classification, other.classification, n, m);
  append_attribute(gps_time, other.gps_time, n, m);
  append_attribute(rgb, other.rgb, n, m);
  append_attribute(normals, other.normals, n, m);
  points.insert(points.end(), other.points.begin(), other.points.end());
}

}  // namespace city3d
