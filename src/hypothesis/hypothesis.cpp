// Candidate faces of one building (paper section 3.3) from a 2.5D arrangement; see hypothesis.hpp for
// the construction. The only CGAL code is the 2D arrangement in build_arrangement(); everything
// after it works on plain double structures with explicit vertex identities.
#include "city3d/hypothesis.hpp"

#include <CGAL/Arr_consolidated_curve_data_traits_2.h>
#include <CGAL/Arr_extended_dcel.h>
#include <CGAL/Arr_segment_traits_2.h>
#include <CGAL/Arrangement_2.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numeric>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/log.hpp"

namespace city3d {

void HypothesisParams::validate() const {
  std::vector<std::string> problems;
  auto need = [&](bool ok, const std::string& what) {
    if (!ok) problems.push_back(what);
  };
  need(support_distance > 0.0, "support_distance must be > 0");
  need(min_face_area >= 0.0, "min_face_area must be >= 0");
  need(line_support_margin > 0.0, "line_support_margin must be > 0");
  need(cell_support_margin >= 0.0, "cell_support_margin must be >= 0");
  need(min_support_points >= 1, "min_support_points must be >= 1");
  need(vertex_merge_tolerance > 0.0, "vertex_merge_tolerance must be > 0");
  need(parallel_tolerance > 0.0, "parallel_tolerance must be > 0");
  need(max_planes_per_cell >= 1, "max_planes_per_cell must be >= 1");
  need(floor_clearance > 0.0, "floor_clearance must be > 0");
  need(unmeasured_floor_drop >= 0.0, "unmeasured_floor_drop must be >= 0");
  need(min_part_area >= 0.0, "min_part_area must be >= 0");
  need(min_edge_length >= 0.0, "min_edge_length must be >= 0");
  need(min_cell_width >= 0.0, "min_cell_width must be >= 0");
  need(min_line_overlap >= 0.0, "min_line_overlap must be >= 0");
  need(line_merge_distance >= 0.0, "line_merge_distance must be >= 0");
  need(large_cell_count >= 0, "large_cell_count must be >= 0");
  need(max_planes_per_large_cell >= 1, "max_planes_per_large_cell must be >= 1");
  if (problems.empty()) return;
  std::string message = "hypothesis: invalid parameters: ";
  for (std::size_t i = 0; i < problems.size(); ++i) message += (i ? "; " : "") + problems[i];
  throw ConfigError(message);
}

namespace detail {
namespace {

// ---------------------------------------------------------------------------------------------
// The 2D arrangement, as plain data.

enum class CurveKind { footprint, inner_wall, roof_line, bridge };

struct InputCurve {
  Point2 a, b;
  CurveKind kind;
  int source;  // inner wall: index into walls; others -1
};

struct PlainArrangement {
  std::vector<Point2> vertices;
  struct Edge {
    std::uint32_t u = 0, w = 0;  // u < w
    int left = -1, right = -1;   // inside cell on the left / right of u -> w, or -1 (outside)
    std::uint32_t line = 0;      // collinearity class of the curves it lies on
    int wall_source = -1;        // smallest inner-wall index among its curves
  };
  std::vector<Edge> edges;
  struct Cell {
    std::vector<std::pair<std::uint32_t, bool>> loop;  // (edge, walked u -> w), counter-clockwise
    std::vector<Point2> polygon;                       // loop vertices, counter-clockwise
    double area = 0.0;
  };
  std::vector<Cell> cells;
};

using Kernel = CGAL::Exact_predicates_exact_constructions_kernel;
using SegmentTraits = CGAL::Arr_segment_traits_2<Kernel>;
using Traits = CGAL::Arr_consolidated_curve_data_traits_2<SegmentTraits, unsigned>;
using Dcel = CGAL::Arr_extended_dcel<Traits, int, int, int>;
using Arrangement = CGAL::Arrangement_2<Traits, Dcel>;

// Removes every edge with the same face on both sides (a dangling "antenna" or a bridge without a
// partner): such a face would not be a simple polygon.
void remove_antennas(Arrangement& arr) {
  for (;;) {
    std::vector<Arrangement::Halfedge_handle> antennas;
    for (auto e = arr.edges_begin(); e != arr.edges_end(); ++e)
      if (e->face() == e->twin()->face()) antennas.push_back(e);
    if (antennas.empty()) return;
    for (auto e : antennas) arr.remove_edge(e);
  }
}

// Marks faces inside (data 1) or outside (0) the footprint: walk from the unbounded face, toggling
// across edges that lie on an odd number of footprint segments (an edge shared by two footprint
// polygons of a multipolygon does not toggle).
void classify_faces(Arrangement& arr, const std::vector<InputCurve>& curves) {
  for (auto f = arr.faces_begin(); f != arr.faces_end(); ++f) f->set_data(-1);
  std::vector<Arrangement::Face_handle> queue{arr.unbounded_face()};
  arr.unbounded_face()->set_data(0);
  auto visit_ccb = [&](Arrangement::Ccb_halfedge_circulator first, int inside) {
    auto he = first;
    do {
      int footprint_count = 0;
      for (unsigned id : he->curve().data())
        if (curves[id].kind == CurveKind::footprint) ++footprint_count;
      auto other = he->twin()->face();
      if (other->data() < 0) {
        other->set_data((footprint_count % 2 == 1) ? 1 - inside : inside);
        queue.push_back(other);
      }
    } while (++he != first);
  };
  for (std::size_t q = 0; q < queue.size(); ++q) {
    auto f = queue[q];
    if (!f->is_unbounded()) visit_ccb(f->outer_ccb(), f->data());
    for (auto h = f->inner_ccbs_begin(); h != f->inner_ccbs_end(); ++h) visit_ccb(*h, f->data());
  }
}

// Splits every inside face that has a hole with a horizontal line across the whole footprint at
// the middle height of the hole: the line crosses the hole's boundary at least twice, so the hole
// becomes part of the outer boundaries of the pieces above and below (a line through a vertex of the
// hole, or a ray from it, could merely touch it and leave a pinched, non-simple cell). Returns false
// when no face needed it.
bool bridge_holes(Arrangement& arr, std::vector<InputCurve>& curves, std::vector<Traits::Curve_2>& bridges,
                  double x_min, double x_max) {
  bridges.clear();
  for (auto f = arr.faces_begin(); f != arr.faces_end(); ++f) {
    if (f->is_unbounded() || f->data() != 1) continue;
    for (auto h = f->inner_ccbs_begin(); h != f->inner_ccbs_end(); ++h) {
      auto he = *h;
      Kernel::FT lo = he->source()->point().y(), hi = lo;
      auto first = he;
      do {
        const auto& y = he->source()->point().y();
        if (y < lo) lo = y;
        if (y > hi) hi = y;
      } while (++he != first);
      // Rounded to double so that the line is a plain input segment; a hole thinner than that
      // rounding is a degenerate input anyway.
      const double mid = CGAL::to_double((lo + hi) / 2);
      const auto id = static_cast<unsigned>(curves.size());
      curves.push_back({{x_min, mid}, {x_max, mid}, CurveKind::bridge, -1});
      bridges.emplace_back(Kernel::Segment_2(Kernel::Point_2(x_min, mid), Kernel::Point_2(x_max, mid)), id);
    }
  }
  return !bridges.empty();
}

// Merges every thin inside cell (area below min_width / 2 x perimeter: a strip narrower than about
// min_width, or a sliver triangle) into the inside neighbour with which it shares the longest
// boundary, by removing the shared edges. Nearly coincident lines otherwise make cells whose faces
// are degenerate (zero area in double) and inflate the selection problem. A merge is done only when
// it keeps the cell a simple polygon: the shared edges form one chain, and no other vertex of the thin
// cell lies on the neighbour. Cells are visited in arrangement order, one merge at a time
// (deterministic). Runs before bridge_holes(). Returns the number of merges.
std::size_t merge_thin_cells(Arrangement& arr, double min_width) {
  if (min_width <= 0.0) return 0;
  std::size_t merges = 0;
  auto point_of = [](Arrangement::Vertex_const_handle v) {
    return Point2{CGAL::to_double(v->point().x()), CGAL::to_double(v->point().y())};
  };
  auto usable = [](Arrangement::Face_const_handle f) {
    return !f->is_unbounded() && f->data() == 1 && f->number_of_inner_ccbs() == 0;
  };
  for (;;) {
    bool merged = false;
    for (auto f = arr.faces_begin(); f != arr.faces_end() && !merged; ++f) {
      if (!usable(f)) continue;
      double twice_area = 0.0, perimeter = 0.0;
      auto he = f->outer_ccb(), first = he;
      do {
        const Point2 a = point_of(he->source()), b = point_of(he->target());
        twice_area += a.x * b.y - b.x * a.y;
        perimeter += std::hypot(b.x - a.x, b.y - a.y);
      } while (++he != first);
      if (std::abs(twice_area) >= min_width * perimeter) continue;
      // The neighbour with the longest shared boundary (first in boundary order on ties).
      std::vector<std::pair<Arrangement::Face_handle, double>> shared;
      do {
        auto other = he->twin()->face();
        if (!usable(other) || other == f) continue;
        const Point2 a = point_of(he->source()), b = point_of(he->target());
        auto it = std::find_if(shared.begin(), shared.end(), [&](const auto& s) { return s.first == other; });
        if (it == shared.end()) shared.emplace_back(other, 0.0), it = std::prev(shared.end());
        it->second += std::hypot(b.x - a.x, b.y - a.y);
      } while (++he != first);
      if (shared.empty()) continue;
      auto best = shared.front();
      for (const auto& s : shared)
        if (s.second > best.second) best = s;
      const auto neighbour = best.first;
      // One chain: the boundary switches between shared and not shared exactly twice.
      std::vector<Arrangement::Halfedge_handle> chain;
      std::vector<Arrangement::Vertex_handle> chain_vertices, other_vertices;
      int switches = 0;
      do {
        const bool on = he->twin()->face() == neighbour;
        const bool next_on = he->next()->twin()->face() == neighbour;
        if (on != next_on) ++switches;
        if (on) {
          chain.push_back(he);
          chain_vertices.push_back(he->source());
          chain_vertices.push_back(he->target());
        } else {
          other_vertices.push_back(he->target());
        }
      } while (++he != first);
      if (switches != 2) continue;
      bool pinched = false;
      auto nh = neighbour->outer_ccb(), nfirst = nh;
      do {
        const auto v = nh->target();
        if (std::find(chain_vertices.begin(), chain_vertices.end(), v) == chain_vertices.end() &&
            std::find(other_vertices.begin(), other_vertices.end(), v) != other_vertices.end())
          pinched = true;
      } while (++nh != nfirst && !pinched);
      if (pinched) continue;
      for (auto e : chain) arr.remove_edge(e);
      ++merges;
      merged = true;
    }
    if (!merged) return merges;
  }
}

PlainArrangement build_arrangement(std::vector<InputCurve> curves, double min_cell_width) {
  std::vector<Traits::Curve_2> input;
  double x_min = std::numeric_limits<double>::infinity(), x_max = -x_min;
  for (unsigned i = 0; i < curves.size(); ++i) {
    const auto& c = curves[i];
    Kernel::Point_2 a(c.a.x, c.a.y), b(c.b.x, c.b.y);
    if (a == b) continue;
    input.emplace_back(Kernel::Segment_2(a, b), i);
    x_min = std::min({x_min, c.a.x, c.b.x});
    x_max = std::max({x_max, c.a.x, c.b.x});
  }
  Arrangement arr;
  CGAL::insert(arr, input.begin(), input.end());
  remove_antennas(arr);
  classify_faces(arr, curves);
  // Thin cells are merged before holes are bridged: should a union still enclose something, the
  // bridging below splits it like any cell with a hole.
  if (const std::size_t merges = merge_thin_cells(arr, min_cell_width)) {
    log_debug("hypothesis: merged " + std::to_string(merges) + " thin cells into their neighbours");
    remove_antennas(arr);
  }
  std::vector<Traits::Curve_2> bridges;
  for (int round = 0; round < 8 && bridge_holes(arr, curves, bridges, x_min - 1.0, x_max + 1.0); ++round) {
    for (const auto& c : bridges) {
      CGAL::insert(arr, c);
      input.push_back(c);
    }
    remove_antennas(arr);
    classify_faces(arr, curves);
  }
  for (auto f = arr.faces_begin(); f != arr.faces_end(); ++f)
    if (!f->is_unbounded() && f->data() == 1 && f->number_of_inner_ccbs() > 0)
      throw ReconstructionError("hypothesis: a cell of the arrangement keeps a hole after bridging");

  // Collinearity classes of the curves (exact predicates on the input segments): the vertical plane
  // over an edge is identified by its class, so walls over collinear pieces are coplanar.
  std::vector<unsigned> klass(curves.size());
  std::iota(klass.begin(), klass.end(), 0u);
  auto find = [&](unsigned i) {
    while (klass[i] != i) i = klass[i] = klass[klass[i]];
    return i;
  };
  for (std::size_t i = 0; i < input.size(); ++i) {
    for (std::size_t j = i + 1; j < input.size(); ++j) {
      const auto& si = input[i];
      const auto& sj = input[j];
      if (CGAL::collinear(si.source(), si.target(), sj.source()) &&
          CGAL::collinear(si.source(), si.target(), sj.target())) {
        const unsigned a = find(si.data()), b = find(sj.data());
        if (a != b) klass[std::max(a, b)] = std::min(a, b);
      }
    }
  }

  // Vertices incident to an edge of an inside face, in exact lexicographic order (deterministic).
  std::vector<Arrangement::Vertex_handle> vertices;
  for (auto v = arr.vertices_begin(); v != arr.vertices_end(); ++v) {
    v->set_data(-1);
    if (v->is_isolated()) continue;
    bool used = false;
    auto he = v->incident_halfedges(), first = he;
    do {
      if (he->face()->data() == 1 || he->twin()->face()->data() == 1) used = true;
    } while (++he != first);
    if (used) vertices.push_back(v);
  }
  std::sort(vertices.begin(), vertices.end(), [](auto a, auto b) {
    return CGAL::compare_xy(a->point(), b->point()) == CGAL::SMALLER;
  });
  PlainArrangement out;
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    vertices[i]->set_data(static_cast<int>(i));
    out.vertices.push_back({CGAL::to_double(vertices[i]->point().x()), CGAL::to_double(vertices[i]->point().y())});
  }

