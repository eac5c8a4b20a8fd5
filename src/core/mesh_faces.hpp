// What several modules ask of a mesh's faces (rings of indices into its vertex list): whether the
// indices are in range, Newell's normal, the edge-connected parts (each written as one Solid), and
// whether the faces around a vertex form one fan (union-find: core/union_find.hpp). Private to the library.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

#include "city3d/types.hpp"
#include "core/union_find.hpp"
#include "core/vec.hpp"

namespace city3d::detail {

/// Every index of `face` names one of `vertices`.
inline bool indices_in_range(const std::vector<std::uint32_t>& face, const std::vector<Point3>& vertices) {
  return std::all_of(face.begin(), face.end(), [&](std::uint32_t v) { return v < vertices.size(); });
}

/// Newell's normal of the ring `face` of `vertices`: twice its vector area, robust for non-convex and
/// slightly non-planar polygons. The indices must be in range.
inline Vec newell_normal(const std::vector<Point3>& vertices, const std::vector<std::uint32_t>& face) {
  Vec n{0, 0, 0};
  for (std::size_t i = 0; i < face.size(); ++i) {
    const Point3& a = vertices[face[i]];
    const Point3& b = vertices[face[(i + 1) % face.size()]];
    n.x += (a.y - b.y) * (a.z + b.z);
    n.y += (a.z - b.z) * (a.x + b.x);
    n.z += (a.x - b.x) * (a.y + b.y);
  }
  return n;
}

/// The edge-connected part of each face: faces that share an edge (either direction) are in one part.
/// Parts are numbered 0, 1, ... in order of their first face. Indices need not be in range.
std::vector<std::size_t> edge_connected_parts(const std::vector<std::vector<std::uint32_t>>& faces);

/// How many fans the face corners around one vertex form: each corner is the (previous, next) vertex
/// of a face at that vertex, and corners that share a neighbour are joined. A manifold vertex has one.
std::size_t fans_around(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& corners);

}  // namespace city3d::detail
