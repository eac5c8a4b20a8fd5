// Face hypothesis, step 2 (continued): clean-up of the plain arrangement. Edges shorter than
// min_edge_length are contracted (nearly concurrent lines make cells without area), and detached
// parts of the inside cells too small to be a building part are dropped.
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
#include "city3d/log.hpp"
#include "hypothesis/steps.hpp"

namespace city3d::detail {
namespace {

// Contracts arrangement edges shorter than `min_length` (nearly concurrent lines make tiny cells whose
// faces have no area and would leave their neighbours open). The endpoints of a short edge become one
// vertex (the lower index, keeping its coordinates); cells left with fewer than three edges vanish,
// and the two edges that bounded such a sliver become one. Throws ReconstructionError when the
// result is not a valid subdivision (two cells claiming the same side of an edge, or a pinched cell);
// contract_robustly() then retries with smaller tolerances.
PlainArrangement contract_short_edges(const PlainArrangement& in, double min_length) {
  const std::size_t nv = in.vertices.size();
  std::vector<std::uint32_t> root(nv);
  std::iota(root.begin(), root.end(), 0u);
  auto find = [&](std::uint32_t i) {
    while (root[i] != i) i = root[i] = root[root[i]];
    return i;
  };
  bool any = false;
  for (const auto& e : in.edges) {
    const Point2 a = in.vertices[e.u], b = in.vertices[e.w];
    if (std::hypot(b.x - a.x, b.y - a.y) >= min_length) continue;
    const std::uint32_t ra = find(e.u), rb = find(e.w);
    if (ra != rb) root[std::max(ra, rb)] = std::min(ra, rb);
    any = true;
  }
  if (!any) return in;

  PlainArrangement out;
  std::vector<std::uint32_t> new_vertex(nv, std::numeric_limits<std::uint32_t>::max());
  auto vertex_of = [&](std::uint32_t v) {
    const std::uint32_t r = find(v);
    if (new_vertex[r] == std::numeric_limits<std::uint32_t>::max()) {
      new_vertex[r] = static_cast<std::uint32_t>(out.vertices.size());
      out.vertices.push_back(in.vertices[r]);
    }
    return new_vertex[r];
  };
  // Number the surviving vertices in old order (deterministic).
  for (std::uint32_t v = 0; v < nv; ++v)
    if (find(v) == v) vertex_of(v);

  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> edge_index;
  std::vector<std::vector<std::uint32_t>> loops;  // per surviving cell: directed vertex loop
  std::vector<std::vector<std::uint32_t>> loop_old_edges;
  for (const auto& cell : in.cells) {
    std::vector<std::uint32_t> loop, old_edges;
    for (const auto& [e, forward] : cell.loop) {
      const auto& edge = in.edges[e];
      const std::uint32_t a = vertex_of(forward ? edge.u : edge.w), b = vertex_of(forward ? edge.w : edge.u);
      if (a == b) continue;
      loop.push_back(a);
      old_edges.push_back(e);
    }
    if (loop.size() < 3) continue;  // a sliver: gone
    // A loop that visits a vertex twice (a sliver part of the cell collapsed onto a point) is split
    // there into simple loops: pieces of two vertices are slivers (gone), the others become cells
    // of their own. A piece is kept even when snapping turned it clockwise: dropping it would open
    // a crack between its neighbours, whose walls nearly touch.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> stack;  // (vertex, old edge leaving it)
    auto emit = [&](std::size_t from) {
      std::vector<std::uint32_t> piece, piece_edges;
      for (std::size_t k = from; k < stack.size(); ++k) {
        piece.push_back(stack[k].first);
        piece_edges.push_back(stack[k].second);
      }
      stack.resize(from);
      if (piece.size() < 3) return;
      loops.push_back(std::move(piece));
      loop_old_edges.push_back(std::move(piece_edges));
    };
    for (std::size_t k = 0; k < loop.size(); ++k) {
      const auto seen = std::find_if(stack.begin(), stack.end(), [&](const auto& s) { return s.first == loop[k]; });
      if (seen != stack.end()) emit(static_cast<std::size_t>(seen - stack.begin()));
      stack.emplace_back(loop[k], old_edges[k]);
    }
    emit(0);
  }
  for (std::size_t c = 0; c < loops.size(); ++c) {
    PlainArrangement::Cell cell;
    const auto& loop = loops[c];
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const std::uint32_t a = loop[i], b = loop[(i + 1) % loop.size()];
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = edge_index.find(key);
      if (it == edge_index.end()) {
        it = edge_index.emplace(key, static_cast<std::uint32_t>(out.edges.size())).first;
        PlainArrangement::Edge edge;
        edge.u = key.first;
        edge.w = key.second;
        edge.line = in.edges[loop_old_edges[c][i]].line;
        out.edges.push_back(edge);
      }
      auto& edge = out.edges[it->second];
      const auto& old = in.edges[loop_old_edges[c][i]];
      if (old.wall_source >= 0 && (edge.wall_source < 0 || old.wall_source < edge.wall_source))
        edge.wall_source = old.wall_source;
      int& side = (a == edge.u) ? edge.left : edge.right;
      if (side >= 0)
        throw ReconstructionError(ReconstructionStage::hypothesis, "degenerate arrangement (two cells on one side of an edge after snapping)");
      side = static_cast<int>(c);
      cell.loop.emplace_back(it->second, a == edge.u);
      cell.polygon.push_back(out.vertices[a]);
    }
    cell.area = loop_area(cell.polygon);
    out.cells.push_back(std::move(cell));
  }
  // Edges are numbered in cell order; renumber them by (u, w) as build_arrangement does.
  std::vector<std::uint32_t> order(out.edges.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t x, std::uint32_t y) {
    return std::make_pair(out.edges[x].u, out.edges[x].w) < std::make_pair(out.edges[y].u, out.edges[y].w);
  });
  std::vector<std::uint32_t> rank(order.size());
  std::vector<PlainArrangement::Edge> edges;
  for (std::size_t i = 0; i < order.size(); ++i) {
    rank[order[i]] = static_cast<std::uint32_t>(i);
    edges.push_back(out.edges[order[i]]);
  }
  out.edges = std::move(edges);
  for (auto& cell : out.cells)
    for (auto& entry : cell.loop) entry.first = rank[entry.first];
  return out;
}

}  // namespace