  // Inside cells, ordered by their first directed edge (smallest vertex, then its successor).
  struct CellRef {
    std::pair<int, int> key;
    Arrangement::Face_handle face;
  };
  std::vector<CellRef> cells;
  for (auto f = arr.faces_begin(); f != arr.faces_end(); ++f) {
    if (f->is_unbounded() || f->data() != 1) continue;
    std::pair<int, int> key{std::numeric_limits<int>::max(), 0};
    auto he = f->outer_ccb(), first = he;
    do key = std::min(key, std::make_pair(he->source()->data(), he->target()->data()));
    while (++he != first);
    cells.push_back({key, f});
  }
  std::sort(cells.begin(), cells.end(), [](const CellRef& a, const CellRef& b) { return a.key < b.key; });
  for (auto f = arr.faces_begin(); f != arr.faces_end(); ++f) f->set_data(-1);
  for (std::size_t i = 0; i < cells.size(); ++i) cells[i].face->set_data(static_cast<int>(i));

  // Edges bordering an inside cell, ordered by (u, w).
  std::vector<std::pair<std::pair<int, int>, Arrangement::Halfedge_handle>> edges;
  for (auto e = arr.edges_begin(); e != arr.edges_end(); ++e) {
    Arrangement::Halfedge_handle he = e;
    if (he->face()->data() < 0 && he->twin()->face()->data() < 0) continue;
    if (he->source()->data() > he->target()->data()) he = he->twin();
    edges.push_back({{he->source()->data(), he->target()->data()}, he});
  }
  std::sort(edges.begin(), edges.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (std::size_t i = 0; i < edges.size(); ++i) {
    auto he = edges[i].second;
    he->set_data(static_cast<int>(i));
    he->twin()->set_data(static_cast<int>(i));
    PlainArrangement::Edge e;
    e.u = static_cast<std::uint32_t>(edges[i].first.first);
    e.w = static_cast<std::uint32_t>(edges[i].first.second);
    e.left = he->face()->data();
    e.right = he->twin()->face()->data();
    unsigned line = std::numeric_limits<unsigned>::max();
    for (unsigned id : he->curve().data()) {
      line = std::min(line, find(id));
      if (curves[id].kind == CurveKind::inner_wall && (e.wall_source < 0 || curves[id].source < e.wall_source))
        e.wall_source = curves[id].source;
    }
    e.line = line;
    out.edges.push_back(e);
  }
  // Renumber the line classes densely in edge order.
  std::map<std::uint32_t, std::uint32_t> dense;
  for (auto& e : out.edges) e.line = dense.emplace(e.line, static_cast<std::uint32_t>(dense.size())).first->second;

  for (const auto& ref : cells) {
    PlainArrangement::Cell cell;
    auto he = ref.face->outer_ccb();
    while (he->source()->data() != ref.key.first || he->target()->data() != ref.key.second) ++he;
    auto first = he;
    do {
      const auto& e = out.edges[static_cast<std::size_t>(he->data())];
      cell.loop.emplace_back(static_cast<std::uint32_t>(he->data()),
                             static_cast<int>(e.u) == he->source()->data());
      cell.polygon.push_back(out.vertices[static_cast<std::size_t>(he->source()->data())]);
    } while (++he != first);
    double area = 0.0;
    for (std::size_t i = 0; i < cell.polygon.size(); ++i) {
      const auto& p = cell.polygon[i];
      const auto& q = cell.polygon[(i + 1) % cell.polygon.size()];
      area += p.x * q.y - q.x * p.y;
    }
    cell.area = 0.5 * area;
    out.cells.push_back(std::move(cell));
  }
  return out;
}

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
        throw ReconstructionError("hypothesis: degenerate arrangement (two cells on one side of an edge after snapping)");
      side = static_cast<int>(c);
      cell.loop.emplace_back(it->second, a == edge.u);
      cell.polygon.push_back(out.vertices[a]);
    }
    double area = 0.0;
    for (std::size_t i = 0; i < cell.polygon.size(); ++i) {
      const auto& p = cell.polygon[i];
      const auto& q = cell.polygon[(i + 1) % cell.polygon.size()];
      area += p.x * q.y - q.x * p.y;
    }
    cell.area = 0.5 * area;
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

// ---------------------------------------------------------------------------------------------
// A uniform xy grid over a set of points (the support and plane-ranking loops ask for the points in
// a box; without an index they scanned every point for every cell and wall face). Each entry is a
// payload index; queries return every entry whose bin meets the box (callers test exactly).
class PointGrid {
 public:
  // `xy(i)` gives the position of entry i, for i in 0..count-1.
  template <typename XY>
  PointGrid(std::size_t count, XY xy) {
    Box2 box;
    for (std::size_t i = 0; i < count; ++i) box.add(xy(i));
    if (box.empty()) return;
    origin_ = box.min;
    const double w = box.max.x - box.min.x, h = box.max.y - box.min.y;
    // About four entries per bin, at most ~1M bins, never below 10 cm.
    size_ = std::max(0.1, std::sqrt(std::max(w * h, 1e-6) * 4.0 / static_cast<double>(count)));
    while ((w / size_ + 1.0) * (h / size_ + 1.0) > 1e6) size_ *= 2.0;
    nx_ = static_cast<long>(w / size_) + 1;
    ny_ = static_cast<long>(h / size_) + 1;
    bins_.assign(static_cast<std::size_t>(nx_ * ny_), {});
    for (std::size_t i = 0; i < count; ++i) {
      const Point2 p = xy(i);
      bins_[static_cast<std::size_t>(bin_y(p.y) * nx_ + bin_x(p.x))].push_back(static_cast<std::uint32_t>(i));
    }
  }
  template <typename Visit>
  void for_each_in(double x0, double y0, double x1, double y1, Visit visit) const {
    if (bins_.empty() || x1 < x0 || y1 < y0) return;
    const long i0 = bin_x(x0), i1 = bin_x(x1), j0 = bin_y(y0), j1 = bin_y(y1);
    for (long j = j0; j <= j1; ++j)
      for (long i = i0; i <= i1; ++i)
        for (std::uint32_t k : bins_[static_cast<std::size_t>(j * nx_ + i)]) visit(k);
  }

