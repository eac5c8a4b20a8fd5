// Planar segments by region growing: PCA normals, CGAL Shape_detection (5.5 positional API),
// least-squares refit, roof/wall labels. The only translation unit that includes region growing.
#include "city3d/planes.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Shape_detection/Region_growing/Region_growing.h>
#include <CGAL/Shape_detection/Region_growing/Region_growing_on_point_set.h>
#include <CGAL/property_map.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <iterator>
#include <limits>
#include <numeric>
#include <optional>
#include <sstream>
#include <string>
#include <utility>

#include "city3d/error.hpp"
#include "city3d/log.hpp"
#include "planes/neighbours.hpp"

namespace city3d {

void PlaneParams::validate() const {
  std::vector<std::string> problems;
  if (k_neighbors < 3)
    problems.push_back("k_neighbors = " + std::to_string(k_neighbors) + ", need >= 3");
  if (min_points < 3)
    problems.push_back("min_points = " + std::to_string(min_points) + ", need >= 3");
  // Negated comparisons so that NaN is rejected too.
  if (!(max_distance > 0.0) || !std::isfinite(max_distance))
    problems.push_back("max_distance = " + std::to_string(max_distance) + " m, need > 0");
  if (!(max_angle > 0.0 && max_angle <= 90.0))
    problems.push_back("max_angle = " + std::to_string(max_angle) + " deg, need in (0, 90]");
  if (absorb_rounds < 0)
    problems.push_back("absorb_rounds = " + std::to_string(absorb_rounds) + ", need >= 0");
  if (small_min_points < 3)
    problems.push_back("small_min_points = " + std::to_string(small_min_points) + ", need >= 3");
  for (const auto& [name, value] : {std::pair<const char*, int>{"small_divisor", small_divisor},
                                    {"small_points_divisor", small_points_divisor},
                                    {"few_points_divisor", few_points_divisor}})
    if (value < 1) problems.push_back(std::string(name) + " = " + std::to_string(value) + ", need >= 1");
  if (!(wall_max_normal_z >= 0.0 && wall_max_normal_z < 1.0))
    problems.push_back("wall_max_normal_z = " + std::to_string(wall_max_normal_z) +
                       ", need in [0, 1)");
  if (!(few_points_max_slope > 0.0 && few_points_max_slope <= 90.0))
    problems.push_back("few_points_max_slope = " + std::to_string(few_points_max_slope) +
                       " deg, need in (0, 90]");
  if (few_points_candidates < 3)
    problems.push_back("few_points_candidates = " + std::to_string(few_points_candidates) + ", need >= 3");
  if (few_points_max_points < 3)
    problems.push_back("few_points_max_points = " + std::to_string(few_points_max_points) + ", need >= 3");
  if (problems.empty()) return;
  std::string message = "planes: invalid parameters: ";
  for (std::size_t i = 0; i < problems.size(); ++i) message += (i ? "; " : "") + problems[i];
  throw ConfigError(message);
}

namespace detail {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using PointWithNormal = std::pair<Kernel::Point_3, Kernel::Vector_3>;
using PointRange = std::vector<PointWithNormal>;
using PointMap = CGAL::First_of_pair_property_map<PointWithNormal>;
using NormalMap = CGAL::Second_of_pair_property_map<PointWithNormal>;

namespace sd = CGAL::Shape_detection;

/// Each point's k nearest neighbours, searched once, in the order CGAL's K_neighbor_query gives them
/// (nearest first, the point itself among them; k_nearest_lists, neighbours.hpp, gives that search's
/// lists, entry for entry). The normals, the seed ordering, the growing and the refitting all ask for
/// the same lists, the growing once per point a region reaches and again whenever a region too small
/// is undone: handed out from here, each list is searched once.
class StoredNeighbors {
 public:
  StoredNeighbors(const std::vector<Point3>& points, std::size_t k)
      : count_(std::min(k, points.size())), lists_(k_nearest_lists(points, k)) {}

  /// The neighbours of point i.
  struct List {
    const std::uint32_t* first;
    const std::uint32_t* last;
    const std::uint32_t* begin() const { return first; }
    const std::uint32_t* end() const { return last; }
    std::size_t size() const { return static_cast<std::size_t>(last - first); }
  };
  List of(std::size_t i) const { return {lists_.data() + i * count_, lists_.data() + (i + 1) * count_}; }

  /// The neighbours of point i, as a CGAL NeighborQuery hands them over.
  void operator()(std::size_t i, std::vector<std::size_t>& neighbors) const {
    const List list = of(i);
    neighbors.assign(list.begin(), list.end());
  }

