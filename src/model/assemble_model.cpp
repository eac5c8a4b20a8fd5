// Model assembly: selected candidate faces -> welded, oriented, merged and validated polygon mesh.
// Topology is by vertex identity throughout; coordinates are used only for orientation (volume),
// turning angles when a merged boundary touches itself, and the collinearity test.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/mesh_check.hpp"
#include "city3d/model.hpp"
#include "core/mesh_faces.hpp"
#include "core/vec.hpp"

namespace city3d {

void AssembleParams::validate() const {
  std::string errors;
  if (!(collinear_tolerance > 0.0)) errors += " collinear_tolerance must be > 0;";
  if (!(planarity_tolerance > 0.0)) errors += " planarity_tolerance must be > 0;";
  if (!errors.empty()) {
    errors.pop_back();
    throw ConfigError("model: invalid parameters:" + errors);
  }
}

namespace {

using Loop = std::vector<std::uint32_t>;
using EdgeKey = std::pair<std::uint32_t, std::uint32_t>;

EdgeKey undirected(std::uint32_t a, std::uint32_t b) { return a < b ? EdgeKey{a, b} : EdgeKey{b, a}; }

using detail::cross;
using detail::dot;
using detail::newell_normal;
using detail::norm;
using detail::sub;
using detail::UnionFind;
using detail::Vec;

// Largest distance of a loop's vertices from the plane through their mean with Newell's normal.
double planarity_error(const std::vector<Point3>& vs, const Loop& loop) {
  const Vec n = newell_normal(vs, loop);
  const double length = norm(n);
  if (!(length > 0.0)) return std::numeric_limits<double>::infinity();
  Vec mean{0, 0, 0};
  for (auto v : loop) mean = {mean.x + vs[v].x, mean.y + vs[v].y, mean.z + vs[v].z};
  const double k = 1.0 / static_cast<double>(loop.size());
  const Point3 c{mean.x * k, mean.y * k, mean.z * k};
  double worst = 0.0;
  for (auto v : loop) worst = std::max(worst, std::abs(dot(sub(vs[v], c), n)) / length);
  return worst;
}

// Signed volume of the closed loops (divergence theorem over fan triangles, about `ref`).
double signed_volume(const std::vector<Point3>& vs, const std::vector<Loop>& loops, const Point3& ref) {
  double volume = 0.0;
  for (const Loop& loop : loops) {
    for (std::size_t i = 1; i + 1 < loop.size(); ++i) {
      const Vec a = sub(vs[loop[0]], ref), b = sub(vs[loop[i]], ref), c = sub(vs[loop[i + 1]], ref);
      volume += dot(a, cross(b, c)) / 6.0;
    }
  }
  return volume;
}

// Chains the directed boundary edges of a merged region into loops. At a vertex with several
// outgoing edges the leftmost turn (seen along `normal`) is taken, which keeps regions that only
// touch at a vertex in separate loops.
std::vector<Loop> chain_loops(const std::vector<Point3>& vs, std::vector<EdgeKey> directed, const Vec& normal) {
  std::sort(directed.begin(), directed.end());
  std::vector<bool> used(directed.size(), false);
  auto outgoing = [&](std::uint32_t v) {
    std::vector<std::size_t> out;
    auto it = std::lower_bound(directed.begin(), directed.end(), EdgeKey{v, 0});
    for (; it != directed.end() && it->first == v; ++it) {
      const auto i = static_cast<std::size_t>(it - directed.begin());
      if (!used[i]) out.push_back(i);
    }
    return out;
  };
  std::vector<Loop> loops;
  for (std::size_t start = 0; start < directed.size(); ++start) {
    if (used[start]) continue;
    Loop loop;
    std::size_t cur = start;
    for (std::size_t guard = 0; guard <= directed.size(); ++guard) {
      used[cur] = true;
      loop.push_back(directed[cur].first);
      const std::uint32_t v = directed[cur].second;
      if (v == directed[start].first) break;
      const auto out = outgoing(v);
      if (out.empty()) return {};  // open chain: the caller keeps the original faces
      std::size_t best = out[0];
      if (out.size() > 1) {
        const Vec in = sub(vs[v], vs[directed[cur].first]);
        double best_angle = -std::numeric_limits<double>::infinity();
        for (std::size_t i : out) {
          const Vec o = sub(vs[directed[i].second], vs[v]);
          const double angle = std::atan2(dot(cross(in, o), normal), dot(in, o));
          if (angle > best_angle) {
            best_angle = angle;
            best = i;
          }
        }
      }
      cur = best;
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

std::string edge_name(const EdgeKey& e) { return std::to_string(e.first) + "-" + std::to_string(e.second); }

}  // namespace

PolygonMesh assemble_model(const CandidateFaces& candidates, const std::vector<bool>& selected,
                           const AssembleParams& params, std::vector<SurfaceType>* surfaces) {
  params.validate();
  const auto& faces = candidates.faces;
  const auto& vs = candidates.vertices;
  if (selected.size() != faces.size())
    throw ConfigError("model: " + std::to_string(selected.size()) + " selection flags for " +
                      std::to_string(faces.size()) + " candidate faces");

  struct Face {
    Loop loop;
    std::uint32_t plane_id;
    FaceKind kind;
  };
  std::vector<Face> model;
  for (std::size_t i = 0; i < faces.size(); ++i)
    if (selected[i]) model.push_back({faces[i].vertices, faces[i].plane_id, faces[i].kind});
  if (model.empty()) throw ReconstructionError(ReconstructionStage::model, "no face selected");

  // 1. Weld: every undirected edge in exactly two selected faces.
  struct Use {
    std::size_t face;
    bool forward;  // traversed from the smaller to the larger vertex id
  };
  std::map<EdgeKey, std::vector<Use>> uses;
  for (std::size_t f = 0; f < model.size(); ++f) {
    const Loop& l = model[f].loop;
    for (std::size_t i = 0; i < l.size(); ++i) {
      const std::uint32_t a = l[i], b = l[(i + 1) % l.size()];
      uses[undirected(a, b)].push_back({f, a < b});
    }
  }
  for (const auto& [edge, list] : uses)
    if (list.size() != 2)
      throw ReconstructionError(ReconstructionStage::model, "edge " + edge_name(edge) + " is used by " + std::to_string(list.size()) +
                                " selected faces (need 2)");

  // 2. Orient: neighbours must traverse their shared edge in opposite directions.
  std::vector<std::vector<std::pair<std::size_t, bool>>> adjacent(model.size());  // (face, same direction)
  for (const auto& [edge, list] : uses) {
    const bool same = list[0].forward == list[1].forward;
    adjacent[list[0].face].push_back({list[1].face, same});
    adjacent[list[1].face].push_back({list[0].face, same});
  }
  std::vector<int> flip(model.size(), -1);
  std::vector<std::size_t> shell(model.size(), 0);
  std::size_t shell_count = 0;
  for (std::size_t s = 0; s < model.size(); ++s) {
    if (flip[s] >= 0) continue;
    flip[s] = 0;
    std::vector<std::size_t> queue{s};
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const std::size_t f = queue[q];
      shell[f] = shell_count;
      for (const auto& [g, same] : adjacent[f]) {
        const int want = same ? 1 - flip[f] : flip[f];
        if (flip[g] < 0) {
          flip[g] = want;
          queue.push_back(g);
        } else if (flip[g] != want) {
          throw ReconstructionError(ReconstructionStage::model, "the selected faces are not orientable (a Moebius-like strip)");
        }
      }
    }
    ++shell_count;
  }
  for (std::size_t f = 0; f < model.size(); ++f)
    if (flip[f] == 1) std::reverse(model[f].loop.begin(), model[f].loop.end());
  Point3 ref{0, 0, 0};
  for (const auto& p : vs) ref = {ref.x + p.x, ref.y + p.y, ref.z + p.z};
  if (!vs.empty()) {
    const double n = static_cast<double>(vs.size());
    ref = {ref.x / n, ref.y / n, ref.z / n};
  }
  for (std::size_t s = 0; s < shell_count; ++s) {
    std::vector<Loop> loops;
    for (std::size_t f = 0; f < model.size(); ++f)
      if (shell[f] == s) loops.push_back(model[f].loop);
    if (signed_volume(vs, loops, ref) < 0.0)
      for (std::size_t f = 0; f < model.size(); ++f)
        if (shell[f] == s) std::reverse(model[f].loop.begin(), model[f].loop.end());
  }

  // 3. Merge adjacent coplanar faces.
  if (params.merge_coplanar) {
    UnionFind coplanar(model.size());
    for (const auto& [edge, list] : uses) {
      if (model[list[0].face].plane_id != model[list[1].face].plane_id) continue;
      coplanar.join_to_smaller(list[0].face, list[1].face);
    }
    std::vector<Face> merged;
    std::vector<std::vector<std::size_t>> groups(model.size());
    for (std::size_t f = 0; f < model.size(); ++f) groups[coplanar.find(f)].push_back(f);
    for (const auto& group : groups) {
      if (group.empty()) continue;
      if (group.size() == 1) {
        merged.push_back(model[group[0]]);
        continue;
      }
      std::map<EdgeKey, int> count;  // directed edges; an interior edge appears once each way
      Vec normal{0, 0, 0};
      for (std::size_t f : group) {
        const Loop& l = model[f].loop;
        const Vec n = newell_normal(vs, l);
        normal = {normal.x + n.x, normal.y + n.y, normal.z + n.z};
        for (std::size_t i = 0; i < l.size(); ++i) ++count[{l[i], l[(i + 1) % l.size()]}];
      }
      std::vector<EdgeKey> boundary;
      for (const auto& [e, c] : count)
        if (!count.count({e.second, e.first})) boundary.push_back(e);
      const auto loops = chain_loops(vs, boundary, normal);
      // One simple loop: the merged polygon. A loop that comes back to a vertex (the region touches
      // itself there, around a hole that reaches its boundary) is not a simple polygon.
      Loop sorted = loops.empty() ? Loop{} : loops[0];
      std::sort(sorted.begin(), sorted.end());
      const bool simple = std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end();
      if (loops.size() == 1 && loops[0].size() >= 3 && simple &&
          planarity_error(vs, loops[0]) <= params.planarity_tolerance) {
        merged.push_back({loops[0], model[group[0]].plane_id, model[group[0]].kind});
      } else {
        for (std::size_t f : group) merged.push_back(model[f]);  // hole or pinch: keep the simple pieces
      }
    }
    model = std::move(merged);
  }

  // 4. Remove collinear vertices that only two faces share and that have exactly two neighbours,
  // the smallest vertex first, one at a time. Removing a vertex changes the neighbours of its two
  // neighbours only, and shortens its two faces, so only those vertices are looked at again (a
  // model of thousands of vertices, most of them on straight wall edges, is not rescanned per removal).
  {
    std::map<std::uint32_t, std::vector<std::size_t>> in_faces;  // a face per occurrence in a loop
    for (std::size_t f = 0; f < model.size(); ++f)
      for (std::uint32_t v : model[f].loop) in_faces[v].push_back(f);
    std::map<std::uint32_t, std::vector<std::uint32_t>> neighbours;  // sorted, distinct
    const auto find_neighbours = [&](std::uint32_t v) {
      std::vector<std::uint32_t>& list = neighbours[v];
      list.clear();
      for (std::size_t f : in_faces[v]) {
        const Loop& l = model[f].loop;
        for (std::size_t i = 0; i < l.size(); ++i)
          if (l[i] == v) {
            list.push_back(l[(i + l.size() - 1) % l.size()]);
            list.push_back(l[(i + 1) % l.size()]);
          }
      }
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
    };
    for (const auto& entry : in_faces) find_neighbours(entry.first);
    const auto removable = [&](std::uint32_t v) {
      const std::vector<std::uint32_t>& list = neighbours[v];
      const std::vector<std::size_t>& faces_of_v = in_faces[v];
      if (list.size() != 2 || faces_of_v.size() != 2) return false;
      const Point3& a = vs[list[0]];
      const Point3& b = vs[list[1]];
      const Point3& p = vs[v];
      const Vec ab = sub(b, a), ap = sub(p, a);
      const double len = norm(ab);
      if (len <= 0.0) return false;
      const double t = dot(ap, ab) / (len * len);
      if (t <= 0.0 || t >= 1.0 || norm(cross(ab, ap)) / len > params.collinear_tolerance) return false;
      for (std::size_t f : faces_of_v)
        if (model[f].loop.size() <= 3) return false;
      return true;
    };
    std::set<std::uint32_t> ready;
    for (const auto& entry : in_faces)
      if (removable(entry.first)) ready.insert(entry.first);
    while (!ready.empty()) {
      const std::uint32_t v = *ready.begin();
      const std::vector<std::uint32_t> ends = neighbours[v];
      const std::vector<std::size_t> faces_of_v = in_faces[v];
      for (std::size_t f : faces_of_v) {
        Loop& l = model[f].loop;
        l.erase(std::find(l.begin(), l.end(), v));
      }
      in_faces.erase(v);
      neighbours.erase(v);
      ready.erase(v);
      for (std::uint32_t u : ends) find_neighbours(u);
      std::vector<std::uint32_t> again = ends;
      for (std::size_t f : faces_of_v) again.insert(again.end(), model[f].loop.begin(), model[f].loop.end());
      for (std::uint32_t u : again) {
        if (removable(u))
          ready.insert(u);
        else
          ready.erase(u);
      }
    }
  }

  // 5. Compact the vertices and validate.
  PolygonMesh mesh;
  std::vector<std::uint32_t> index(vs.size(), std::numeric_limits<std::uint32_t>::max());
  for (const Face& f : model) {
    std::vector<std::uint32_t> out;
    for (std::uint32_t v : f.loop) {
      if (index[v] == std::numeric_limits<std::uint32_t>::max()) {
        index[v] = static_cast<std::uint32_t>(mesh.vertices.size());
        mesh.vertices.push_back(vs[v]);
      }
      out.push_back(index[v]);
    }
    mesh.faces.push_back(std::move(out));
  }
  if (surfaces) {
    surfaces->clear();
    for (const Face& f : model)
      surfaces->push_back(f.kind == FaceKind::roof   ? SurfaceType::roof
                          : f.kind == FaceKind::wall ? SurfaceType::wall
                                                     : SurfaceType::ground);
  }
  const MeshCheck check = check_mesh(mesh);
  if (!check.valid()) {
    std::ostringstream message;
    message << "invalid mesh (" << mesh.faces.size() << " faces):";
    if (!check.closed) message << " not closed, " << check.boundary_edges << " boundary edges;";
    if (!check.manifold)
      message << " not manifold, " << check.non_manifold_edges << " edges and " << check.non_manifold_vertices
              << " vertices;";
    if (check.degenerate_faces) message << " " << check.degenerate_faces << " degenerate faces;";
    if (!check.outward) message << " volume " << check.signed_volume << " m3 <= 0;";
    throw ReconstructionError(ReconstructionStage::model, message.str());
  }
  return mesh;
}

}  // namespace city3d
