// Face hypothesis, step 2: the 2D arrangement of the input curves (CGAL Arrangement_2 with exact
// predicates and constructions; the only CGAL code of the hypothesis, so that the other steps compile
// fast). Dangling edges are removed, cells classified inside / outside the footprint, thin cells
// merged into a neighbour, cells with holes split, and the result exported as a PlainArrangement
// (double coordinates, deterministic order) with the collinearity class of every edge.
#include <CGAL/Arr_consolidated_curve_data_traits_2.h>
#include <CGAL/Arr_extended_dcel.h>
#include <CGAL/Arr_segment_traits_2.h>
#include <CGAL/Arrangement_2.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
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
  // One merge attempt at face f: true when f was merged (f's handle is then not to be used again).
  const auto try_merge = [&](Arrangement::Face_handle f) {
    if (!usable(f)) return false;
    double twice_area = 0.0, perimeter = 0.0;
    auto he = f->outer_ccb(), first = he;
    do {
      const Point2 a = point_of(he->source()), b = point_of(he->target());
      twice_area += a.x * b.y - b.x * a.y;
      perimeter += std::hypot(b.x - a.x, b.y - a.y);
    } while (++he != first);
    if (std::abs(twice_area) >= min_width * perimeter) return false;
    // The neighbour with the longest shared boundary (first in boundary order on ties).
    std::vector<std::pair<Arrangement::Face_handle, double>> shared;
    do {
      auto other = he->twin()->face();
      if (!usable(other) || other == f) continue;  // to the next boundary edge
      const Point2 a = point_of(he->source()), b = point_of(he->target());
      auto it = std::find_if(shared.begin(), shared.end(), [&](const auto& s) { return s.first == other; });
      if (it == shared.end()) shared.emplace_back(other, 0.0), it = std::prev(shared.end());
      it->second += std::hypot(b.x - a.x, b.y - a.y);
    } while (++he != first);
    if (shared.empty()) return false;
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
    if (switches != 2) return false;
    bool pinched = false;
    auto nh = neighbour->outer_ccb(), nfirst = nh;
    do {
      const auto v = nh->target();
      if (std::find(chain_vertices.begin(), chain_vertices.end(), v) == chain_vertices.end() &&
          std::find(other_vertices.begin(), other_vertices.end(), v) != other_vertices.end())
        pinched = true;
    } while (++nh != nfirst && !pinched);
    if (pinched) return false;
    for (auto e : chain) arr.remove_edge(e);
    ++merges;
    return true;
  };
  // Sweeps over the faces in arrangement order; after a merge the sweep goes on from the same
  // position (the faces before it were checked, and a merge deletes one face and keeps the order of
  // the others) instead of starting over: 4,000 merges among 12,000 faces took 41 s that way (a
  // footprint over the whole Delft block). Sweeps repeat until one merges nothing.
  for (;;) {
    bool merged_in_sweep = false;
    std::size_t position = 0;
    auto f = arr.faces_begin();
    while (f != arr.faces_end()) {
      if (!try_merge(f)) {
        ++f;
        ++position;
        continue;
      }
      merged_in_sweep = true;
      f = arr.faces_begin();
      for (std::size_t k = 0; k < position && f != arr.faces_end(); ++k) ++f;
    }
    if (!merged_in_sweep) return merges;
  }
}

}  // namespace

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
      throw ReconstructionError(ReconstructionStage::hypothesis, "a cell of the arrangement keeps a hole after bridging");

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
    cell.area = loop_area(cell.polygon);
    out.cells.push_back(std::move(cell));
  }
  return out;
}

}  // namespace city3d::detail
