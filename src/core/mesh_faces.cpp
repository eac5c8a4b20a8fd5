// The edge-connected parts of a mesh's faces and the fans around a vertex (mesh_faces.hpp).
#include "core/mesh_faces.hpp"

#include <map>
#include <numeric>
#include <utility>

namespace city3d::detail {

std::vector<std::size_t> edge_connected_parts(const std::vector<std::vector<std::uint32_t>>& faces) {
  // Union-find over the faces, joined through the first face seen on each undirected edge.
  std::vector<std::size_t> parent(faces.size());
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  const auto find = [&parent](std::size_t f) {
    while (parent[f] != f) f = parent[f] = parent[parent[f]];
    return f;
  };
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::size_t> first_face_of_edge;
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const auto& face = faces[f];
    for (std::size_t k = 0; k < face.size(); ++k) {
      const auto [it, fresh] = first_face_of_edge.emplace(std::minmax(face[k], face[(k + 1) % face.size()]), f);
      if (!fresh) parent[find(f)] = find(it->second);
    }
  }
  std::vector<std::size_t> part(faces.size());
  std::map<std::size_t, std::size_t> part_of_root;
  for (std::size_t f = 0; f < faces.size(); ++f)
    part[f] = part_of_root.emplace(find(f), part_of_root.size()).first->second;
  return part;
}

std::size_t fans_around(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& corners) {
  std::vector<std::size_t> up(corners.size());
  std::iota(up.begin(), up.end(), std::size_t{0});
  const auto root = [&up](std::size_t i) {
    while (up[i] != i) i = up[i] = up[up[i]];
    return i;
  };
  std::map<std::uint32_t, std::size_t> with;  // the first corner with each neighbour
  for (std::size_t c = 0; c < corners.size(); ++c)
    for (std::uint32_t w : {corners[c].first, corners[c].second}) {
      const auto [it, fresh] = with.emplace(w, c);
      if (!fresh) up[root(c)] = root(it->second);
    }
  std::size_t fans = 0;
  for (std::size_t c = 0; c < corners.size(); ++c) fans += root(c) == c;
  return fans;
}

}  // namespace city3d::detail
