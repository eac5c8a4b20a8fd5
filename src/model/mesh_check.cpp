// Mesh validity: directed-edge pairing (closed, consistently oriented), edge and vertex manifoldness,
// shells, degenerate faces, and the signed volume that tells outward from inward orientation.
#include "city3d/mesh_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <tuple>
#include <vector>

#include "core/mesh_faces.hpp"
#include "core/vec.hpp"

namespace city3d {
namespace {

using detail::cross;
using detail::dot;
using detail::indices_in_range;
using detail::sub;
using detail::UnionFind;
using detail::Vec;

std::uint64_t key(std::uint32_t a, std::uint32_t b) { return (std::uint64_t{a} << 32) | b; }

// The centre of the box (the origin for an empty one): the volume sum's reference point.
Point3 centre_of(const Box3& bounds) {
  return bounds.empty() ? Point3{}
                        : Point3{0.5 * (bounds.min.x + bounds.max.x), 0.5 * (bounds.min.y + bounds.max.y),
                                 0.5 * (bounds.min.z + bounds.max.z)};
}

// Adds the signed volume of the tetrahedra from `centre` to the fan triangles of `face` to `volume`.
void add_fan_volume(const std::vector<Point3>& vertices, const std::vector<std::uint32_t>& face,
                    const Point3& centre, double& volume) {
  for (std::size_t k = 1; k + 1 < face.size(); ++k) {
    const Vec a = sub(vertices[face[0]], centre);
    const Vec b = sub(vertices[face[k]], centre);
    const Vec c = sub(vertices[face[k + 1]], centre);
    volume += dot(a, cross(b, c)) / 6.0;
  }
}

}  // namespace

MeshCheck check_mesh(const PolygonMesh& mesh) {
  MeshCheck check;
  const auto& vertices = mesh.vertices;
  check.vertex_count = vertices.size();
  check.face_count = mesh.faces.size();

  // Scale for the zero-area test, and a reference point near the mesh so that the volume sum does
  // not lose digits to large coordinates.
  Box3 bounds;
  for (const Point3& v : vertices) bounds.add(v);
  const Point3 centre = centre_of(bounds);
  const double diagonal2 =
      bounds.empty() ? 0.0 : dot(sub(bounds.max, bounds.min), sub(bounds.max, bounds.min));
  const double min_area = 1e-12 * std::max(1.0, diagonal2);

  // Directed edges (a << 32 | b) with their face; faces with bad indices are left out.
  std::vector<std::pair<std::uint64_t, std::size_t>> directed;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& face = mesh.faces[f];
    if (!indices_in_range(face, vertices)) {
      ++check.degenerate_faces;
      continue;
    }
    std::vector<std::uint32_t> sorted(face);
    std::sort(sorted.begin(), sorted.end());
    const bool repeated = std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end();

    const Vec normal = detail::newell_normal(vertices, face);  // twice the vector area
    for (std::size_t k = 0; k < face.size(); ++k) directed.push_back({key(face[k], face[(k + 1) % face.size()]), f});
    const double area = 0.5 * std::sqrt(dot(normal, normal));
    check.area += area;
    if (face.size() < 3 || repeated || area <= min_area) ++check.degenerate_faces;

    add_fan_volume(vertices, face, centre, check.signed_volume);
  }

  std::sort(directed.begin(), directed.end());
  auto count_of = [&](std::uint64_t k) {
    auto range = std::equal_range(directed.begin(), directed.end(), std::make_pair(k, std::size_t{0}),
                                  [](const auto& l, const auto& r) { return l.first < r.first; });
    return static_cast<std::size_t>(range.second - range.first);
  };