 private:
  long bin_x(double x) const { return std::clamp(static_cast<long>(std::floor((x - origin_.x) / size_)), 0L, nx_ - 1); }
  long bin_y(double y) const { return std::clamp(static_cast<long>(std::floor((y - origin_.y) / size_)), 0L, ny_ - 1); }
  Point2 origin_{0.0, 0.0};
  double size_ = 1.0;
  long nx_ = 0, ny_ = 0;
  std::vector<std::vector<std::uint32_t>> bins_;
};

// ---------------------------------------------------------------------------------------------
// Plain geometry helpers.

bool inside_polygon(const std::vector<Point2>& poly, double x, double y) {
  bool inside = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const auto& a = poly[i];
    const auto& b = poly[j];
    if ((a.y > y) != (b.y > y) && x < (b.x - a.x) * (y - a.y) / (b.y - a.y) + a.x) inside = !inside;
  }
  return inside;
}

double distance_to_segment(const Point2& a, const Point2& b, double x, double y) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? ((x - a.x) * dx + (y - a.y) * dy) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(a.x + t * dx - x, a.y + t * dy - y);
}

double distance_to_polygon(const std::vector<Point2>& poly, double x, double y) {
  if (inside_polygon(poly, x, y)) return 0.0;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < poly.size(); ++i)
    best = std::min(best, distance_to_segment(poly[i], poly[(i + 1) % poly.size()], x, y));
  return best;
}

