// Face hypothesis, step 4: the candidate faces. Every cell is lifted onto each of its roof planes
// (a roof face) and onto the floor (a floor face); over every arrangement edge, the vertical strip
// between the levels of the cells on its two sides is cut into wall faces. Vertices are identified by
// (xy position, height cluster), never by comparing 3D coordinates, so faces weld exactly; faces with
// an edge no other face has could never close and are pruned.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <map>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "city3d/error.hpp"
#include "hypothesis/steps.hpp"

namespace city3d::detail {
namespace {

// The vertices above one xy position (an arrangement vertex or a station inside an edge): the
// levels through it, clustered by height; column holds the vertex ids from bottom to top.
struct Column {
  std::vector<int> levels;             // ascending level id
  std::vector<std::uint32_t> cluster;  // per entry of levels: index into column
  std::vector<std::uint32_t> column;   // vertex ids, ascending height

  std::uint32_t cluster_of(int level) const {
    const auto it = std::lower_bound(levels.begin(), levels.end(), level);
    return cluster[static_cast<std::size_t>(it - levels.begin())];
  }
  std::uint32_t vertex_of(int level) const { return column[cluster_of(level)]; }
};

Column make_column(const Levels& lv, std::vector<int> levels, double x, double y, double tolerance,
                   std::vector<Point3>& vertices) {
  Column col;
  std::sort(levels.begin(), levels.end());
  levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
  std::vector<std::pair<double, int>> by_height;
  for (int l : levels) by_height.emplace_back(lv.height(l, x, y), l);
  std::sort(by_height.begin(), by_height.end());
  col.levels = levels;
  col.cluster.assign(levels.size(), 0);
  std::size_t i = 0;
  while (i < by_height.size()) {
    std::size_t j = i + 1;
    while (j < by_height.size() && by_height[j].first - by_height[j - 1].first < tolerance) ++j;
    double z = 0.0;
    for (std::size_t k = i; k < j; ++k) z += by_height[k].first;
    z /= static_cast<double>(j - i);
    const auto cluster = static_cast<std::uint32_t>(col.column.size());
    col.column.push_back(static_cast<std::uint32_t>(vertices.size()));
    vertices.push_back({x, y, z});
    for (std::size_t k = i; k < j; ++k) {
      const auto pos = std::lower_bound(levels.begin(), levels.end(), by_height[k].second) - levels.begin();
      col.cluster[static_cast<std::size_t>(pos)] = cluster;
    }
    i = j;
  }
  return col;
}

struct EdgeStrip {
  std::vector<int> levels;       // H(e)
  std::vector<double> stations;  // metres from u; front 0, back length
  std::vector<Column> interior;  // columns at stations 1..n-2
};

}  // namespace

std::vector<std::vector<std::uint32_t>> lift_cells(const PlainArrangement& arr,
                                                   const std::vector<std::vector<int>>& cell_planes,
                                                   const Levels& lv, double vertex_merge_tolerance,
                                                   CandidateFaces& out) {
  const auto R = static_cast<std::size_t>(lv.floor());
  const std::size_t cell_count = arr.cells.size();
  const int F = lv.floor();

  // Levels per edge and per vertex; stations where levels cross inside an edge.
  const double tol = vertex_merge_tolerance;
  std::vector<Point3> vertices;
  std::vector<EdgeStrip> strips(arr.edges.size());
  std::vector<std::vector<int>> vertex_levels(arr.vertices.size(), std::vector<int>{F});
  for (std::size_t e = 0; e < arr.edges.size(); ++e) {
    const auto& edge = arr.edges[e];
    auto& levels = strips[e].levels;
    if (edge.left >= 0) levels = cell_planes[static_cast<std::size_t>(edge.left)];
    if (edge.right >= 0)
      levels.insert(levels.end(), cell_planes[static_cast<std::size_t>(edge.right)].begin(),
                    cell_planes[static_cast<std::size_t>(edge.right)].end());
    if (edge.left < 0 || edge.right < 0) levels.push_back(F);
    std::sort(levels.begin(), levels.end());
    levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
    for (std::uint32_t v : {edge.u, edge.w})
      vertex_levels[v].insert(vertex_levels[v].end(), levels.begin(), levels.end());
  }
  std::vector<Column> vertex_columns;
  for (std::size_t v = 0; v < arr.vertices.size(); ++v)
    vertex_columns.push_back(
        make_column(lv, vertex_levels[v], arr.vertices[v].x, arr.vertices[v].y, tol, vertices));

  for (std::size_t e = 0; e < arr.edges.size(); ++e) {
    const auto& edge = arr.edges[e];
    auto& strip = strips[e];
    const Point2 a = arr.vertices[edge.u], b = arr.vertices[edge.w];
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    std::vector<double> crossings;
    for (std::size_t i = 0; i < strip.levels.size(); ++i) {
      for (std::size_t j = i + 1; j < strip.levels.size(); ++j) {
        const double d0 = lv.height(strip.levels[i], a.x, a.y) - lv.height(strip.levels[j], a.x, a.y);
        const double d1 = lv.height(strip.levels[i], b.x, b.y) - lv.height(strip.levels[j], b.x, b.y);
        if (std::abs(d0) < tol || std::abs(d1) < tol || (d0 > 0) == (d1 > 0)) continue;
        const double t = len * d0 / (d0 - d1);
        if (t > 1e-6 && t < len - 1e-6) crossings.push_back(t);
      }
    }
    std::sort(crossings.begin(), crossings.end());
    strip.stations.push_back(0.0);
    for (std::size_t i = 0; i < crossings.size();) {
      std::size_t j = i + 1;
      while (j < crossings.size() && crossings[j] - crossings[j - 1] < 1e-6) ++j;
      strip.stations.push_back(std::accumulate(crossings.begin() + static_cast<std::ptrdiff_t>(i),
                                               crossings.begin() + static_cast<std::ptrdiff_t>(j), 0.0) /
                               static_cast<double>(j - i));
      i = j;
    }
    strip.stations.push_back(len);
    for (std::size_t k = 1; k + 1 < strip.stations.size(); ++k) {
      const double t = strip.stations[k] / len;
      strip.interior.push_back(
          make_column(lv, strip.levels, a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), tol, vertices));
    }
  }
  auto column_at = [&](std::size_t e, std::size_t k) -> const Column& {
    const auto& strip = strips[e];
    if (k == 0) return vertex_columns[arr.edges[e].u];
    if (k + 1 == strip.stations.size()) return vertex_columns[arr.edges[e].w];
    return strip.interior[k - 1];
  };