  // Edge pairing, manifold edges and shells in one pass over the distinct directed edges.
  UnionFind shells(mesh.faces.size());
  bool every_edge_paired_once = true;
  for (std::size_t i = 0; i < directed.size();) {
    std::size_t j = i;
    while (j < directed.size() && directed[j].first == directed[i].first) ++j;
    const std::uint32_t a = static_cast<std::uint32_t>(directed[i].first >> 32);
    const std::uint32_t b = static_cast<std::uint32_t>(directed[i].first & 0xFFFFFFFFu);
    const std::size_t here = j - i;
    const std::size_t opposite = count_of(key(b, a));
    if (opposite == 0) check.boundary_edges += here;
    if (opposite != 1 || here != 1) every_edge_paired_once = false;
    if (a < b || opposite == 0) {  // count each undirected edge once
      ++check.edge_count;
      if (here + opposite > 2 || here > 1 || opposite > 1) ++check.non_manifold_edges;
    }
    for (std::size_t k = i + 1; k < j; ++k) shells.join(directed[k].second, directed[i].second);
    if (opposite > 0) {
      auto it = std::lower_bound(directed.begin(), directed.end(), std::make_pair(key(b, a), std::size_t{0}));
      shells.join(it->second, directed[i].second);
    }
    i = j;
  }
  for (std::size_t f = 0; f < mesh.faces.size(); ++f)
    if (shells.find(f) == f) ++check.shell_count;

  // Vertex manifoldness: the face corners around a vertex (previous, next) must chain into a single
  // fan; corner (p, v, n) is followed by the corner whose previous vertex is n.
  struct Corner {
    std::uint32_t vertex, previous, next;
  };
  std::vector<Corner> corners;
  for (const auto& face : mesh.faces) {
    if (face.size() < 3 || !indices_in_range(face, vertices)) continue;
    for (std::size_t k = 0; k < face.size(); ++k)
      corners.push_back({face[k], face[(k + face.size() - 1) % face.size()], face[(k + 1) % face.size()]});
  }
  std::sort(corners.begin(), corners.end(), [](const Corner& l, const Corner& r) {
    return std::tie(l.vertex, l.previous, l.next) < std::tie(r.vertex, r.previous, r.next);
  });
  std::vector<bool> visited(corners.size(), false);
  for (std::size_t i = 0; i < corners.size();) {
    std::size_t j = i;
    while (j < corners.size() && corners[j].vertex == corners[i].vertex) ++j;
    std::size_t fans = 0;
    for (std::size_t start = i; start < j; ++start) {
      if (visited[start]) continue;
      ++fans;
      // Walk forward from `start`, then backward, marking the corners of this fan.
      for (std::size_t c = start; !visited[c];) {
        visited[c] = true;
        auto it = std::lower_bound(corners.begin() + static_cast<std::ptrdiff_t>(i),
                                   corners.begin() + static_cast<std::ptrdiff_t>(j), corners[c].next,
                                   [](const Corner& l, std::uint32_t p) { return l.previous < p; });
        if (it == corners.begin() + static_cast<std::ptrdiff_t>(j) || it->previous != corners[c].next) break;
        c = static_cast<std::size_t>(it - corners.begin());
      }
      for (std::size_t c = start;;) {
        const std::uint32_t previous = corners[c].previous;
        std::size_t found = j;
        for (std::size_t k = i; k < j; ++k)
          if (corners[k].next == previous) {
            found = k;
            break;
          }
        if (found == j || visited[found]) break;
        visited[found] = true;
        c = found;
      }
    }
    if (fans > 1) ++check.non_manifold_vertices;
    i = j;
  }

  check.closed = !directed.empty() && every_edge_paired_once;
  check.manifold = check.non_manifold_edges == 0 && check.non_manifold_vertices == 0;
  check.outward = check.signed_volume > 0.0;
  return check;
}

double signed_volume(const PolygonMesh& mesh) {
  Box3 bounds;
  for (const Point3& v : mesh.vertices) bounds.add(v);
  const Point3 centre = centre_of(bounds);
  double volume = 0.0;
  for (const auto& face : mesh.faces)
    if (indices_in_range(face, mesh.vertices)) add_fan_volume(mesh.vertices, face, centre, volume);
  return volume;
}

}  // namespace city3d