// Contracts short edges with min_length, or, when that pinches a cell (features of about that size),
// with min_length / 10 and / 100, or not at all.
PlainArrangement contract_robustly(const PlainArrangement& in, double min_length) {
  for (double length = min_length; length >= min_length / 100.0 && length > 0.0; length /= 10.0) {
    try {
      return contract_short_edges(in, length);
    } catch (const ReconstructionError& e) {
      log_debug(std::string(e.what()) + "; retrying with a smaller tolerance");
    }
  }
  return in;
}

// Removes the connected parts of the inside cells (connected across edges with inside cells on both
// sides) whose area is below `min_area`, except the largest part. A self-touching outline ring
// leaves such specks (a lobe of a few cm2 would become a separate tower). Edges keep their order;
// an edge that loses one side borders the outside there.
PlainArrangement drop_small_parts(const PlainArrangement& in, double min_area) {
  const std::size_t nc = in.cells.size();
  std::vector<std::size_t> part(nc);
  std::iota(part.begin(), part.end(), std::size_t{0});
  auto find = [&](std::size_t i) {
    while (part[i] != i) i = part[i] = part[part[i]];
    return i;
  };
  for (const auto& e : in.edges)
    if (e.left >= 0 && e.right >= 0) {
      const std::size_t a = find(static_cast<std::size_t>(e.left)), b = find(static_cast<std::size_t>(e.right));
      if (a != b) part[std::max(a, b)] = std::min(a, b);
    }
  std::vector<double> area(nc, 0.0);
  for (std::size_t c = 0; c < nc; ++c) area[find(c)] += in.cells[c].area;
  std::size_t largest = 0;
  for (std::size_t c = 0; c < nc; ++c)
    if (area[c] > area[largest]) largest = c;
  std::vector<int> new_cell(nc, -1);
  PlainArrangement out;
  out.vertices = in.vertices;
  bool any = false;
  for (std::size_t c = 0; c < nc; ++c) {
    const std::size_t r = find(c);
    if (r != largest && area[r] < min_area) {
      any = true;
      continue;
    }
    new_cell[c] = static_cast<int>(out.cells.size());
    out.cells.push_back(in.cells[c]);
  }
  if (!any) return in;
  std::vector<std::uint32_t> new_edge(in.edges.size(), std::numeric_limits<std::uint32_t>::max());
  for (std::size_t e = 0; e < in.edges.size(); ++e) {
    auto edge = in.edges[e];
    edge.left = edge.left >= 0 ? new_cell[static_cast<std::size_t>(edge.left)] : -1;
    edge.right = edge.right >= 0 ? new_cell[static_cast<std::size_t>(edge.right)] : -1;
    if (edge.left < 0 && edge.right < 0) continue;
    new_edge[e] = static_cast<std::uint32_t>(out.edges.size());
    out.edges.push_back(edge);
  }
  for (auto& cell : out.cells)
    for (auto& entry : cell.loop) entry.first = new_edge[entry.first];
  log_debug("hypothesis: dropped " + std::to_string(nc - out.cells.size()) + " cells of small detached parts");
  return out;
}

}  // namespace city3d::detail
