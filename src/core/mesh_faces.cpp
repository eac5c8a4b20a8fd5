// The edge-connected parts of a mesh's faces and the fans around a vertex (mesh_faces.hpp).
#include "core/mesh_faces.hpp"

#include <map>
#include <numeric>
#include <utility>

namespace city3d::detail {

std::vector<std::size_t> edge_connected_parts(const std::vector<std::vector<std::uint32_t>>& faces) {
  // Union-find over the faces, joined through the first face seen on each undirected edge.
  UnionFind parts(faces.size());
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::size_t> first_face_of_edge;
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const auto& face = faces[f];
    for (std::size_t k = 0; k < face.size(); ++k) {
      const auto [it, fresh] = first_face_of_edge.emplace(std::minmax(face[k], face[(k + 1) % face.size()]), f);
      if (!fresh) parts.join(f, it->second);
    }
  }
  std::vector<std::size_t> part(faces.size());
  std::map<std::size_t, std::size_t> part_of_root;
  for (std::size_t f = 0; f < faces.size(); ++f)
    part[f] = part_of_root.emplace(parts.find(f), part_of_root.size()).first->second;
  return part;
}

std::size_t fans_around(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& corners) {
  UnionFind fans_of(corners.size());
  std::map<std::uint32_t, std::size_t> with;  // the first corner with each neighbour
  for (std::size_t c = 0; c < corners.size(); ++c)
    for (std::uint32_t w : {corners[c].first, corners[c].second}) {
      const auto [it, fresh] = with.emplace(w, c);
      if (!fresh) fans_of.join(c, it->second);
    }
  std::size_t fans = 0;
  for (std::size_t c = 0; c < corners.size(); ++c) fans += fans_of.find(c) == c;
  return fans;
}

}  // namespace city3d::detail