 private:
  std::size_t count_;                  // neighbours of every point
  std::vector<std::uint32_t> lists_;   // point i's at [i * count_, (i + 1) * count_)
};

// The queries only read the stored lists, so every detection on the points can share them.
using RegionType = sd::Point_set::Least_squares_plane_fit_region<Kernel, PointRange, PointMap, NormalMap>;
using Sorting = sd::Point_set::Least_squares_plane_fit_sorting<Kernel, PointRange, const StoredNeighbors, PointMap>;
using SeedMap = Sorting::Seed_map;
using RegionGrowing = sd::Region_growing<PointRange, const StoredNeighbors, RegionType, SeedMap>;

/// Least-squares plane through `indices` of `points`: the eigenvector of the smallest eigenvalue of
/// the covariance about the centroid. Centring first keeps the covariance well conditioned.
struct Fit {
  Eigen::Vector3d centroid;
  Eigen::Vector3d normal;  // unit
};

template <typename IndexRange, typename PointAt>
Fit fit_plane(const IndexRange& indices, PointAt point_at) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (auto i : indices) centroid += point_at(i);
  centroid /= static_cast<double>(indices.size());
  // The sums of d d^T entry by entry, six of them: d_i d_j and d_j d_i are the same double.
  double xx = 0.0, yx = 0.0, zx = 0.0, yy = 0.0, zy = 0.0, zz = 0.0;
  for (auto i : indices) {
    const Eigen::Vector3d d = point_at(i) - centroid;
    xx += d.x() * d.x();
    yx += d.y() * d.x();
    zx += d.z() * d.x();
    yy += d.y() * d.y();
    zy += d.z() * d.y();
    zz += d.z() * d.z();
  }
  Eigen::Matrix3d covariance;
  covariance << xx, yx, zx,
                yx, yy, zy,
                zx, zy, zz;
  // Eigenvalues come sorted ascending; column 0 is the normal.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  Eigen::Vector3d normal = solver.eigenvectors().col(0);
  if (!(normal.norm() > 0.0) || !normal.allFinite()) normal = Eigen::Vector3d::UnitZ();
  return {centroid, normal.normalized()};
}

Eigen::Vector3d centroid_of(const std::vector<Point3>& points) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const Point3& p : points) c += Eigen::Vector3d(p.x, p.y, p.z);
  return points.empty() ? c : Eigen::Vector3d(c / static_cast<double>(points.size()));
}

/// The segment of the points `region` (ascending indices): their least-squares plane, labelled roof or
/// wall by |n_z|, roof normals up, wall normals away from `building_centroid` in plan.
template <typename IndexRange>
PlanarSegment segment_of(const IndexRange& region, const std::vector<Point3>& points, const PlaneParams& params,
                         const Eigen::Vector3d& building_centroid) {
  const auto point_at = [&](std::size_t i) { return Eigen::Vector3d(points[i].x, points[i].y, points[i].z); };
  const Fit fit = fit_plane(region, point_at);
  Eigen::Vector3d n = fit.normal;
  PlanarSegment segment;
  segment.kind = std::abs(n.z()) < params.wall_max_normal_z ? PlanarSegment::Kind::wall : PlanarSegment::Kind::roof;
  if (segment.kind == PlanarSegment::Kind::roof) {
    if (n.z() < 0.0) n = -n;
  } else {
    // Outward from the building's centroid, measured horizontally (walls are near vertical).
    const Eigen::Vector3d out = fit.centroid - building_centroid;
    if (n.x() * out.x() + n.y() * out.y() < 0.0) n = -n;
  }
  segment.plane = {n.x(), n.y(), n.z(), -n.dot(fit.centroid)};
  double sum_squares = 0.0;
  segment.points.reserve(region.size());
  for (std::size_t i : region) {
    segment.points.push_back(static_cast<std::uint32_t>(i));
    const double distance = segment.plane.signed_distance(points[i]);
    sum_squares += distance * distance;
  }
  segment.rms = std::sqrt(sum_squares / static_cast<double>(region.size()));
  return segment;
}

/// Largest first; segments are disjoint, so the smallest point index is a unique tie-breaker.
bool largest_first(const PlanarSegment& l, const PlanarSegment& r) {
  if (l.points.size() != r.points.size()) return l.points.size() > r.points.size();
  return l.points.front() < r.points.front();
}

}  // namespace

