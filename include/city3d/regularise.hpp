// Regularisation: turns the polylines of the heightmap edges into regular line segments (parallel,
// collinear, orthogonal), by clustering and adjustment (paper section 3.2, "Regularity enhancement").
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "city3d/polylines.hpp"
#include "city3d/types.hpp"

namespace city3d {

/// A line segment in a local metric frame.
struct Segment2 {
  Point2 a, b;
};

/// Parameters of the regularisation stage. Angles in degrees, distances in metres.
struct RegulariseParams {
  /// Near-parallel / near-orthogonal snapping threshold, and the largest rotation that aligns a cluster
  /// with a footprint edge direction (the paper's 20 degrees). In [0, 45].
  double angle_threshold = 20.0;
  /// DBSCAN neighbourhood distance: the larger of the two minimum distances between one segment and
  /// the other's supporting line. Also the largest offset between near-collinear segments that are
  /// made collinear. > 0.
  double cluster_distance = 0.5;
  /// DBSCAN neighbourhood angle between two segments' directions. In (0, 90).
  double cluster_angle = 15.0;
  /// DBSCAN minimum number of neighbours (the segment included) of a core segment. >= 1. Segments in
  /// no cluster keep their own direction (they still take part in the snapping).
  int min_cluster = 1;
  /// Collinear segments whose extents overlap or are closer than this along their line are merged. >= 0.
  double merge_gap = 0.3;
  /// Footprint edges shorter than this do not propose directions. >= 0.
  double min_footprint_edge = 1.0;
  /// Segments shorter than this are dropped from the input (degenerate pieces). >= 0.
  double min_segment_length = 0.05;

  /// Throws ConfigError listing every invalid field.
  void validate() const;
};

/// The regular segments and how many there were before and after.
struct RegularisationResult {
  std::vector<Segment2> segments;
  std::size_t segments_before = 0;  ///< segments of the input polylines (after dropping degenerate ones)
  std::size_t segments_after = 0;   ///< == segments.size()
};

/// Regularises polylines (local frame).
///
/// 1. Splits the polylines into segments.
/// 2. Clusters them with DBSCAN: two segments are neighbours when their directions differ by at most
///    cluster_angle and their distance (see cluster_distance) is at most cluster_distance.
/// 3. Rotates every segment of a cluster, about its midpoint, to the cluster's length-weighted mean
///    direction (endpoints projected onto the rotated line).
/// 4. With a footprint, a cluster direction within angle_threshold of a footprint edge direction takes
///    that direction exactly.
/// 5. Taking directions by decreasing supporting length (footprint directions first), a direction
///    within angle_threshold of an earlier one, or of its perpendicular, becomes exactly that.
/// 6. Segments with the same direction whose offsets differ by at most cluster_distance are moved
///    onto one common line (length-weighted mean offset): exactly collinear.
/// 7. Overlapping collinear segments (gap up to merge_gap) are merged.
/// Deterministic. Throws ConfigError for invalid params.
RegularisationResult regularise(const std::vector<Polyline2>& polylines,
                                const std::vector<Polygon2>* footprint_local, const RegulariseParams& params);

/// The numbers of regularise_outline() besides its angle threshold.
struct OutlineSnapParams {
  /// The dominant direction is the one with the most edge length within this many degrees of it
  /// (modulo 90), in (0, 45].
  double dominant_window = 10.0;
  /// Consecutive lines closer than this many degrees to parallel have no corner worth taking: the
  /// outline is returned as it was, in (0, 90).
  double min_corner_angle = 5.0;
  /// The result is refused when it would move a corner further than this from every corner of the
  /// input, metres (> 0)...
  double max_shift = 1.5;
  /// ...or change the outline's area by more than this share of it (> 0).
  double max_area_change = 0.1;

  /// Throws ConfigError listing every invalid field ("outline snap: invalid parameters: ...").
  void validate() const;
};

/// Regularises a closed outline (an inferred footprint): edge directions within `angle_threshold`
/// degrees of the dominant direction (or its orthogonal) are snapped to it exactly, consecutive edges
/// that end up parallel are merged into one line (length-weighted offset), and the vertices become
/// the intersections of consecutive lines. Returns the input unchanged when two consecutive lines are
/// within `min_corner_angle` of parallel, or when the result would move a corner by more than
/// `max_shift` metres, change the area by more than `max_area_change` (10%), or self-intersect.
/// Throws ConfigError (invalid params).
Polygon2 regularise_outline(const Polygon2& polygon, double angle_threshold = 20.0,
                            const OutlineSnapParams& params = {});

/// How fit_outline_to_points() moves an inferred outline onto its outermost points.
struct OutlineFitParams {
  /// Points within this of an edge's line count for it, metres (> 0)...
  double band = 1.0;
  /// ...when their projection lies this far in from each end of the edge (at most a quarter of its
  /// length), metres (>= 0).
  double end_margin = 0.5;
  /// An edge with fewer such points stays where it is (>= 1).
  int min_points = 5;
  /// The edge goes to the k-th outermost of its points, k the larger of 2 and this share of them, in
  /// (0, 1]: a robust maximum, which a stray point does not pull out.
  double outermost_share = 0.02;
  /// The fit is refused when it would move a corner further than this, metres (> 0)...
  double max_shift = 1.5;
  /// ...or change the outline's area by more than this share of it (> 0).
  double max_area_change = 0.25;

  /// Throws ConfigError listing every invalid field ("outline fit: invalid parameters: ...").
  void validate() const;
};

/// Moves each edge of an inferred outline, along its normal (its direction is kept), onto the
/// outermost points beside it, so that walls pass through the facade points a cloud has and roofs
/// end at their last points otherwise. For each edge, the points whose projection lies on the edge
/// (`end_margin` metres in from each end, at most a quarter of its length) and within `band` metres
/// of its line count; the line goes to the k-th largest of their outward offsets, k = the larger of
/// 2 and `outermost_share` (2%) of them (a robust maximum: a stray point does not pull the wall out).
/// Edges with fewer than `min_points` such points stay. The corners become the intersections of
/// consecutive lines; returns the input unchanged when that would move a corner by more than
/// `max_shift`, make the ring non-simple, or change its area by more than `max_area_change` (25%). `points`
/// in the outline's (local) frame; the outline counter-clockwise (as infer_outline() and regularise_outline()
/// give it). Throws ConfigError (invalid params).
Polygon2 fit_outline_to_points(const Polygon2& outline, const std::vector<Point3>& points,
                               const OutlineFitParams& params = {});

}  // namespace city3d