struct Vec3 {
  double x, y, z;
};
Vec3 newell_normal(const std::vector<Point3>& poly) {
  Vec3 n{0, 0, 0};
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const auto& p = poly[i];
    const auto& q = poly[(i + 1) % poly.size()];
    n.x += (p.y - q.y) * (p.z + q.z);
    n.y += (p.z - q.z) * (p.x + q.x);
    n.z += (p.x - q.x) * (p.y + q.y);
  }
  return {0.5 * n.x, 0.5 * n.y, 0.5 * n.z};
}

Point3 centroid(const std::vector<Point3>& poly) {
  // Area-weighted centroid of the fan triangles (all coplanar, so the weights have one sign).
  double total = 0.0;
  Point3 sum{0.0, 0.0, 0.0};
  for (std::size_t i = 1; i + 1 < poly.size(); ++i) {
    const auto& a = poly[0];
    const auto& b = poly[i];
    const auto& c = poly[i + 1];
    const Vec3 u{b.x - a.x, b.y - a.y, b.z - a.z}, v{c.x - a.x, c.y - a.y, c.z - a.z};
    const double area = 0.5 * std::sqrt(std::pow(u.y * v.z - u.z * v.y, 2) + std::pow(u.z * v.x - u.x * v.z, 2) +
                                        std::pow(u.x * v.y - u.y * v.x, 2));
    total += area;
    sum.x += area * (a.x + b.x + c.x) / 3.0;
    sum.y += area * (a.y + b.y + c.y) / 3.0;
    sum.z += area * (a.z + b.z + c.z) / 3.0;
  }
  if (total <= 0.0) {
    sum = {0.0, 0.0, 0.0};
    for (const auto& p : poly) {
      sum.x += p.x;
      sum.y += p.y;
      sum.z += p.z;
    }
    total = static_cast<double>(std::max<std::size_t>(poly.size(), 1));
  }
  return {sum.x / total, sum.y / total, sum.z / total};
}

// ---------------------------------------------------------------------------------------------
double roof_height(const PlanarSegment& roof, double x, double y) {
  const Plane3& p = roof.plane;
  return -(p.a * x + p.b * y + p.d) / p.c;
}

// Levels (roof planes 0..R-1 and the floor R) and the vertices at one xy position.

struct Levels {
  const std::vector<PlanarSegment>* roofs;
  double ground_z;
  int floor() const { return static_cast<int>(roofs->size()); }
  double height(int level, double x, double y) const {
    if (level == floor()) return ground_z;
    return roof_height((*roofs)[static_cast<std::size_t>(level)], x, y);
  }
};

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

bool inside_footprint(const std::vector<Polygon2>& footprint, double x, double y) {
  bool inside = false;  // even-odd over every ring
  for (const auto& poly : footprint) {
    if (inside_polygon(poly.outer, x, y)) inside = !inside;
    for (const auto& hole : poly.holes)
      if (inside_polygon(hole, x, y)) inside = !inside;
  }
  return inside;
}

