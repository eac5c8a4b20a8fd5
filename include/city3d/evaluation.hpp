// Evaluation of a reconstructed model: RMSE of the points to its surface, and validity as a solid
// (closed, 2-manifold, outward, planar faces, no self-intersection), as the paper and the
// regression suite report them.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "city3d/types.hpp"

namespace city3d {

/// Root mean square of the distances from each point to the nearest point of the model surface,
/// metres. `mesh` and `points` must be in the same (local) frame. Faces may be non-convex; they are
/// triangulated internally (ear clipping in the face's plane) and queried with an AABB tree.
/// Throws ReconstructionError when `points` is empty or the mesh has no face with area.
double rmse(const PolygonMesh& mesh, const std::vector<Point3>& points);

/// The distance from each point to the nearest point of the model surface, metres, in the order
/// of `points` (what rmse() squares and averages). Same frame rules and errors as rmse().
std::vector<double> point_distances(const PolygonMesh& mesh, const std::vector<Point3>& points);

/// Triangulates every face of `mesh` by ear clipping in the plane of the face (Newell normal);
/// non-convex faces are handled, and each triangle keeps the face's orientation. A face of n
/// vertices gives n - 2 triangles. Faces with out-of-range indices or fewer than three vertices
/// give none.
std::vector<std::array<std::uint32_t, 3>> triangulate(const PolygonMesh& mesh);

/// What check_validity() found.
struct MeshValidity {
  bool closed = false;                     ///< every directed edge has exactly one opposite
  bool manifold = false;                   ///< no edge in more than two faces, every vertex one fan
  bool outward = false;                    ///< signed volume > 0
  bool planar = false;                     ///< max_planarity_error <= the tolerance
  bool self_intersecting_checked = false;  ///< the self-intersection test ran (closed and manifold)
  bool self_intersects = false;            ///< meaningful when self_intersecting_checked
  double volume = 0.0;                     ///< signed, cubic metres (divergence theorem)
  double max_planarity_error = 0.0;        ///< metres: max vertex distance to its face's Newell plane
  std::size_t faces = 0, vertices = 0;
  std::string problem;  ///< every problem found, "; "-separated; empty if valid

  /// A valid solid: closed, manifold, outward, planar and checked free of self-intersections.
  bool valid() const {
    return closed && manifold && outward && planar && self_intersecting_checked && !self_intersects;
  }
};

/// Checks `mesh` as a solid. Never throws on bad geometry or topology (that is what it reports);
/// out-of-range vertex indices are reported as a problem. planarity_tolerance in metres.
MeshValidity check_validity(const PolygonMesh& mesh, double planarity_tolerance = 0.01);

}  // namespace city3d
