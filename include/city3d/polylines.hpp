// Polylines: simplifies the edge pixels of a building heightmap into a few polylines with an
// optimal-transport edge-collapse under a Hausdorff bound (paper section 3.2, after de Goes et al. 2011).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "city3d/types.hpp"

namespace city3d {

/// An open or closed polyline in a local metric frame. A closed polyline repeats its first vertex at
/// the end (front() == back() exactly); an open one does not.
using Polyline2 = std::vector<Point2>;

/// True when `p` has at least 4 vertices and its first and last vertices are the same point.
bool is_closed(const Polyline2& p);

/// Parameters of the polyline stage. Distances in metres.
struct PolylineParams {
  /// eps_d: every input pixel lies within this distance of the simplified shape, and every point of
  /// the simplified shape (vertices and edges) lies within it of the pixels. > 0.
  double max_hausdorff = 0.25;
  /// eps_c: stop collapsing when the root-mean-square transport distance of all pixels to the
  /// simplified shape, in pixels (i.e. divided by `resolution`), would exceed this. > 0.
  /// The original City3D code worked in pixel coordinates, hence the unit.
  double max_cost = 2.0;
  /// Pixel size r; 0 = estimate it as the median nearest-neighbour spacing of the pixels. >= 0.
  double resolution = 0.0;
  /// Delaunay edges up to this many pixel sizes long join pixels into chains (2.5 bridges a one-pixel
  /// gap in a Canny contour, including diagonally). >= 1.
  double link_pixels = 2.5;
  /// Connected groups of edges shorter than this in total are dropped as noise (edge filtering). >= 0.
  double min_polyline_length = 1.0;
  /// Move vertices onto the intersection of the lines fitted to their edges' pixels (after each
  /// collapse and at the end), where the Hausdorff bound still holds: sharper corners, fewer vertices.
  bool relocate = true;
  /// Relocation's pull towards a vertex's old position, as a share of its pixels' weight (keeps
  /// near-collinear cases stable). > 0.
  double relocate_pull = 1e-3;
  /// A collapse that breaks the Hausdorff bound with its kept vertex in place tries it at the
  /// intersection of the two remaining edges' lines (a corner a staircase bevelled) only when the sine
  /// of their angle exceeds this (0.17: about 10 degrees). In [0, 1).
  double corner_min_sine = 0.17;
  /// Collapsing and the final relocation repeat at most this many rounds (relocation can unblock
  /// collapses; they stop early when a round collapses nothing). >= 1.
  std::size_t relocate_rounds = 4;

  /// Throws ConfigError listing every invalid field.
  void validate() const;
};

/// Counters of one run, for logging and tests.
struct PolylineStats {
  std::size_t pixels = 0;           ///< distinct input pixels
  std::size_t initial_edges = 0;    ///< short Delaunay edges the simplification started from
  std::size_t collapses = 0;        ///< vertex removals performed
  std::size_t filtered_edges = 0;   ///< edges dropped by the edge filter
  double resolution = 0.0;          ///< pixel size used, metres
  double rms_transport = 0.0;       ///< final root-mean-square transport distance, metres
  double max_pixel_distance = 0.0;  ///< final largest pixel-to-shape distance (before filtering), m
};

/// Extracts polylines from edge pixels (pixel centres, local metric frame).
///
/// Steps: 2D Delaunay triangulation of the pixels; its edges no longer than link_pixels x r form a
/// graph; greedy vertex removal by half-edge collapse, always the one with the smallest increase of
/// the total transport cost, subject to the Hausdorff bound eps_d; edge filtering; chains of edges
/// that carry mass become polylines. Isolated pixels and small groups give no polyline. The result
/// is deterministic (it depends only on the set of pixels, not their order). Fewer than 2 pixels
/// give no polyline. Throws ConfigError for invalid params.
std::vector<Polyline2> extract_polylines(const std::vector<Point2>& edge_pixels, const PolylineParams& params,
                                         PolylineStats* stats = nullptr);

}  // namespace city3d
