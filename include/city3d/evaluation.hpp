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
/// triangulated internally (ear clipping in the face's plane). Each point's nearest triangle is found
/// through a grid of columns in xy; where two triangles are about as near (a point nearest to an edge
/// they share) CGAL's AABB tree decides. The distances are CGAL's closest points' either way.
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

/// Tolerances of the validity check, val3dity's defaults (val3dity 2.6, the validator 3DBAG reports with).
struct ValidityParams {
  double snap_tolerance = 0.001;    ///< metres: vertices closer than this are one vertex (val3dity snap_tol)
  double planarity_distance = 0.01; ///< metres: a vertex farther from its polygon's fitted plane is 203
  double planarity_normals = 20.0;  ///< degrees: two triangles of a polygon whose normals differ more are 204
  /// Throws ConfigError listing every invalid field.
  void validate() const;
};

/// One violated rule of ISO 19107 as val3dity numbers them:
/// 101 TOO_FEW_POINTS, 102 CONSECUTIVE_POINTS_SAME, 104 RING_SELF_INTERSECTION (103 RING_NOT_CLOSED
/// applies to GML only: an index ring is closed by construction),
/// 201 INTERSECTION_RINGS, 202 DUPLICATED_RINGS, 203 NON_PLANAR_POLYGON_DISTANCE_PLANE,
/// 204 NON_PLANAR_POLYGON_NORMALS_DEVIATION, 205 POLYGON_INTERIOR_DISCONNECTED, 206 INNER_RING_OUTSIDE,
/// 207 INNER_RINGS_NESTED, 208 ORIENTATION_RINGS_SAME,
/// 301 TOO_FEW_POLYGONS, 302 SHELL_NOT_CLOSED, 303 NON_MANIFOLD_VERTEX, 304 NON_MANIFOLD_EDGE,
/// 305 MULTIPLE_CONNECTED_COMPONENTS, 306 SHELL_SELF_INTERSECTION, 307 POLYGON_WRONG_ORIENTATION,
/// 309 VERTICES_NOT_USED,
/// 401 INTERSECTION_SHELLS, 402 DUPLICATED_SHELLS, 403 INNER_SHELL_OUTSIDE, 405 WRONG_ORIENTATION_SHELL.
struct ValidityError {
  int code = 0;
  int shell = -1;    ///< shell index, -1 for the solid as a whole
  int face = -1;     ///< polygon index within the shell, -1 for the shell as a whole
  std::string info;  ///< what was measured, e.g. "27.3 degrees"
  /// "204 NON_PLANAR_POLYGON_NORMALS_DEVIATION (shell 0, face 3: 27.3 degrees)".
  std::string text() const;
};

/// val3dity's name of an error code ("RING_SELF_INTERSECTION"), or "UNKNOWN_ERROR".
const char* validity_error_name(int code);

/// A polygon of a solid: rings of vertex indices, the exterior first, then the interior rings (holes).
using SolidPolygon = std::vector<std::vector<std::uint32_t>>;

/// A solid as val3dity sees it: shared vertices, an exterior shell (shells[0], polygons
/// counter-clockwise seen from outside) and optional interior shells (cavities, oriented inward).
struct SolidGeometry {
  std::vector<Point3> vertices;
  std::vector<std::vector<SolidPolygon>> shells;
};

/// Validates `solid` as val3dity does with default options: vertices within snap_tolerance are
/// merged first, then rings and polygons (101-208), then each shell (301-309) when its polygons are
/// valid, then the solid (401-405) when its shells are valid. Never throws on bad geometry; returns
/// every error found, in that order (empty = valid).
std::vector<ValidityError> validate_solid(const SolidGeometry& solid, const ValidityParams& params = {});

/// The edge-connected parts of a mesh, each as the Solid the CityJSON writer writes for it (a model
/// of several parts becomes one Solid per part), in order of their first face.
std::vector<PolygonMesh> mesh_parts(const PolygonMesh& mesh);

/// Validates a model as written: each edge-connected part as one solid (see mesh_parts). Errors
/// carry the part index as their shell.
std::vector<ValidityError> validate_model(const PolygonMesh& mesh, const ValidityParams& params = {});

/// The distinct codes of `errors`, ascending, comma-separated ("104,204"); empty when valid.
std::string validity_codes(const std::vector<ValidityError>& errors);

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
  /// The mesh as one solid (one exterior shell) under val3dity's rules (validate_solid), with the
  /// planarity distance set to planarity_tolerance.
  std::vector<ValidityError> errors;

  /// A valid solid: closed, manifold, outward, planar, checked free of self-intersections, and free
  /// of every val3dity error.
  bool valid() const {
    return closed && manifold && outward && planar && self_intersecting_checked && !self_intersects &&
           errors.empty();
  }
};

/// Checks `mesh` as a solid. Never throws on bad geometry or topology (that is what it reports);
/// out-of-range vertex indices are reported as a problem. planarity_tolerance in metres.
MeshValidity check_validity(const PolygonMesh& mesh, double planarity_tolerance = 0.01);

}  // namespace city3d