  // Roof and floor faces over every cell.
  std::vector<CandidateFace> faces;
  // A face that walks along the level of `level` over edge e (in direction `forward`), from the
  // start vertex up to (not including) the end vertex, visiting the stations of e.
  auto walk_edge = [&](std::size_t e, bool forward, int level, std::vector<std::uint32_t>& loop) {
    const auto& strip = strips[e];
    const std::size_t n = strip.stations.size();
    const bool on_strip = std::binary_search(strip.levels.begin(), strip.levels.end(), level);
    loop.push_back(column_at(e, forward ? 0 : n - 1).vertex_of(level));
    if (!on_strip) return;
    for (std::size_t i = 1; i + 1 < n; ++i) loop.push_back(column_at(e, forward ? i : n - 1 - i).vertex_of(level));
  };
  for (std::size_t c = 0; c < cell_count; ++c) {
    const auto& cell = arr.cells[c];
    for (int r : cell_planes[c]) {
      CandidateFace f;
      f.kind = FaceKind::roof;
      f.source = r;
      f.plane_id = static_cast<std::uint32_t>(r);
      f.cell_or_edge = static_cast<std::uint32_t>(c);
      for (const auto& [e, forward] : cell.loop) walk_edge(e, forward, r, f.vertices);
      faces.push_back(std::move(f));
    }
    CandidateFace floor;
    floor.kind = FaceKind::floor;
    floor.plane_id = static_cast<std::uint32_t>(R);
    floor.cell_or_edge = static_cast<std::uint32_t>(c);
    for (const auto& [e, forward] : cell.loop) walk_edge(e, forward, F, floor.vertices);
    std::reverse(floor.vertices.begin(), floor.vertices.end());  // faces down
    faces.push_back(std::move(floor));
  }