/// What the detections on one building's points share, whatever their thresholds (PlaneDetector).
struct Neighbourhoods {
  int k_neighbors = 0;
  std::vector<Point3> points;  // as given
  // Identical points: the neighbour searches see one of each. CGAL's kd-tree cannot split equal
  // points, so 200,000 of them made every k-neighbour query scan all of them (hours); each copy
  // joins the plane of the point it copies. Without copies the points go through as they are.
  std::vector<Point3> distinct;                     // `points` less their copies; empty without copies
  std::vector<std::vector<std::uint32_t>> members;  // of each distinct point, its copies in `points`
  PointRange range;                                 // the searched points with their PCA normals
  std::optional<StoredNeighbors> neighbors;         // none for fewer than 3 points: no plane to find
  std::vector<std::size_t> seeds;                   // the searched points, most locally planar first

  /// The points the searches see: `points`, or `distinct` when there are copies.
  const std::vector<Point3>& searched() const { return members.empty() ? points : distinct; }
};

namespace {

/// Copies of identical points set aside: fills `distinct` and `members`, or leaves them empty when
/// no point is repeated.
void set_copies_aside(Neighbourhoods& n) {
  const std::vector<Point3>& points = n.points;
  std::vector<std::uint32_t> order(points.size());
  std::iota(order.begin(), order.end(), 0u);
  const auto less = [&](std::uint32_t a, std::uint32_t b) {
    const Point3 &p = points[a], &q = points[b];
    if (p.x != q.x) return p.x < q.x;
    if (p.y != q.y) return p.y < q.y;
    if (p.z != q.z) return p.z < q.z;
    return a < b;
  };
  const auto same = [&](std::uint32_t a, std::uint32_t b) {
    const Point3 &p = points[a], &q = points[b];
    return p.x == q.x && p.y == q.y && p.z == q.z;
  };
  std::sort(order.begin(), order.end(), less);
  std::vector<std::uint32_t> original_of(points.size());  // each point's first copy
  std::size_t copies = 0;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const bool repeat = k > 0 && same(order[k - 1], order[k]);
    original_of[order[k]] = repeat ? original_of[order[k - 1]] : order[k];
    copies += repeat;
  }
  if (copies == 0) return;

  std::vector<std::uint32_t> distinct_index(points.size());
  for (std::uint32_t i = 0; i < points.size(); ++i) {
    if (original_of[i] == i) {
      distinct_index[i] = static_cast<std::uint32_t>(n.distinct.size());
      n.distinct.push_back(points[i]);
      n.members.emplace_back();
    }
    n.members[distinct_index[original_of[i]]].push_back(i);
  }
  log_debug("planes: " + std::to_string(copies) + " copies of identical points set aside for the searches");
}

/// The regions grown on the searched points with `params`' thresholds, refitted, as segments of the
/// searched points, largest first.
std::vector<PlanarSegment> grow_planes(const Neighbourhoods& n, const PlaneParams& params) {
  const std::vector<Point3>& local_points = n.searched();
  if (local_points.size() < static_cast<std::size_t>(params.min_points)) {
    log_debug("planes: " + std::to_string(local_points.size()) + " points, fewer than min_points = " +
              std::to_string(params.min_points) + ", no planes");
    return {};
  }
  const auto point_at = [&](std::size_t i) {
    const Point3& p = local_points[i];
    return Eigen::Vector3d(p.x, p.y, p.z);
  };
  const StoredNeighbors& neighbors = *n.neighbors;  // min_points >= 3

  RegionType region_type(n.range, params.max_distance, params.max_angle,
                         static_cast<std::size_t>(params.min_points), PointMap(), NormalMap());
  RegionGrowing region_growing(n.range, neighbors, region_type, SeedMap(n.seeds));
  std::vector<std::vector<std::size_t>> regions;
  region_growing.detect(std::back_inserter(regions));

  // Refitting: the points the growing left out (mostly along creases and steps, where the PCA
  // normals mix two planes and fail the angle test) join the plane of a neighbour when they lie
  // within max_distance of it, the nearest such plane first; absorb_rounds rounds let the planes
  // grow a few points into a crease, so that both planes of a ridge or a hip reach its line.
  // Each round decides on the planes as they were at its start, so the order of the points does
  // not matter; the planes are refitted at the end.
  if (params.absorb_rounds > 0 && !regions.empty()) {
    constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> label(local_points.size(), kNone);
    for (std::size_t r = 0; r < regions.size(); ++r)
      for (std::size_t i : regions[r]) label[i] = static_cast<std::uint32_t>(r);
    std::vector<Fit> fits;
    for (const auto& region : regions) fits.push_back(fit_plane(region, point_at));
    for (int round = 0; round < params.absorb_rounds; ++round) {
      std::vector<std::pair<std::size_t, std::uint32_t>> joins;
      for (std::size_t i = 0; i < local_points.size(); ++i) {
        if (label[i] != kNone) continue;
        double best = params.max_distance;
        std::uint32_t best_label = kNone;
        for (std::size_t k : neighbors.of(i)) {
          const std::uint32_t l = label[k];
          if (l == kNone) continue;
          const double d = std::abs(fits[l].normal.dot(point_at(i) - fits[l].centroid));
          if (d < best || (d == best && l < best_label)) best = d, best_label = l;
        }
        if (best_label != kNone) joins.emplace_back(i, best_label);
      }
      if (joins.empty()) break;
      for (const auto& [i, l] : joins) {
        label[i] = l;
        regions[l].push_back(i);
      }
    }
  }

  const Eigen::Vector3d building_centroid = centroid_of(local_points);
  std::vector<PlanarSegment> segments;
  segments.reserve(regions.size());
  for (auto& region : regions) {
    std::sort(region.begin(), region.end());
    segments.push_back(segment_of(region, local_points, params, building_centroid));
  }

  std::sort(segments.begin(), segments.end(), largest_first);

  if (log_level() >= LogLevel::debug) {
    std::size_t walls = 0;
    for (const auto& s : segments) walls += s.kind == PlanarSegment::Kind::wall;
    std::ostringstream message;
    message << "planes: " << segments.size() << " planes (" << walls << " walls) from "
            << local_points.size() << " points";
    log_debug(message.str());
  }
  return segments;
}

}  // namespace
}  // namespace detail

