// Planar segments of one building's points: region growing (Rabbani et al. 2006) on PCA normals,
// each region refitted by least squares and labelled roof or wall (City3D, paper section 3.1).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "city3d/types.hpp"

namespace city3d {

/// Parameters of detect_planes(). City3D grows regions with min 40 points, 0.5 m and 30 degrees in
/// a 1 m sphere; growing here is stricter in distance (0.2 m, k nearest neighbours), and with the
/// stricter growth planes of 20 points gave models closer to the points on all three datasets of
/// the dev set (docs/BENCHMARKS.md, "min_points"), so 20 is the default.
struct PlaneParams {
  int k_neighbors = 12;        ///< neighbours for the PCA normals and for growing, >= 3
  int min_points = 20;         ///< points a plane needs to be reported, >= 3
  double max_distance = 0.2;   ///< point-to-plane distance while growing, metres, > 0
  /// Point normal vs plane normal while growing, degrees, in (0, 90]. City3D grows at 30; 20 keeps
  /// small roof parts apart, and with the refitting below (which brings the crease points into their
  /// planes) it fitted the dev set better (AHN3 median 0.181 against 0.205 m with lambda_c 0.3),
  /// the Delft block as well (docs/BENCHMARKS.md, "RMSE against faces").
  double max_angle = 20.0;
  /// Rounds of refitting after the growing: a point in no plane joins the nearest plane (within
  /// max_distance) among those of its k neighbours; then the planes are refitted. >= 0, 0 = off.
  int absorb_rounds = 3;
  /// A segment is a wall when |n_z| of its unit normal is below this, in [0, 1). The default 0.17
  /// is sin(9.8 deg): the normal is more than 80.2 deg away from vertical, i.e. the plane is within
  /// 9.8 deg of vertical. Everything else (flat and sloped roofs up to ~80 deg) is a roof.
  double wall_max_normal_z = 0.17;
  /// Fewest points of a plane when a building is retried with smaller planes (a shed or a garage of
  /// fewer than min_points in all) and in explain_more's rebuilds, >= 3.
  int small_min_points = 10;
  /// A building without a roof plane is retried with planes of min_points / small_divisor points, or
  /// of its points / small_points_divisor when that is fewer (at least small_min_points); explain_more's
  /// left-out levels and planes take the first too. Each >= 1.
  int small_divisor = 2;
  int small_points_divisor = 3;
  /// A plane through triples of few points (detect_planes_of_few_points) holds at least its points /
  /// few_points_divisor of them (rounded up). >= 1.
  int few_points_divisor = 4;
  /// A plane through triples of few points (detect_planes_of_few_points) that is neither a wall nor
  /// a roof of at most this slope, degrees, is not taken: among a few returns at two heights (a step,
  /// an eave over a lower part), a triple spanning both makes a plane steeper than roofs are, a blade
  /// over the lower part. In (0, 90].
  double few_points_max_slope = 70.0;
  /// The triples of detect_planes_of_few_points are drawn from at most this many of the points not
  /// yet in a plane, evenly spread over them in order (every one of them when there are no more); a
  /// triple's inliers are counted among all of them. The triples grow with the cube of this. >= 3.
  int few_points_candidates = 60;
  /// Most points of a building with no roof plane from region growing that still gets the planes
  /// through triples (detect_planes_of_few_points): a house of tens or hundreds of returns in a survey of 1
  /// point per m2, whose k-neighbour normals mix its slopes. >= 3.
  int few_points_max_points = 2000;

  /// Throws ConfigError listing every invalid field ("planes: invalid parameters: ...; ...").
  void validate() const;
};

/// A plane a x + b y + c z + d = 0 with a unit normal (a, b, c), in the frame of the points.
struct Plane3 {
  double a = 0.0;
  double b = 0.0;
  double c = 1.0;
  double d = 0.0;

  /// Signed distance of p to the plane, metres (positive on the normal's side).
  double signed_distance(const Point3& p) const { return a * p.x + b * p.y + c * p.z + d; }
};

/// A set of points supporting one plane.
struct PlanarSegment {
  enum class Kind { roof, wall };

  /// Least-squares plane of `points`. Roof normals point up (c >= 0). Wall normals point away
  /// from the centroid of all input points (outwards for an outer wall).
  Plane3 plane;
  std::vector<std::uint32_t> points;  ///< indices into the input points, ascending
  Kind kind = Kind::roof;
  double rms = 0.0;                   ///< RMS point-to-plane distance of `points`, metres
};

/// Detects the planar segments of one building's points.
///
/// `local_points` must be in a local metric frame (coordinates of tens or hundreds of metres, not
/// RD New world values): normals and fits lose precision far from the origin.
/// Steps: PCA normals from the k nearest neighbours; CGAL region growing seeded in order of local
/// planarity; least-squares refit of every region; roof/wall label by |n_z|.
/// Output is deterministic for a given input order: segments are sorted by size (largest first),
/// ties broken by their smallest point index. Points in no segment are simply not referenced.
/// Returns an empty vector when there are fewer than `min_points` points.
/// Throws ConfigError (invalid params) or ReconstructionError (a non-finite coordinate, or more
/// than 2^32 - 1 points).
std::vector<PlanarSegment> detect_planes(const std::vector<Point3>& local_points,
                                         const PlaneParams& params);

namespace detail {
struct Neighbourhoods;  // planes.cpp
}

/// detect_planes() in two steps, for detections that differ in thresholds but not in the points or k:
/// the first (the constructor) does what depends on the points and k_neighbors only, the k nearest
/// neighbours of every point, its PCA normal and the seed order, four fifths of the work on the
/// city3d_dev clouds; each detect() then grows, refits and labels with its own min_points,
/// max_distance, max_angle, absorb_rounds and wall_max_normal_z. (The pipeline detects again on the
/// same points: with smaller planes for a building without a roof plane, and in explain_more's variants.)
/// detect(params) returns exactly what detect_planes(local_points, params) returns. Copyable and
/// cheap to copy (the shared work is immutable); detect() may run on several threads at once.
class PlaneDetector {
 public:
  /// Throws ConfigError (k_neighbors < 3) or ReconstructionError (as detect_planes()).
  PlaneDetector(const std::vector<Point3>& local_points, int k_neighbors);

  /// Throws ConfigError (invalid params, or params.k_neighbors not the detector's).
  std::vector<PlanarSegment> detect(const PlaneParams& params) const;

 private:
  std::shared_ptr<const detail::Neighbourhoods> shared_;
};

/// The planes of a building too small or too sparse for region growing (a shed of a few points, a house
/// in a survey of 2 points per m2, whose k-neighbour normals mix its roof's slopes): the plane through
/// three of the points that holds the most of them within max_distance, every triple of the
/// candidates tried (`params.few_points_candidates` of the points not yet in a plane, evenly spread;
/// all of them when there are no more), refitted by least squares, its points taken; again on the rest
/// while a plane holds at least `min_inliers` (at least 4: any three points make a plane) of them.
/// Labelled and ordered as detect_planes() does. Returns nothing for fewer than min_inliers or more
/// than `max_points` points, or a non-finite coordinate. Planes steeper than `params.few_points_max_slope`
/// but not walls are not taken (their points are left to the next plane). Deterministic.
std::vector<PlanarSegment> detect_planes_of_few_points(const std::vector<Point3>& local_points,
                                                       const PlaneParams& params, std::size_t min_inliers,
                                                       std::size_t max_points = 60);

}  // namespace city3d
