// Topological and geometric validity of a polygon mesh: closed, 2-manifold, outward oriented.
#pragma once

#include <cstddef>

#include "city3d/types.hpp"

namespace city3d {

/// What check_mesh() found. A valid solid has valid() == true.
struct MeshCheck {
  std::size_t vertex_count = 0;
  std::size_t face_count = 0;
  std::size_t edge_count = 0;             ///< undirected edges
  std::size_t shell_count = 0;            ///< connected components of faces joined by shared edges
  std::size_t boundary_edges = 0;         ///< directed edges whose opposite is missing
  std::size_t non_manifold_edges = 0;     ///< undirected edges used by more than two face sides, or
                                          ///< the same directed edge used twice (inconsistent orientation)
  std::size_t non_manifold_vertices = 0;  ///< vertices whose faces form more than one fan
  std::size_t degenerate_faces = 0;  ///< < 3 vertices, a repeated vertex, an out-of-range index, or no area
  double signed_volume = 0.0;        ///< cubic metres, divergence theorem over fan triangles
  double area = 0.0;                 ///< square metres, sum of face areas (Newell)

  bool closed = false;    ///< every directed edge has its opposite exactly once
  bool manifold = false;  ///< no non-manifold edge or vertex
  bool outward = false;   ///< signed_volume > 0 (meaningful when closed)

  bool valid() const { return closed && manifold && outward && degenerate_faces == 0; }
};

/// Checks `mesh`. Faces are vertex-index loops, counter-clockwise seen from outside. Never throws
/// on bad topology (that is what it reports); out-of-range indices count as degenerate faces.
MeshCheck check_mesh(const PolygonMesh& mesh);

/// check_mesh(mesh).signed_volume, the same number, without the topology checks (faces with
/// out-of-range indices are left out, as there).
double signed_volume(const PolygonMesh& mesh);

}  // namespace city3d