// A roof line or inner wall whose end lies inside the footprint with no other curve crossing it
// within `reach` of that end would be a dangling edge (removed, leaving the cell unsplit). Such an
// end is extended to the first curve ahead of it (plus a hair, so the exact arrangement sees a
// proper crossing; the hair is an antenna and is removed). Curves are processed in order and
// extended curves count for later ones, so the result is deterministic.
void extend_dangling_ends(std::vector<InputCurve>& curves, const std::vector<Polygon2>& footprint, double reach) {
  constexpr double hair = 1e-6;
  for (std::size_t i = 0; i < curves.size(); ++i) {
    if (curves[i].kind != CurveKind::roof_line && curves[i].kind != CurveKind::inner_wall) continue;
    for (int end = 0; end < 2; ++end) {
      InputCurve& c = curves[i];
      const Point2 p = end ? c.b : c.a, q = end ? c.a : c.b;
      const double len = std::hypot(p.x - q.x, p.y - q.y);
      if (len <= 0.0 || !inside_footprint(footprint, p.x, p.y)) continue;
      const Point2 d{(p.x - q.x) / len, (p.y - q.y) / len};
      const double back = -std::min(reach, len);
      double ahead = std::numeric_limits<double>::infinity();
      bool connected = false;
      for (std::size_t j = 0; j < curves.size() && !connected; ++j) {
        if (j == i) continue;
        const Point2 a = curves[j].a, b = curves[j].b;
        const Point2 e{b.x - a.x, b.y - a.y};
        const double denom = d.x * e.y - d.y * e.x;
        if (std::abs(denom) < 1e-12) continue;
        // p + t d == a + s e
        const double t = ((a.x - p.x) * e.y - (a.y - p.y) * e.x) / denom;
        const double s = ((a.x - p.x) * d.y - (a.y - p.y) * d.x) / denom;
        if (s < 0.0 || s > 1.0) continue;
        if (t >= back && t <= 0.0) connected = true;
        else if (t > 0.0) ahead = std::min(ahead, t);
      }
      if (connected || !std::isfinite(ahead)) continue;
      const Point2 moved{p.x + (ahead + hair) * d.x, p.y + (ahead + hair) * d.y};
      (end ? c.b : c.a) = moved;
    }
  }
}

// A feasible start for face selection: one roof face per cell, the floors, and over every edge the
// wall faces between the roofs chosen on its two sides (or the floor, outside). Each cell first takes
// its segment's face prior if it holds one, else its best-supported roof face. One roof per cell can
// still leave an edge with one or four faces (a checkerboard of high and low cells around a vertex
// puts four walls on one vertical edge), so a local search then changes one cell's roof at a time,
// taking the change that leaves the fewest such edges (cells holding a face prior only when no other
// change helps), until none is left or no change helps. Returns an empty vector in that case.
std::vector<bool> start_assignment(const CandidateFaces& out, const PlainArrangement& arr, const Levels& lv,
                                   std::size_t cell_count) {
  const SelectionProblem& prob = out.problem;
  const std::size_t nf = out.faces.size();
  const int floor_level = lv.floor();
  std::vector<bool> is_prior(nf, false);
  for (auto f : prob.face_prior) is_prior[f] = true;
  std::vector<std::vector<std::uint32_t>> roofs_of_cell(cell_count), walls_of_edge(arr.edges.size());
  std::vector<Point3> wall_centroid(nf);
  std::vector<bool> selected(nf, false);
  for (std::uint32_t i = 0; i < nf; ++i) {
    const auto& f = out.faces[i];
    if (f.kind == FaceKind::roof) roofs_of_cell[f.cell_or_edge].push_back(i);
    if (f.kind == FaceKind::floor) selected[i] = true;
    if (f.kind == FaceKind::wall) {
      walls_of_edge[f.cell_or_edge].push_back(i);
      wall_centroid[i] = centroid(out.polygons[i]);
    }
  }
  std::vector<std::vector<std::uint32_t>> edges_of_face(nf);
  for (std::uint32_t e = 0; e < prob.edges.size(); ++e)
    for (auto f : prob.edges[e].faces) edges_of_face[f].push_back(e);

  // The chosen roof face per cell, and per problem edge how many selected faces it has.
  std::vector<std::uint32_t> roof_of_cell(cell_count);
  std::vector<bool> prior_cell(cell_count, false);
  for (std::size_t c = 0; c < cell_count; ++c) {
    if (roofs_of_cell[c].empty()) return {};
    std::uint32_t best = roofs_of_cell[c].front();
    for (auto i : roofs_of_cell[c]) {
      if (is_prior[i] != is_prior[best] ? is_prior[i] : prob.support[i] > prob.support[best]) best = i;
      prior_cell[c] = prior_cell[c] || is_prior[i];
    }
    roof_of_cell[c] = best;
  }
  std::vector<int> count(prob.edges.size(), 0);
  std::size_t bad = 0;
  const auto is_bad = [](int n) { return n != 0 && n != 2; };
  const auto toggle = [&](std::uint32_t f) {
    selected[f] = !selected[f];
    for (auto e : edges_of_face[f]) {
      bad -= is_bad(count[e]);
      count[e] += selected[f] ? 1 : -1;
      bad += is_bad(count[e]);
    }
  };
  const auto level = [&](int cell) {
    return cell < 0 ? floor_level : out.faces[roof_of_cell[static_cast<std::size_t>(cell)]].source;
  };
  const auto wall_on = [&](std::uint32_t f) {
    const auto& edge = arr.edges[out.faces[f].cell_or_edge];
    const int a = level(edge.left), b = level(edge.right);
    if (a == b) return false;
    const Point3& c = wall_centroid[f];
    const double ha = lv.height(a, c.x, c.y), hb = lv.height(b, c.x, c.y);
    return std::min(ha, hb) < c.z && c.z < std::max(ha, hb);
  };
  // Puts roof face `roof` on cell c and updates the walls around it.
  const auto choose = [&](std::size_t c, std::uint32_t roof) {
    if (selected[roof_of_cell[c]]) toggle(roof_of_cell[c]);
    roof_of_cell[c] = roof;
    toggle(roof);
    for (const auto& [e, forward] : arr.cells[c].loop)
      for (auto f : walls_of_edge[e])
        if (selected[f] != wall_on(f)) toggle(f);
  };
  for (std::uint32_t f = 0; f < nf; ++f)
    if (selected[f]) {
      selected[f] = false;
      toggle(f);
    }
  for (std::size_t c = 0; c < cell_count; ++c) choose(c, roof_of_cell[c]);

  const std::size_t max_steps = 4 * cell_count + 16;
  for (std::size_t step = 0; bad > 0 && step < max_steps; ++step) {
    std::size_t e = 0;
    while (!is_bad(count[e])) ++e;
    std::vector<std::size_t> cells;
    for (auto f : prob.edges[e].faces) {
      const auto& face = out.faces[f];
      if (face.kind != FaceKind::wall) {
        cells.push_back(face.cell_or_edge);
        continue;
      }
      for (int side : {arr.edges[face.cell_or_edge].left, arr.edges[face.cell_or_edge].right})
        if (side >= 0) cells.push_back(static_cast<std::size_t>(side));
    }
    std::sort(cells.begin(), cells.end());
    cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
    std::size_t best_bad = bad, best_cell = 0;
    std::uint32_t best_roof = 0;
    for (bool allow_prior : {false, true}) {
      for (std::size_t c : cells) {
        if (prior_cell[c] && !allow_prior) continue;
        const std::uint32_t current = roof_of_cell[c];
        for (auto roof : roofs_of_cell[c]) {
          if (roof == current) continue;
          choose(c, roof);
          if (bad < best_bad) {
            best_bad = bad;
            best_cell = c;
            best_roof = roof;
          }
          choose(c, current);
        }
      }
      if (best_bad < bad) break;
    }
    if (best_bad == bad) break;
    choose(best_cell, best_roof);
  }
  if (bad > 0) {
    log_debug("hypothesis: no start assignment (" + std::to_string(bad) +
              " edges left with one or more than two faces)");
    return {};
  }
  return selected;
}

}  // namespace
}  // namespace detail