  for (std::size_t e = 0; e < arr.edges.size(); ++e) {
    const auto& strip = strips[e];
    const auto& edge = arr.edges[e];
    const std::size_t n = strip.stations.size();
    // Pieces: between consecutive tracks over each interval between stations.
    struct Piece {
      std::size_t k;                      // interval k .. k+1
      std::uint32_t lo0, lo1, hi0, hi1;   // cluster indices at stations k and k+1
    };
    std::vector<Piece> pieces;
    for (std::size_t k = 0; k + 1 < n; ++k) {
      const Column& c0 = column_at(e, k);
      const Column& c1 = column_at(e, k + 1);
      std::vector<std::pair<double, std::pair<std::uint32_t, std::uint32_t>>> tracks;
      for (int l : strip.levels) {
        const std::uint32_t a = c0.cluster_of(l), b = c1.cluster_of(l);
        tracks.push_back({vertices[c0.column[a]].z + vertices[c1.column[b]].z, {a, b}});
      }
      std::sort(tracks.begin(), tracks.end());
      tracks.erase(std::unique(tracks.begin(), tracks.end(),
                               [](const auto& x, const auto& y) { return x.second == y.second; }),
                   tracks.end());
      for (std::size_t i = 0; i + 1 < tracks.size(); ++i)
        pieces.push_back({k, tracks[i].second.first, tracks[i].second.second, tracks[i + 1].second.first,
                          tracks[i + 1].second.second});
    }
    // Join pieces across interior stations where the vertical side between them has length.
    std::vector<std::size_t> next(pieces.size(), pieces.size());
    std::vector<bool> has_prev(pieces.size(), false);
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      if (pieces[i].k + 2 >= n || pieces[i].lo1 == pieces[i].hi1) continue;
      for (std::size_t j = i + 1; j < pieces.size(); ++j) {
        if (pieces[j].k == pieces[i].k + 1 && pieces[j].lo0 == pieces[i].lo1 && pieces[j].hi0 == pieces[i].hi1) {
          next[i] = j;
          has_prev[j] = true;
          break;
        }
      }
    }
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      if (has_prev[i]) continue;
      std::vector<std::size_t> chain{i};
      while (next[chain.back()] < pieces.size()) chain.push_back(next[chain.back()]);
      const std::size_t k0 = pieces[chain.front()].k, k1 = pieces[chain.back()].k + 1;
      std::vector<std::uint32_t> loop;
      // Bottom, left to right.
      for (std::size_t q = 0; q < chain.size(); ++q) loop.push_back(column_at(e, k0 + q).column[pieces[chain[q]].lo0]);
      // Right side, bottom to top (every vertex of the column on the way).
      const Column& right = column_at(e, k1);
      for (std::uint32_t c = pieces[chain.back()].lo1; c <= pieces[chain.back()].hi1; ++c) loop.push_back(right.column[c]);
      // Top, right to left.
      for (std::size_t q = chain.size(); q-- > 0;) loop.push_back(column_at(e, k0 + q).column[pieces[chain[q]].hi0]);
      // Left side, top to bottom, without the end points.
      const Column& left = column_at(e, k0);
      for (std::uint32_t c = pieces[chain.front()].hi0; c-- > pieces[chain.front()].lo0 + 1;) loop.push_back(left.column[c]);
      std::vector<std::uint32_t> clean;
      for (std::uint32_t v : loop)
        if (clean.empty() || clean.back() != v) clean.push_back(v);
      while (clean.size() > 1 && clean.front() == clean.back()) clean.pop_back();
      if (clean.size() < 3) continue;
      // As built the face is counter-clockwise seen from the right of u -> w; face the outside.
      if (edge.left < 0) std::reverse(clean.begin(), clean.end());
      CandidateFace f;
      f.kind = FaceKind::wall;
      f.source = edge.wall_source;
      f.plane_id = static_cast<std::uint32_t>(R + 1 + edge.line);
      f.cell_or_edge = static_cast<std::uint32_t>(e);
      f.vertices = std::move(clean);
      faces.push_back(std::move(f));
    }
  }

  // Areas; prune faces with an edge no other face has (they could never
  // be part of a closed surface).
  for (auto& f : faces) {
    std::vector<Point3> poly;
    for (auto v : f.vertices) poly.push_back(vertices[v]);
    const Vec3 n = newell_normal(poly);
    f.area = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
  }
  std::vector<bool> alive(faces.size());
  // Faces of sliver cells (nearly collinear vertices, area ~0 in double) are kept: dropping them would
  // open their neighbours. The floor and coplanar roofs absorb them when the model is merged.
  for (std::size_t i = 0; i < faces.size(); ++i) alive[i] = faces[i].vertices.size() >= 3;
  using EdgeKey = std::pair<std::uint32_t, std::uint32_t>;
  auto edge_key = [](std::uint32_t a, std::uint32_t b) { return a < b ? EdgeKey{a, b} : EdgeKey{b, a}; };
  std::map<EdgeKey, std::vector<std::uint32_t>> edge_faces;
  for (;;) {
    edge_faces.clear();
    for (std::uint32_t i = 0; i < faces.size(); ++i) {
      if (!alive[i]) continue;
      const auto& vs = faces[i].vertices;
      for (std::size_t k = 0; k < vs.size(); ++k) edge_faces[edge_key(vs[k], vs[(k + 1) % vs.size()])].push_back(i);
    }
    bool changed = false;
    for (const auto& [key, list] : edge_faces) {
      if (list.size() == 1 && alive[list[0]]) {
        alive[list[0]] = false;
        changed = true;
      }
    }
    if (!changed) break;
  }
  for (std::size_t i = 0; i < faces.size(); ++i)
    if (!alive[i] && faces[i].kind == FaceKind::floor)
      throw ReconstructionError(ReconstructionStage::hypothesis, "floor face over cell " + std::to_string(faces[i].cell_or_edge) +
                                " cannot be closed (internal error)");

  std::vector<std::uint32_t> new_index(faces.size(), 0);
  for (std::size_t i = 0; i < faces.size(); ++i) {
    if (!alive[i]) continue;
    new_index[i] = static_cast<std::uint32_t>(out.faces.size());
    out.faces.push_back(std::move(faces[i]));
  }
  // Compact the vertices to those in use, keeping their order.
  std::vector<std::uint32_t> vertex_index(vertices.size(), std::numeric_limits<std::uint32_t>::max());
  for (const auto& f : out.faces)
    for (auto v : f.vertices) vertex_index[v] = 0;
  for (std::size_t v = 0; v < vertices.size(); ++v) {
    if (vertex_index[v] == 0) {
      vertex_index[v] = static_cast<std::uint32_t>(out.vertices.size());
      out.vertices.push_back(vertices[v]);
    }
  }
  for (auto& f : out.faces)
    for (auto& v : f.vertices) v = vertex_index[v];
  for (const auto& f : out.faces) {
    std::vector<Point3> poly;
    for (auto v : f.vertices) poly.push_back(out.vertices[v]);
    out.polygons.push_back(std::move(poly));
  }

  // Per edge of the faces' union: the faces using it, renumbered.
  std::vector<std::vector<std::uint32_t>> edges;
  for (const auto& [key, list] : edge_faces) {
    std::vector<std::uint32_t> users;
    for (auto f : list) users.push_back(new_index[f]);
    std::sort(users.begin(), users.end());
    edges.push_back(std::move(users));
  }
  return edges;
}

}  // namespace city3d::detail
