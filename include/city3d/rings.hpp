// Plane geometry of rings and polygons, shared by every module that measures or tests an outline:
// areas, point in ring, distances, the convex hull. Each function is the one formula its callers use,
// so that two modules measuring the same ring get the same bits.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "city3d/types.hpp"

namespace city3d {

/// The signed area of a ring (shoelace formula over the vertices as given), m2; positive when
/// counter-clockwise. For rings in a local frame (near the origin); see twice_signed_area() for
/// world coordinates.
double signed_area(const Ring2& ring);

/// The area of a ring, m2, whatever its orientation.
double ring_area(const Ring2& ring);

/// The area of polygons with holes, m2: outer rings less their holes.
double polygons_area(const std::vector<Polygon2>& polygons);

/// Twice the signed area of a ring (shoelace formula); positive when counter-clockwise. The
/// first vertex is subtracted from every vertex first, which keeps the products small at RD New
/// magnitudes (x ~ 85 000, y ~ 447 000) where they would otherwise cancel catastrophically.
double twice_signed_area(const Ring2& ring);

/// Whether `p` lies inside `ring` (even-odd crossing rule; a point on an edge is either).
bool inside_ring(const Ring2& ring, const Point2& p);

/// Whether two rings come closer than `gap` anywhere: one inside the other, a vertex near the other's
/// edge, or crossing edges.
bool rings_near(const Ring2& a, const Ring2& b, double gap);

/// How many of the points `indices` names lie inside `ring` in plan view.
std::size_t points_inside(const Ring2& ring, const std::vector<std::uint32_t>& indices,
                          const std::vector<Point3>& points);

/// The distance from `p` to the segment from `a` to `b`, metres.
double segment_distance(const Point2& p, const Point2& a, const Point2& b);

/// What tidy_footprint() removed.
struct TidiedFootprint {
  std::size_t merged = 0;  ///< vertices within the merge distance of the vertex before them
  std::size_t spikes = 0;  ///< tips of spikes narrower than the spike width
};

/// Drops from each ring of `polygons` every vertex within `merge_distance` of the vertex before it
/// (two vertices a validator takes for one: 102 CONSECUTIVE_POINTS_SAME), and the tip of every spike
/// narrower than `spike_width`: a vertex whose two neighbours are closer to each other than that while it
/// stands farther from the line between them than they are apart (a sliver no wall can be built on: 104
/// RING_SELF_INTERSECTION once snapped). A gently curved ring of short edges keeps its vertices, and a
/// ring keeps at least 3.
TidiedFootprint tidy_footprint(std::vector<Polygon2>& polygons, double merge_distance, double spike_width);

/// Opens a footprint's pinches: places where two of its rings, or two stretches of one ring, touch or
/// come closer than half of `clearance` (a hole touching its outer ring at a point, two parts meeting
/// at a corner, two holes sharing a vertex: valid polygons in OGC's rules, but every solid extruded
/// from them has an edge of four faces). The vertex that touches moves between its own two edges, away
/// from the ring it touches, until they are `clearance` apart (at most 10 x `clearance`, and a third of
/// its shorter edge). The rings keep their order and orientation, and no edge crosses another. Returns
/// where the vertices were; when a pinch cannot be opened so (a ring that crosses another), the polygons
/// are left as they were and `unopened` (when given) gets the place.
std::vector<Point2> open_pinches(std::vector<Polygon2>& polygons, double clearance,
                                 Point2* unopened = nullptr);

/// The convex hull of `points`, counter-clockwise, without collinear points (monotone chain).
Ring2 convex_hull(std::vector<Point2> points);

}  // namespace city3d