// -------------------------------------------------------------------------------------------------

CandidateFaces generate_candidates(const std::vector<Point3>& points,
                                   const std::vector<PlanarSegment>& roof_planes_in,
                                   const std::vector<VerticalPlane>& walls,
                                   const std::vector<Polygon2>& footprint_local, double ground_z,
                                   bool ground_measured, const HypothesisParams& params) {
  using namespace detail;
  params.validate();

  std::vector<PlanarSegment> roofs;
  for (const auto& s : roof_planes_in)
    if (s.kind == PlanarSegment::Kind::roof && std::abs(s.plane.c) > 1e-6) roofs.push_back(s);
  if (roofs.empty())
    throw ReconstructionError("hypothesis: " + std::to_string(roof_planes_in.size()) +
                              " planes, need at least 1 roof plane");
  for (const auto& s : roofs)
    for (std::uint32_t i : s.points)
      if (i >= points.size())
        throw ReconstructionError("hypothesis: roof segment refers to point " + std::to_string(i) + " of " +
                                  std::to_string(points.size()));
  const std::size_t R = roofs.size();

  // 1. Curves of the arrangement.
  std::vector<InputCurve> curves;
  for (const auto& poly : footprint_local) {
    std::vector<const Ring2*> rings{&poly.outer};
    for (const auto& h : poly.holes) rings.push_back(&h);
    for (const Ring2* ring : rings)
      for (std::size_t i = 0; i < ring->size(); ++i)
        curves.push_back({(*ring)[i], (*ring)[(i + 1) % ring->size()], CurveKind::footprint, -1});
  }
  if (curves.size() < 3) throw ReconstructionError("hypothesis: empty footprint");
  const double margin = params.line_support_margin;
  for (std::size_t i = 0; i < walls.size(); ++i) {
    const auto& w = walls[i];
    if (w.outer) continue;
    const double len = std::hypot(w.b.x - w.a.x, w.b.y - w.a.y);
    if (len <= 0.0) continue;
    const double dx = (w.b.x - w.a.x) / len, dy = (w.b.y - w.a.y) / len;
    curves.push_back({{w.a.x - margin * dx, w.a.y - margin * dy},
                      {w.b.x + margin * dx, w.b.y + margin * dy},
                      CurveKind::inner_wall,
                      static_cast<int>(i)});
  }
  std::vector<InputCurve> roof_lines;
  for (std::size_t i = 0; i < R; ++i) {
    for (std::size_t j = i + 1; j < R; ++j) {
      // z_i(x, y) == z_j(x, y)  <=>  A x + B y + C == 0.
      const Plane3& p = roofs[i].plane;
      const Plane3& q = roofs[j].plane;
      const double A = p.a / p.c - q.a / q.c, B = p.b / p.c - q.b / q.c, C = p.d / p.c - q.d / q.c;
      const double norm = std::hypot(A, B);
      const double cross = std::sqrt(std::pow(p.b * q.c - p.c * q.b, 2) + std::pow(p.c * q.a - p.a * q.c, 2) +
                                     std::pow(p.a * q.b - p.b * q.a, 2));
      if (cross < params.parallel_tolerance || norm < 1e-12) continue;
      const Point2 origin{-A * C / (norm * norm), -B * C / (norm * norm)};
      const Point2 dir{-B / norm, A / norm};
      auto interval = [&](const PlanarSegment& s) {
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (std::uint32_t k : s.points) {
          const Point3& pt = points[k];
          if (std::abs(A * pt.x + B * pt.y + C) / norm > margin) continue;
          const double t = (pt.x - origin.x) * dir.x + (pt.y - origin.y) * dir.y;
          lo = std::min(lo, t);
          hi = std::max(hi, t);
        }
        return std::make_pair(lo, hi);
      };
      const auto a = interval(roofs[i]);
      const auto b = interval(roofs[j]);
      const double lo = std::max(a.first, b.first), hi = std::min(a.second, b.second);
      if (!(lo <= hi) || hi - lo < params.min_line_overlap) continue;
      roof_lines.push_back({{origin.x + (lo - margin) * dir.x, origin.y + (lo - margin) * dir.y},
                            {origin.x + (hi + margin) * dir.x, origin.y + (hi + margin) * dir.y},
                            CurveKind::roof_line,
                            -1});
    }
  }
  // Nearly coincident roof lines (both ends of one within line_merge_distance of the other's line,
  // overlapping along it) become one: the longer line, extended over both. Longest first, ties in
  // input order (deterministic).
  if (params.line_merge_distance > 0.0) {
    std::vector<std::size_t> order(roof_lines.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    auto length = [&](std::size_t i) { return std::hypot(roof_lines[i].b.x - roof_lines[i].a.x, roof_lines[i].b.y - roof_lines[i].a.y); };
    std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) { return length(x) > length(y); });
    std::vector<InputCurve> kept;
    for (std::size_t i : order) {
      const InputCurve& c = roof_lines[i];
      bool absorbed = false;
      for (auto& k : kept) {
        const double len = std::hypot(k.b.x - k.a.x, k.b.y - k.a.y);
        const Point2 d{(k.b.x - k.a.x) / len, (k.b.y - k.a.y) / len};
        auto across = [&](const Point2& p) { return std::abs(-(p.x - k.a.x) * d.y + (p.y - k.a.y) * d.x); };
        auto along = [&](const Point2& p) { return (p.x - k.a.x) * d.x + (p.y - k.a.y) * d.y; };
        if (across(c.a) > params.line_merge_distance || across(c.b) > params.line_merge_distance) continue;
        const double t0 = std::min(along(c.a), along(c.b)), t1 = std::max(along(c.a), along(c.b));
        if (t1 < 0.0 || t0 > len) continue;
        const Point2 a0 = k.a;
        if (t0 < 0.0) k.a = {a0.x + t0 * d.x, a0.y + t0 * d.y};
        if (t1 > len) k.b = {a0.x + t1 * d.x, a0.y + t1 * d.y};
        absorbed = true;
        break;
      }
      if (!absorbed) kept.push_back(c);
    }
    if (kept.size() < roof_lines.size())
      log_debug("hypothesis: merged " + std::to_string(roof_lines.size() - kept.size()) + " nearly coincident roof lines");
    roof_lines = std::move(kept);
  }
  const std::size_t line_count = roof_lines.size();
  curves.insert(curves.end(), roof_lines.begin(), roof_lines.end());

  extend_dangling_ends(curves, footprint_local, 2.0 * margin);
  const PlainArrangement arr =
      drop_small_parts(contract_robustly(build_arrangement(curves, params.min_cell_width), params.min_edge_length), params.min_part_area);
  if (arr.cells.empty()) throw ReconstructionError("hypothesis: the footprint has no inside cell");
  const std::size_t cell_count = arr.cells.size();

  // 2. Candidate roof planes per cell.
  struct PlaneRank {
    std::size_t inside, near;
    int plane;
  };
  std::vector<std::vector<PlaneRank>> ranked(cell_count);
  std::vector<std::vector<int>> cell_planes(cell_count);
  // Every (plane, point) membership, indexed in xy.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> memberships;
  for (std::size_t r = 0; r < R; ++r)
    for (std::uint32_t k : roofs[r].points) memberships.emplace_back(static_cast<std::uint32_t>(r), k);
  const PointGrid membership_grid(memberships.size(), [&](std::size_t i) {
    const Point3& p = points[memberships[i].second];
    return Point2{p.x, p.y};
  });
  std::vector<std::size_t> near_count(R), inside_count(R);
  // A large arrangement gets fewer planes per cell: the problem grows with cells x planes.
  const bool large = cell_count > static_cast<std::size_t>(params.large_cell_count);
  const auto max_planes = static_cast<std::size_t>(large ? std::min(params.max_planes_per_cell, params.max_planes_per_large_cell)
                                                         : params.max_planes_per_cell);
  if (large && max_planes < static_cast<std::size_t>(params.max_planes_per_cell))
    log_debug("hypothesis: " + std::to_string(cell_count) + " cells, at most " + std::to_string(max_planes) +
              " roof planes per cell");
  for (std::size_t c = 0; c < cell_count; ++c) {
    const auto& poly = arr.cells[c].polygon;
    Box2 box;
    for (const auto& p : poly) box.add(p);
    const double cm = params.cell_support_margin;
    std::fill(near_count.begin(), near_count.end(), 0);
    std::fill(inside_count.begin(), inside_count.end(), 0);
    membership_grid.for_each_in(box.min.x - cm, box.min.y - cm, box.max.x + cm, box.max.y + cm, [&](std::uint32_t i) {
      const Point3& pt = points[memberships[i].second];
      if (pt.x < box.min.x - cm || pt.x > box.max.x + cm || pt.y < box.min.y - cm || pt.y > box.max.y + cm) return;
      const double d = distance_to_polygon(poly, pt.x, pt.y);
      if (d <= cm) ++near_count[memberships[i].first];
      if (d <= 0.0) ++inside_count[memberships[i].first];
    });
    for (std::size_t r = 0; r < R; ++r) {
      const std::size_t need = std::min<std::size_t>(static_cast<std::size_t>(params.min_support_points),
                                                     roofs[r].points.size());
      if (need > 0 && near_count[r] >= need) ranked[c].push_back({inside_count[r], near_count[r], static_cast<int>(r)});
    }
    // Best-supported first (points inside the cell, then points near it, then plane index); keep
    // at most max_planes_per_cell.
    auto& list = ranked[c];
    std::sort(list.begin(), list.end(), [](const PlaneRank& x, const PlaneRank& y) {
      if (x.inside != y.inside) return x.inside > y.inside;
      if (x.near != y.near) return x.near > y.near;
      return x.plane < y.plane;
    });
    if (list.size() > max_planes) list.resize(max_planes);
    for (const auto& pr : list) cell_planes[c].push_back(pr.plane);
    std::sort(cell_planes[c].begin(), cell_planes[c].end());
    if (cell_planes[c].empty()) {
      // No plane has points near this cell: take the plane(s) whose points come nearest.
      std::vector<double> nearest(R, std::numeric_limits<double>::infinity());
      for (std::size_t r = 0; r < R; ++r)
        for (std::uint32_t k : roofs[r].points)
          nearest[r] = std::min(nearest[r], distance_to_polygon(poly, points[k].x, points[k].y));
      const double best = *std::min_element(nearest.begin(), nearest.end());
      for (std::size_t r = 0; r < R; ++r)
        if (nearest[r] <= best + cm) cell_planes[c].push_back(static_cast<int>(r));
    }
  }

  // 2b. The floor lies below every roof face: over measured ground, a plane that dips below
  // ground_z + floor_clearance over a cell is dropped there when another candidate of the cell stays
  // above (an unmeasured ground_z is only an upper bound of the ground: the bar is then
  // unmeasured_floor_drop lower); the floor is then lowered (never raised) to floor_clearance below
  // the lowest remaining roof vertex.
  const double clearance = params.floor_clearance;
  const double bar = ground_z + clearance - (ground_measured ? 0.0 : params.unmeasured_floor_drop);
  auto lowest_over = [&](std::size_t c, int r) {
    double low = std::numeric_limits<double>::infinity();
    for (const auto& p : arr.cells[c].polygon) low = std::min(low, roof_height(roofs[static_cast<std::size_t>(r)], p.x, p.y));
    return low;
  };
  double floor_z = ground_z;
  for (std::size_t c = 0; c < cell_count; ++c) {
    auto& list = cell_planes[c];
    std::vector<int> above;
    for (int r : list)
      if (lowest_over(c, r) >= bar) above.push_back(r);
    if (!above.empty()) list = std::move(above);
    for (int r : list) floor_z = std::min(floor_z, lowest_over(c, r) - clearance);
  }
  if (floor_z < ground_z)
    log_debug("hypothesis: floor lowered by " + std::to_string(ground_z - floor_z) + " m below the roofs");
  const Levels lv{&roofs, floor_z};
  const int F = lv.floor();

  // 3. Levels per edge and per vertex; stations where levels cross inside an edge.
  const double tol = params.vertex_merge_tolerance;
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

  // 4. Faces.
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

  // 5. Areas; prune faces with an edge no other face has (they could never
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
      throw ReconstructionError("hypothesis: floor face over cell " + std::to_string(faces[i].cell_or_edge) +
                                " cannot be closed (internal error)");

  CandidateFaces out;
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

  // 6. The selection problem.
  SelectionProblem& prob = out.problem;
  const std::size_t nf = out.faces.size();
  prob.face_count = nf;
  prob.point_count = points.size();
  prob.support.assign(nf, 0.0);
  prob.centroid_z.resize(nf);
  prob.is_roof.resize(nf);
  if (!points.empty()) {
    prob.z_min = std::numeric_limits<double>::infinity();
    prob.z_max = -prob.z_min;
    for (const auto& p : points) {
      prob.z_min = std::min(prob.z_min, p.z);
      prob.z_max = std::max(prob.z_max, p.z);
    }
    if (!(prob.z_max > prob.z_min)) prob.z_max = prob.z_min + 1.0;
  }
  std::vector<int> segment_of(points.size(), -1);
  for (std::size_t r = 0; r < R; ++r)
    for (auto k : roofs[r].points) segment_of[k] = static_cast<int>(r);
  const double eps = params.support_distance;
  // Roof and floor faces: the points over their cell.
  const PointGrid point_grid(points.size(), [&](std::size_t k) { return Point2{points[k].x, points[k].y}; });
  std::vector<std::vector<std::uint32_t>> cell_points(cell_count);
  for (std::size_t c = 0; c < cell_count; ++c) {
    Box2 box;
    for (const auto& p : arr.cells[c].polygon) box.add(p);
    point_grid.for_each_in(box.min.x, box.min.y, box.max.x, box.max.y, [&](std::uint32_t k) {
      const auto& p = points[k];
      if (p.x < box.min.x || p.x > box.max.x || p.y < box.min.y || p.y > box.max.y) return;
      if (inside_polygon(arr.cells[c].polygon, p.x, p.y)) cell_points[c].push_back(k);
    });
    std::sort(cell_points[c].begin(), cell_points[c].end());
  }
  for (std::size_t i = 0; i < nf; ++i) {
    const auto& f = out.faces[i];
    const auto& poly = out.polygons[i];
    prob.centroid_z[i] = centroid(poly).z;
    prob.is_roof[i] = f.kind == FaceKind::roof;
    double support = 0.0;
    if (f.kind == FaceKind::roof) {
      const Plane3& pl = roofs[static_cast<std::size_t>(f.source)].plane;
      for (auto k : cell_points[f.cell_or_edge])
        if (segment_of[k] == f.source && std::abs(pl.signed_distance(points[k])) <= eps) support += 1.0;
    } else if (f.kind == FaceKind::floor) {
      for (auto k : cell_points[f.cell_or_edge])
        if (std::abs(points[k].z - floor_z) <= eps) support += 1.0;
    } else {
      const auto& edge = arr.edges[f.cell_or_edge];
      const Point2 a = arr.vertices[edge.u], b = arr.vertices[edge.w];
      const double len = std::hypot(b.x - a.x, b.y - a.y);
      const double dx = (b.x - a.x) / len, dy = (b.y - a.y) / len;
      std::vector<Point2> tz;  // the face in (along the edge, z)
      double zlo = std::numeric_limits<double>::infinity(), zhi = -zlo;
      for (const auto& p : poly) {
        tz.push_back({(p.x - a.x) * dx + (p.y - a.y) * dy, p.z});
        zlo = std::min(zlo, p.z);
        zhi = std::max(zhi, p.z);
      }
      point_grid.for_each_in(std::min(a.x, b.x) - eps, std::min(a.y, b.y) - eps, std::max(a.x, b.x) + eps,
                             std::max(a.y, b.y) + eps, [&](std::uint32_t k) {
        const auto& p = points[k];
        if (p.z < zlo || p.z > zhi) return;
        const double across = -(p.x - a.x) * dy + (p.y - a.y) * dx;
        if (std::abs(across) > eps) return;
        const double along = (p.x - a.x) * dx + (p.y - a.y) * dy;
        if (along < 0.0 || along > len) return;
        if (inside_polygon(tz, along, p.z)) support += 1.0;
      });
    }
    prob.support[i] = support;
  }

  for (const auto& [key, list] : edge_faces) {
    SelectionProblem::Edge edge;
    for (auto f : list) edge.faces.push_back(new_index[f]);
    std::sort(edge.faces.begin(), edge.faces.end());
    for (std::size_t i = 0; i < edge.faces.size(); ++i)
      for (std::size_t j = i + 1; j < edge.faces.size(); ++j)
        if (out.faces[edge.faces[i]].plane_id != out.faces[edge.faces[j]].plane_id)
          edge.sharp_pairs.emplace_back(edge.faces[i], edge.faces[j]);
    prob.edges.push_back(std::move(edge));
  }

  std::vector<std::vector<std::uint32_t>> roofs_over_cell(cell_count);
  std::vector<long> prior(R, -1);
  for (std::uint32_t i = 0; i < nf; ++i) {
    const auto& f = out.faces[i];
    if (f.kind == FaceKind::floor) prob.forced_on.push_back(i);
    if (f.kind != FaceKind::roof) continue;
    roofs_over_cell[f.cell_or_edge].push_back(i);
    auto& best = prior[static_cast<std::size_t>(f.source)];
    if (prob.support[i] > 0.0 && f.area >= params.min_face_area &&
        (best < 0 || prob.support[i] > prob.support[static_cast<std::size_t>(best)]))
      best = i;
  }
  for (const auto& list : roofs_over_cell)
    for (std::size_t i = 0; i < list.size(); ++i)
      for (std::size_t j = i + 1; j < list.size(); ++j) prob.vertical_overlaps.emplace_back(list[i], list[j]);
  for (long p : prior)
    if (p >= 0) prob.face_prior.push_back(static_cast<std::uint32_t>(p));
  std::sort(prob.face_prior.begin(), prob.face_prior.end());

  // 7. A start assignment for the solvers (see start_assignment()).
  prob.start = start_assignment(out, arr, lv, cell_count);

  out.cell_count = cell_count;
  out.edge_count = arr.edges.size();
  out.line_count = line_count;
  log_debug("hypothesis: " + std::to_string(R) + " roof planes, " + std::to_string(line_count) +
            " intersection lines, " + std::to_string(cell_count) + " cells, " + std::to_string(nf) +
            " candidate faces, " + std::to_string(prob.edges.size()) + " edges");
  return out;
}

}  // namespace city3d