PlaneDetector::PlaneDetector(const std::vector<Point3>& local_points, int k_neighbors) {
  PlaneParams only_k;  // validate() words a bad k as detect_planes() does
  only_k.k_neighbors = k_neighbors;
  only_k.validate();
  if (local_points.size() > std::numeric_limits<std::uint32_t>::max())
    throw ReconstructionError(ReconstructionStage::planes, "" + std::to_string(local_points.size()) +
                              " points, at most 2^32 - 1 supported");
  for (std::size_t i = 0; i < local_points.size(); ++i) {
    const Point3& p = local_points[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw ReconstructionError(ReconstructionStage::planes, "point " + std::to_string(i) + " has a non-finite coordinate");
  }
  auto n = std::make_shared<detail::Neighbourhoods>();
  n->k_neighbors = k_neighbors;
  n->points = local_points;
  detail::set_copies_aside(*n);
  const std::vector<Point3>& points = n->searched();
  if (points.size() >= 3) {
    n->range.reserve(points.size());
    for (const Point3& p : points)
      n->range.emplace_back(detail::Kernel::Point_3(p.x, p.y, p.z), detail::Kernel::Vector_3(0, 0, 1));
    // One search per point serves the normals, the seed order, the growing and the refitting.
    const detail::StoredNeighbors& neighbors =
        n->neighbors.emplace(points, static_cast<std::size_t>(k_neighbors));

    // PCA normals: smallest-eigenvalue direction of the k-neighbourhood (at least 3 points). Their
    // sign is irrelevant to the growing (CGAL compares |cos|), so they are left as the solver gives them.
    const auto point_at = [&](std::size_t i) { return Eigen::Vector3d(points[i].x, points[i].y, points[i].z); };
    for (std::size_t i = 0; i < points.size(); ++i) {
      const detail::Fit fit = detail::fit_plane(neighbors.of(i), point_at);
      n->range[i].second = detail::Kernel::Vector_3(fit.normal.x(), fit.normal.y(), fit.normal.z());
    }

    // Seeds in order of local planarity, so regions start on clean roof patches, not on edges.
    detail::Sorting sorting(n->range, neighbors, detail::PointMap());
    sorting.sort();
    n->seeds.resize(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) n->seeds[i] = get(sorting.seed_map(), i);
  }
  shared_ = std::move(n);
}

std::vector<PlanarSegment> PlaneDetector::detect(const PlaneParams& params) const {
  params.validate();
  const detail::Neighbourhoods& n = *shared_;
  if (params.k_neighbors != n.k_neighbors)
    throw ConfigError("planes: the detector found " + std::to_string(n.k_neighbors) +
                      " neighbours of each point, params ask for k_neighbors = " +
                      std::to_string(params.k_neighbors));
  std::vector<PlanarSegment> segments = detail::grow_planes(n, params);
  if (n.members.empty()) return segments;

  // Each distinct point's copies join its segment; the plane stays the distinct points' fit.
  for (PlanarSegment& segment : segments) {
    std::vector<std::uint32_t> points;
    for (std::uint32_t u : segment.points) points.insert(points.end(), n.members[u].begin(), n.members[u].end());
    std::sort(points.begin(), points.end());
    double sum_squares = 0.0;
    for (std::uint32_t i : points) {
      const double d = segment.plane.signed_distance(n.points[i]);
      sum_squares += d * d;
    }
    segment.rms = std::sqrt(sum_squares / static_cast<double>(points.size()));
    segment.points = std::move(points);
  }
  std::sort(segments.begin(), segments.end(), detail::largest_first);
  return segments;
}

std::vector<PlanarSegment> detect_planes(const std::vector<Point3>& local_points, const PlaneParams& params) {
  params.validate();
  return PlaneDetector(local_points, params.k_neighbors).detect(params);
}

std::vector<PlanarSegment> detect_planes_of_few_points(const std::vector<Point3>& local_points,
                                                       const PlaneParams& params, std::size_t min_inliers,
                                                       std::size_t max_points) {
  params.validate();
  const std::size_t n = local_points.size();
  min_inliers = std::max<std::size_t>(min_inliers, 4);
  if (n < min_inliers || n > max_points) return {};
  for (const Point3& p : local_points)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return {};
  const Eigen::Vector3d building_centroid = detail::centroid_of(local_points);
  const auto point_at = [&](std::size_t i) {
    return Eigen::Vector3d(local_points[i].x, local_points[i].y, local_points[i].z);
  };
  // A normal's |z| between a wall's and this is a plane steeper than roofs are (few_points_max_slope).
  const double min_roof_normal_z = std::cos(params.few_points_max_slope * kPi / 180.0);
  const auto too_steep = [&](double normal_z) {
    return std::abs(normal_z) >= params.wall_max_normal_z && std::abs(normal_z) < min_roof_normal_z;
  };
  std::vector<bool> taken(n, false);
  std::vector<PlanarSegment> segments;
  for (;;) {
    std::vector<std::size_t> free;
    for (std::size_t i = 0; i < n; ++i)
      if (!taken[i]) free.push_back(i);
    if (free.size() < min_inliers) break;
    // The plane through three candidates that holds the most free points within max_distance (the
    // first such triple in index order): every triple of the candidates is tried. The candidates are
    // the free points, or as many of them as few_points_candidates, evenly spread in order.
    const std::size_t m = std::min(free.size(), static_cast<std::size_t>(params.few_points_candidates));
    std::vector<std::size_t> candidates(m);
    for (std::size_t k = 0; k < m; ++k) candidates[k] = free[k * free.size() / m];
    std::vector<std::size_t> best;
    for (std::size_t a = 0; a < m; ++a)
      for (std::size_t b = a + 1; b < m; ++b)
        for (std::size_t c = b + 1; c < m; ++c) {
          const Eigen::Vector3d pa = point_at(candidates[a]);
          Eigen::Vector3d normal = (point_at(candidates[b]) - pa).cross(point_at(candidates[c]) - pa);
          const double length = normal.norm();
          if (!(length > 1e-9)) continue;  // collinear
          normal /= length;
          if (too_steep(normal.z())) continue;
          std::size_t count = 0;
          for (std::size_t i : free) count += std::abs(normal.dot(point_at(i) - pa)) <= params.max_distance;
          if (count <= best.size()) continue;
          best.clear();
          for (std::size_t i : free)
            if (std::abs(normal.dot(point_at(i) - pa)) <= params.max_distance) best.push_back(i);
        }
    if (best.size() < min_inliers) break;
    // Refitted by least squares; the points within max_distance of the refit are the segment.
    PlanarSegment refit = detail::segment_of(best, local_points, params, building_centroid);
    std::vector<std::size_t> inliers;
    for (std::size_t i : free)
      if (std::abs(refit.plane.signed_distance(local_points[i])) <= params.max_distance) inliers.push_back(i);
    if (inliers.size() < min_inliers) inliers = best;
    for (std::size_t i : inliers) taken[i] = true;
    PlanarSegment segment = detail::segment_of(inliers, local_points, params, building_centroid);
    if (!too_steep(segment.plane.c))
      segments.push_back(std::move(segment));  // a refit turned steep: left out
  }
  std::sort(segments.begin(), segments.end(), detail::largest_first);
  return segments;
}

}  // namespace city3d
