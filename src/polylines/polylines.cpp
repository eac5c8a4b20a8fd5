// Edge pixels -> polylines: optimal-transport simplification of a short-edge Delaunay graph under a
// Hausdorff bound (City3D paper section 3.2; transport cost after de Goes, Cohen-Steiner, Alliez and
// Desbrun, "An optimal transport approach to robust reconstruction and simplification of 2D shapes",
// SGP 2011).
//
// What is implemented, and how it differs from de Goes et al. (and CGAL's
// Optimal_transportation_reconstruction_2, which is too slow here and does not bound the Hausdorff
// distance, see DEPENDENCIES.md):
//
//  1. The pixels (exact duplicates merged, each carrying its multiplicity as mass) are triangulated
//     (CGAL 2D Delaunay). Only Delaunay edges no longer than link_pixels x r are kept: the pixel
//     chains become a graph. de Goes keeps the whole triangulation; long edges never carry mass in a
//     good result and only cost time.
//  2. Each pixel is assigned to one edge of the current graph (or to a vertex without edges). An edge
//     is "solid" when transporting its pixels onto the segment is cheaper than transporting each to
//     the nearer endpoint ("ghost"), exactly as in de Goes: the edge cost is min(solid, ghost), with
//        solid = sum_i m_i (n_i^2 + (t_i - c_i)^2 + l_i^2 / 12)
//     where n_i, t_i are the normal offset and abscissa of pixel i, and the edge's length is split
//     into consecutive pieces l_i = L m_i / M (sorted by t) with centres c_i (the uniform measure on
//     the segment; the l_i^2/12 term is the spread of mass inside a piece), and
//        ghost = sum_i m_i min(|p_i - a|^2, |p_i - b|^2).
//  3. Simplification is a greedy sequence of half-edge collapses u -> v (vertex u removed, its edges
//     moved to v). The pixels of every edge around u and v are reassigned to the nearest edge around
//     v afterwards (de Goes also reassigns locally). The collapse with the smallest increase of the
//     total cost goes first (priority queue; stale entries detected by per-vertex version stamps;
//     results memoised per (u, v, versions)). v normally keeps its position; when that breaks the
//     bound and u, v are both inside a chain, v may instead be placed at the intersection of the two
//     remaining neighbouring edges' lines (this removes the short bevels staircases leave at
//     corners). A collapse is allowed only if, afterwards,
//       - every reassigned pixel is within eps_d of its solid edge (or of the nearer endpoint of its
//         ghost edge, or of its vertex), and
//       - every solid edge is covered by pixels: along the edge, no stretch is farther than
//         max(eps_d, half the link length) from its pixels (the gaps between consecutive pixel
//         projections are bounded; the link length term admits the gaps the chains already have),
//       - a vertex that moves stays within eps_d of a pixel.
//     It stops when no collapse is allowed or when the next one would raise the root-mean-square
//     transport distance above eps_c pixels (in practice the Hausdorff bound stops it first).
//     de Goes has no Hausdorff test, keeps a triangulation (collapses must not fold triangles, here
//     the graph may in rare cases gain crossing edges), and evaluates every candidate with
//     relocation; here relocation is cheaper (4).
//  4. Relocation (unless params.relocate is false): after each collapse the kept vertex, and at the
//     end every vertex, moves to the least-squares intersection of the lines fitted (PCA) to the
//     pixels of its solid edges (a small pull to its old position keeps near-collinear cases
//     stable), only when the bound above still holds and the new position is within eps_d of a
//     pixel. Relocation can unblock collapses, so collapsing and the final relocation repeat (up to
//     4 rounds) until no collapse happens. This plays the role of de Goes's relocation step, which
//     minimises the transport cost itself rather than the normal distances.
//  5. Edge filtering: ghost edges are dropped (they carry no wall), and so is every connected group
//     of solid edges shorter than min_polyline_length in total (noise and outliers).
//  6. Polylines are the chains of solid edges between vertices whose degree is not 2; cycles of
//     degree-2 vertices become closed polylines.
//
// Determinism: pixels are sorted before anything else; vertex and edge ids follow that order; ties in
// the queue break on vertex ids. Nothing is keyed by pointer.
#include "city3d/polylines.hpp"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <queue>
#include <sstream>
#include <unordered_map>
#include <utility>

#include "city3d/error.hpp"
#include "city3d/log.hpp"
#include "core/union_find.hpp"

namespace city3d {

bool is_closed(const Polyline2& p) {
  return p.size() >= 4 && p.front().x == p.back().x && p.front().y == p.back().y;
}

void PolylineParams::validate() const {
  std::ostringstream problems;
  if (!(max_hausdorff > 0.0)) problems << " max_hausdorff must be > 0 (got " << max_hausdorff << ");";
  if (!(max_cost > 0.0)) problems << " max_cost must be > 0 (got " << max_cost << ");";
  if (!(resolution >= 0.0)) problems << " resolution must be >= 0 (got " << resolution << ");";
  if (!(link_pixels >= 1.0)) problems << " link_pixels must be >= 1 (got " << link_pixels << ");";
  if (!(min_polyline_length >= 0.0))
    problems << " min_polyline_length must be >= 0 (got " << min_polyline_length << ");";
  if (!(relocate_pull > 0.0) || !std::isfinite(relocate_pull))
    problems << " relocate_pull must be > 0 (got " << relocate_pull << ");";
  if (!(corner_min_sine >= 0.0 && corner_min_sine < 1.0))
    problems << " corner_min_sine must be in [0, 1) (got " << corner_min_sine << ");";
  if (relocate_rounds < 1) problems << " relocate_rounds must be >= 1 (got " << relocate_rounds << ");";
  throw_if_invalid("polylines", problems.str());
}

namespace detail {
namespace {

double sq(double v) { return v * v; }
double dist2(const Point2& a, const Point2& b) { return sq(a.x - b.x) + sq(a.y - b.y); }

double segment_dist2(const Point2& p, const Point2& a, const Point2& b) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double len2 = dx * dx + dy * dy;
  if (len2 <= 0.0) return dist2(p, a);
  double t = ((p.x - a.x) * dx + (p.y - a.y) * dy) / len2;
  t = std::clamp(t, 0.0, 1.0);
  return sq(p.x - (a.x + t * dx)) + sq(p.y - (a.y + t * dy));
}

// The segments from one point a to points b_k, and the nearest of them to a pixel, with exactly
// segment_dist2's arithmetic: the terms that depend on one side only are computed once (this is the
// innermost loop of the simplification). A segment of length 0 gets direction (0, 0) and length 1,
// with which the formula gives |p - a|^2, as segment_dist2 does.
// Where segment_dist2's parameter t clamps, the division is skipped and its result is the same bit
// for bit: a dot product <= 0 clamps t to 0 (p - (a + 0 d) is p - a up to the sign of a zero,
// which squaring removes), one >= |d|^2 gives a quotient >= 1 (division rounds monotonically), so
// t = 1 and the foot is a + d, kept per segment. A NaN falls through to the division as before.
class SegmentFan {
 public:
  void reset(const Point2& a) {
    a_ = a;
    dx_.clear();
    dy_.clear();
    len2_.clear();
    end_x_.clear();
    end_y_.clear();
  }
  void add(const Point2& b) {
    const double dx = b.x - a_.x, dy = b.y - a_.y;
    const double len2 = dx * dx + dy * dy;
    const bool degenerate = len2 <= 0.0;
    dx_.push_back(degenerate ? 0.0 : dx);
    dy_.push_back(degenerate ? 0.0 : dy);
    len2_.push_back(degenerate ? 1.0 : len2);
    end_x_.push_back(a_.x + dx_.back());
    end_y_.push_back(a_.y + dy_.back());
  }
  // The first k with the smallest segment_dist2(p, a, b_k), and that squared distance.
  std::pair<std::size_t, double> nearest(const Point2& p) const {
    const double ax = a_.x, ay = a_.y;
    const double rx = p.x - ax, ry = p.y - ay;
    const double at_a = sq(rx) + sq(ry);
    std::size_t best = 0;
    double best_d2 = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < len2_.size(); ++k) {
      const double dx = dx_[k], dy = dy_[k];
      const double dot = rx * dx + ry * dy;
      double d2;
      if (dot <= 0.0) {
        d2 = at_a;
      } else if (dot >= len2_[k]) {
        d2 = sq(p.x - end_x_[k]) + sq(p.y - end_y_[k]);
      } else {
        const double t = dot / len2_[k];
        d2 = sq(p.x - (ax + t * dx)) + sq(p.y - (ay + t * dy));
      }
      if (d2 < best_d2) {
        best_d2 = d2;
        best = k;
      }
    }
    return {best, best_d2};
  }

 private:
  Point2 a_;
  std::vector<double> dx_, dy_, len2_, end_x_, end_y_;
};

// Uniform hash grid over the pixels for "is there a pixel within d of q" queries.
class PixelGrid {
 public:
  PixelGrid(const std::vector<Point2>& pts, double cell) : pts_(pts), cell_(cell) {
    for (std::size_t i = 0; i < pts.size(); ++i)
      cells_[key(cell_of(pts[i].x), cell_of(pts[i].y))].push_back(i);
  }
  double nearest_dist2(const Point2& q, double max_d) const {
    double best = std::numeric_limits<double>::infinity();
    const int r = static_cast<int>(std::ceil(max_d / cell_));
    const std::int64_t cx = cell_of(q.x), cy = cell_of(q.y);
    for (std::int64_t ix = cx - r; ix <= cx + r; ++ix)
      for (std::int64_t iy = cy - r; iy <= cy + r; ++iy) {
        auto it = cells_.find(key(ix, iy));
        if (it == cells_.end()) continue;
        for (std::size_t i : it->second) best = std::min(best, dist2(q, pts_[i]));
      }
    return best;
  }

 private:
  std::int64_t cell_of(double v) const { return static_cast<std::int64_t>(std::floor(v / cell_)); }
  static std::int64_t key(std::int64_t ix, std::int64_t iy) {
    const std::uint64_t hi = static_cast<std::uint64_t>(ix) << 32;  // unsigned: no UB for negative ix
    return static_cast<std::int64_t>(hi ^ (static_cast<std::uint64_t>(iy) & 0xffffffffu));
  }
  const std::vector<Point2>& pts_;
  double cell_;
  std::unordered_map<std::int64_t, std::vector<std::size_t>> cells_;
};

struct Edge {
  int a = -1, b = -1;
  std::vector<int> pixels;  // ids of the pixels transported to this edge (or its endpoints)
  double cost = 0.0;        // min(solid, ghost)
  bool solid = false;
  bool alive = true;
};

// Cost and validity of one edge (endpoints a, b) carrying `pixels`.
struct EdgeEval {
  double cost = 0.0;
  bool solid = false;
  bool valid = true;
};

// A simulated collapse u -> v: the new neighbours of v and the pixels each new edge gets.
struct CollapsePlan {
  double delta = 0.0;
  bool valid = false;
  Point2 placement;                        // where v ends up
  std::vector<int> neighbours;             // sorted, without u and v
  std::vector<std::vector<int>> assigned;  // per neighbour; or one list for an isolated v
  std::vector<EdgeEval> evals;
};

struct QueueEntry {
  double delta;
  int u, v;
  std::uint32_t version_u, version_v;
  bool operator>(const QueueEntry& o) const {
    if (delta != o.delta) return delta > o.delta;
    if (u != o.u) return u > o.u;
    return v > o.v;
  }
};

class Simplifier {
 public:
  // `grid` (may be null: no relocation) must outlive the simplifier; `params` gives relocation's pull
  // and corner angle.
  Simplifier(const std::vector<Point2>& pixels, const std::vector<double>& mass, double eps_d, double cover,
             double cost_budget, const PixelGrid* grid, const PolylineParams& params)
      : px_(pixels),
        mass_(mass),
        grid_(grid),
        pos_(pixels),
        eps_d_(eps_d),
        eps2_(eps_d * eps_d),
        cover_(cover),
        budget_(cost_budget),
        pull_(params.relocate_pull),
        corner_sine_(params.corner_min_sine) {
    star_.resize(pixels.size());
    vertex_pixels_.resize(pixels.size());
    alive_.assign(pixels.size(), true);
    version_.assign(pixels.size(), 0);
    entries_.assign(pixels.size(), 0);
    memo_.resize(pixels.size());
  }

  // Edges as (a, b) with a < b, sorted; every pixel starts on its own vertex (cost 0).
  void build(const std::vector<std::pair<int, int>>& links) {
    for (const auto& [a, b] : links) {
      const int id = static_cast<int>(edges_.size());
      edges_.push_back(Edge{a, b, {}, 0.0, false, true});
      star_[a].push_back({b, id});
      star_[b].push_back({a, id});
    }
    for (std::size_t v = 0; v < px_.size(); ++v) {
      if (star_[v].empty()) {
        vertex_pixels_[v].push_back(static_cast<int>(v));
      } else {
        int best = star_[v][0].second;
        for (const auto& s : star_[v]) best = std::min(best, s.second);
        edges_[best].pixels.push_back(static_cast<int>(v));
      }
    }
    for (auto& e : edges_) {
      const EdgeEval ev = evaluate(e.a, e.b, e.pixels);
      e.cost = ev.cost;
      e.solid = ev.solid;
    }
  }

  std::size_t run() {
    queue_ = {};
    std::fill(entries_.begin(), entries_.end(), 0);
    for (std::size_t v = 0; v < px_.size(); ++v) push_best(static_cast<int>(v));
    std::size_t collapses = 0;
    std::vector<int> touched;
    while (!queue_.empty()) {
      const QueueEntry top = queue_.top();
      queue_.pop();
      --entries_[top.u];
      if (!alive_[top.u]) continue;
      if (!alive_[top.v] || version_[top.u] != top.version_u || version_[top.v] != top.version_v) {
        if (entries_[top.u] == 0) push_best(top.u);
        continue;
      }
      // The cheapest collapse would exceed the cost tolerance: stop (paper: eps_c).
      if (total_cost_ + top.delta > budget_) break;
      CollapsePlan& plan = plan_collapse(top.u, top.v);
      if (!plan.valid) {  // cannot happen with current versions, but stay safe
        if (entries_[top.u] == 0) push_best(top.u);
        continue;
      }
      apply(top.u, top.v, plan);
      relocate_vertex(top.v);
      ++collapses;
      // Eager update of v and its new neighbours (their stars changed); their neighbours' entries are
      // now stale and get recomputed when popped, or now if they had none (blocked before).
      touched.clear();
      touched.push_back(top.v);
      for (int n : plan.neighbours) touched.push_back(n);
      for (int w : touched) push_best(w);
      for (int w : touched)
        for (const auto& s : star_[w])
          if (entries_[s.first] == 0) push_best(s.first);
    }
    return collapses;
  }

  // Moves v to the least-squares intersection of the lines fitted to the pixels of its solid edges
  // (a small pull towards its position keeps near-collinear cases stable). Kept only when v stays
  // within eps_d of a pixel and every edge around it stays valid. Returns whether v moved.
  bool relocate_vertex(int v) {
    if (!grid_ || !alive_[v]) return false;
    double a11 = 0, a12 = 0, a22 = 0, b1 = 0, b2 = 0, wsum = 0;
    for (const auto& [n, id] : star_[v]) {
      const Edge& e = edges_[id];
      if (!e.solid || e.pixels.size() < 3) continue;
      double m = 0, cx = 0, cy = 0;
      for (int p : e.pixels) {
        m += mass_[p];
        cx += mass_[p] * px_[p].x;
        cy += mass_[p] * px_[p].y;
      }
      cx /= m;
      cy /= m;
      double sxx = 0, sxy = 0, syy = 0;
      for (int p : e.pixels) {
        const double dx = px_[p].x - cx, dy = px_[p].y - cy;
        sxx += mass_[p] * dx * dx;
        sxy += mass_[p] * dx * dy;
        syy += mass_[p] * dy * dy;
      }
      const double angle = 0.5 * std::atan2(2 * sxy, sxx - syy);  // direction of largest spread
      const double nx = -std::sin(angle), ny = std::cos(angle);
      const double c = nx * cx + ny * cy;
      a11 += m * nx * nx;
      a12 += m * nx * ny;
      a22 += m * ny * ny;
      b1 += m * nx * c;
      b2 += m * ny * c;
      wsum += m;
    }
    if (wsum <= 0) return false;
    const double lambda = pull_ * wsum;
    a11 += lambda;
    a22 += lambda;
    b1 += lambda * pos_[v].x;
    b2 += lambda * pos_[v].y;
    const double det = a11 * a22 - a12 * a12;
    if (!(std::abs(det) > 0)) return false;
    const Point2 target{(b1 * a22 - b2 * a12) / det, (a11 * b2 - a12 * b1) / det};
    if (grid_->nearest_dist2(target, eps_d_) > eps2_) return false;
    const Point2 old = pos_[v];
    pos_[v] = target;
    thread_local std::vector<EdgeEval> evals;
    evals.clear();
    for (const auto& [n, id] : star_[v]) {
      const Edge& e = edges_[id];
      evals.push_back(evaluate(e.a, e.b, e.pixels));
      if (!evals.back().valid) {
        pos_[v] = old;
        return false;
      }
    }
    for (std::size_t k = 0; k < star_[v].size(); ++k) {
      Edge& e = edges_[star_[v][k].second];
      total_cost_ += evals[k].cost - e.cost;
      e.cost = evals[k].cost;
      e.solid = evals[k].solid;
    }
    ++version_[v];
    for (const auto& s : star_[v]) ++version_[s.first];
    return true;
  }

  // Final relocation pass over every vertex, in id order.
  void relocate_all() {
    for (std::size_t v = 0; v < pos_.size(); ++v) relocate_vertex(static_cast<int>(v));
  }

  const std::vector<Edge>& edges() const { return edges_; }
  const std::vector<Point2>& positions() const { return pos_; }
  double total_cost() const { return total_cost_; }

  // Largest distance from a pixel to where it is transported (solid edge, ghost endpoint, vertex).
  double max_pixel_distance() const {
    double worst = 0;
    for (const auto& e : edges_) {
      if (!e.alive) continue;
      for (int p : e.pixels) {
        const double d2 = e.solid ? segment_dist2(px_[p], pos_[e.a], pos_[e.b])
                                  : std::min(dist2(px_[p], pos_[e.a]), dist2(px_[p], pos_[e.b]));
        worst = std::max(worst, d2);
      }
    }
    for (std::size_t v = 0; v < pos_.size(); ++v)
      if (alive_[v])
        for (int p : vertex_pixels_[v]) worst = std::max(worst, dist2(px_[p], pos_[v]));
    return std::sqrt(worst);
  }

 private:
  EdgeEval evaluate(int a, int b, const std::vector<int>& pixels) const {
    EdgeEval ev;
    if (pixels.empty()) return ev;  // a ghost edge of cost 0 (a third of simulate's new edges)
    const Point2 pa = pos_[a], pb = pos_[b];
    const double dx = pb.x - pa.x, dy = pb.y - pa.y;
    const double len = std::sqrt(dx * dx + dy * dy);
    double ghost = 0.0;
    bool ghost_ok = true;
    for (int p : pixels) {
      const double d2 = std::min(dist2(px_[p], pa), dist2(px_[p], pb));
      ghost += mass_[p] * d2;
      if (d2 > eps2_) ghost_ok = false;
    }
    if (len <= 0.0) {
      ev.cost = ghost;
      ev.valid = ghost_ok;
      return ev;
    }
    const double ux = dx / len, uy = dy / len;
    // (abscissa, normal^2, mass) sorted by abscissa.
    auto& proj = projections_;
    proj.clear();
    double total_mass = 0.0;
    for (int p : pixels) {
      const double rx = px_[p].x - pa.x, ry = px_[p].y - pa.y;
      proj.push_back({rx * ux + ry * uy, {sq(rx * uy - ry * ux), mass_[p]}});
      total_mass += mass_[p];
    }
    std::sort(proj.begin(), proj.end());
    double solid = 0.0, cumulative = 0.0;
    bool solid_ok = true;
    double prev_t = 0.0, prev_n2 = 0.0, max_gap_excess = 0.0;
    for (const auto& [t, rest] : proj) {
      const auto [n2, m] = rest;
      const double piece = len * m / total_mass;
      const double centre = len * (cumulative + 0.5 * m) / total_mass;
      cumulative += m;
      solid += m * (n2 + sq(t - centre) + piece * piece / 12.0);
      // Hausdorff, pixel -> segment.
      const double tc = std::clamp(t, 0.0, len);
      if (n2 + sq(t - tc) > eps2_) solid_ok = false;
      // Coverage, segment -> pixels: the middle of the gap between consecutive projections.
      const double gap = tc - prev_t;
      max_gap_excess = std::max(max_gap_excess, sq(0.5 * gap) + std::max(n2, prev_n2) - sq(cover_));
      prev_t = tc;
      prev_n2 = n2;
    }
    max_gap_excess = std::max(max_gap_excess, sq(0.5 * (len - prev_t)) + prev_n2 - sq(cover_));
    if (max_gap_excess > 0.0) solid_ok = false;
    ev.solid = solid < ghost;
    ev.cost = ev.solid ? solid : ghost;
    ev.valid = ev.solid ? solid_ok : ghost_ok;
    return ev;
  }

  // The collapse u -> v with v kept in place; when that breaks the Hausdorff bound and u and v both
  // sit inside chains (degree 2), v placed at the intersection of the lines of the two edges that
  // remain (u's other edge and v's other edge). The second placement removes the short bevels a
  // staircase leaves at corners, which no collapse onto an existing vertex can remove.
  // The result lives in scratch_ (reused buffers: no allocation per simulation) until the next call.
  CollapsePlan& plan_collapse(int u, int v) {
    CollapsePlan& plan = simulate(u, v, pos_[v]);
    if (plan.valid || star_[u].size() != 2 || star_[v].size() != 2) return plan;
    const int a = star_[u][0].first == v ? star_[u][1].first : star_[u][0].first;
    const int b = star_[v][0].first == u ? star_[v][1].first : star_[v][0].first;
    if (a == b) return plan;
    const Point2 pa = pos_[a], pu = pos_[u], pv = pos_[v], pb = pos_[b];
    const double d1x = pu.x - pa.x, d1y = pu.y - pa.y, d2x = pv.x - pb.x, d2y = pv.y - pb.y;
    const double denom = d1x * d2y - d1y * d2x;
    const double norms = std::sqrt((d1x * d1x + d1y * d1y) * (d2x * d2x + d2y * d2y));
    if (!(std::abs(denom) > corner_sine_ * norms)) return plan;  // lines within ~10 degrees of parallel
    const double s = ((pb.x - pa.x) * d2y - (pb.y - pa.y) * d2x) / denom;
    const Point2 x{pa.x + s * d1x, pa.y + s * d1y};
    if (!grid_ || grid_->nearest_dist2(x, eps_d_) > eps2_) return plan;
    return simulate(u, v, x);
  }

  // Simulates the collapse u -> v with v moved to `placement`.
  CollapsePlan& simulate(int u, int v, const Point2& placement) {
    struct Restore {
      Point2& slot;
      Point2 saved;
      ~Restore() { slot = saved; }
    } restore{pos_[v], pos_[v]};
    pos_[v] = placement;
    CollapsePlan& plan = scratch_;
    plan.valid = false;
    plan.delta = 0.0;
    plan.neighbours.clear();
    plan.placement = placement;
    double before = 0.0;
    thread_local std::vector<int> pixels;
    pixels.clear();
    for (int w : {u, v}) {
      for (const auto& [n, id] : star_[w]) {
        if (w == v && n == u) continue;  // the edge (u, v) is counted once, from u's side
        before += edges_[id].cost;
        pixels.insert(pixels.end(), edges_[id].pixels.begin(), edges_[id].pixels.end());
        if (n != u && n != v) plan.neighbours.push_back(n);
      }
      for (int p : vertex_pixels_[w]) {
        before += mass_[p] * dist2(px_[p], pos_[w]);
        pixels.push_back(p);
      }
    }
    std::sort(plan.neighbours.begin(), plan.neighbours.end());
    plan.neighbours.erase(std::unique(plan.neighbours.begin(), plan.neighbours.end()), plan.neighbours.end());
    const Point2 pv = pos_[v];
    double after = 0.0;
    if (plan.neighbours.empty()) {
      plan.assigned.resize(1);
      plan.assigned[0] = pixels;
      for (int p : pixels) {
        const double d2 = dist2(px_[p], pv);
        if (d2 > eps2_) return plan;  // invalid
        after += mass_[p] * d2;
      }
    } else {
      plan.assigned.resize(std::max(plan.assigned.size(), plan.neighbours.size()));
      for (auto& a : plan.assigned) a.clear();
      fan_.reset(pv);
      for (int n : plan.neighbours) fan_.add(pos_[n]);
      for (int p : pixels) {
        const auto [best, best_d2] = fan_.nearest(px_[p]);
        if (best_d2 > eps2_) return plan;  // no edge can take this pixel: invalid
        plan.assigned[best].push_back(p);
      }
      plan.evals.resize(plan.neighbours.size());
      for (std::size_t k = 0; k < plan.neighbours.size(); ++k) {
        plan.evals[k] = evaluate(v, plan.neighbours[k], plan.assigned[k]);
        if (!plan.evals[k].valid) return plan;
        after += plan.evals[k].cost;
      }
    }
    plan.delta = after - before;
    plan.valid = true;
    return plan;
  }

  void apply(int u, int v, CollapsePlan& plan) {
    for (int w : {u, v}) {
      for (const auto& [n, id] : star_[w]) {
        if (!edges_[id].alive) continue;
        edges_[id].alive = false;
        total_cost_ -= edges_[id].cost;
        auto& other = star_[n];
        other.erase(
            std::remove_if(other.begin(), other.end(), [id = id](const auto& s) { return s.second == id; }),
            other.end());
      }
      star_[w].clear();
      for (int p : vertex_pixels_[w]) total_cost_ -= mass_[p] * dist2(px_[p], pos_[w]);
      vertex_pixels_[w].clear();
    }
    alive_[u] = false;
    ++version_[v];
    pos_[v] = plan.placement;
    if (plan.neighbours.empty()) {
      vertex_pixels_[v] = std::move(plan.assigned[0]);
      for (int p : vertex_pixels_[v]) total_cost_ += mass_[p] * dist2(px_[p], pos_[v]);
      return;
    }
    for (std::size_t k = 0; k < plan.neighbours.size(); ++k) {
      const int n = plan.neighbours[k];
      const int id = static_cast<int>(edges_.size());
      edges_.push_back(Edge{std::min(v, n), std::max(v, n), std::move(plan.assigned[k]), plan.evals[k].cost,
                            plan.evals[k].solid, true});
      total_cost_ += plan.evals[k].cost;
      star_[v].push_back({n, id});
      star_[n].push_back({v, id});
      ++version_[n];
    }
  }

  void push_best(int u) {
    if (!alive_[u]) return;
    bool found = false;
    QueueEntry best{0.0, u, -1, version_[u], 0};
    auto& memo = memo_[u];
    for (const auto& s : star_[u]) {
      const int v = s.first;
      // A collapse depends only on the stars of u and v (and the positions around them), all of which
      // bump the versions when they change: reuse the last result while the versions match.
      Memo* m = nullptr;
      for (auto& e : memo)
        if (e.v == v) m = &e;
      if (!m) {
        memo.push_back(Memo{v, 0, 0, false, false, 0.0});
        m = &memo.back();
      }
      if (!m->known || m->version_u != version_[u] || m->version_v != version_[v]) {
        const CollapsePlan& plan = plan_collapse(u, v);
        *m = Memo{v, version_[u], version_[v], true, plan.valid, plan.delta};
      }
      if (!m->valid) continue;
      if (!found || m->delta < best.delta || (m->delta == best.delta && v < best.v)) {
        best.delta = m->delta;
        best.v = v;
        found = true;
      }
    }
    if (!found) return;
    best.version_v = version_[best.v];
    queue_.push(best);
    ++entries_[u];
  }

  struct Memo {
    int v;
    std::uint32_t version_u, version_v;
    bool known, valid;
    double delta;
  };

  const std::vector<Point2>& px_;
  const std::vector<double>& mass_;
  const PixelGrid* grid_;
  std::vector<Point2> pos_;
  double eps_d_, eps2_, cover_, budget_;
  double pull_, corner_sine_;                           // PolylineParams::relocate_pull, corner_min_sine
  std::vector<std::vector<std::pair<int, int>>> star_;  // (neighbour, edge id)
  std::vector<Edge> edges_;
  std::vector<std::vector<int>> vertex_pixels_;  // pixels of vertices without edges
  std::vector<char> alive_;
  std::vector<std::uint32_t> version_;
  std::vector<int> entries_;             // queue entries per vertex
  std::vector<std::vector<Memo>> memo_;  // last simulated collapses per vertex
  CollapsePlan scratch_;
  SegmentFan fan_;  // simulate's new edges around v
  mutable std::vector<std::pair<double, std::pair<double, double>>> projections_;  // evaluate's buffer
  std::priority_queue<QueueEntry, std::vector<QueueEntry>, std::greater<QueueEntry>> queue_;
  double total_cost_ = 0.0;
};

// Chains of solid edges between vertices of degree != 2; cycles become closed polylines.
std::vector<Polyline2> trace_polylines(const std::vector<Point2>& pos,
                                       const std::vector<std::pair<int, int>>& edges) {
  std::vector<std::vector<std::pair<int, int>>> adj(pos.size());  // (neighbour, edge index)
  for (std::size_t i = 0; i < edges.size(); ++i) {
    adj[edges[i].first].push_back({edges[i].second, static_cast<int>(i)});
    adj[edges[i].second].push_back({edges[i].first, static_cast<int>(i)});
  }
  for (auto& a : adj) std::sort(a.begin(), a.end());
  std::vector<char> used(edges.size(), 0);
  std::vector<Polyline2> out;
  auto walk = [&](int start, int first_edge) {
    Polyline2 line{pos[start]};
    int at = start, e = first_edge;
    while (true) {
      used[e] = 1;
      at = edges[e].first == at ? edges[e].second : edges[e].first;
      line.push_back(pos[at]);
      if (adj[at].size() != 2 || at == start) break;
      e = adj[at][0].second == e ? adj[at][1].second : adj[at][0].second;
      if (used[e]) break;
    }
    out.push_back(std::move(line));
  };
  for (std::size_t v = 0; v < pos.size(); ++v)
    if (adj[v].size() != 2 && !adj[v].empty())
      for (const auto& [n, e] : adj[v])
        if (!used[e]) walk(static_cast<int>(v), e);
  for (std::size_t v = 0; v < pos.size(); ++v)  // remaining: pure cycles
    for (const auto& [n, e] : adj[v])
      if (!used[e]) walk(static_cast<int>(v), e);
  return out;
}

}  // namespace
}  // namespace detail

std::vector<Polyline2> extract_polylines(const std::vector<Point2>& edge_pixels, const PolylineParams& params,
                                         PolylineStats* stats) {
  using namespace detail;
  params.validate();
  PolylineStats local_stats;
  PolylineStats& st = stats ? *stats : local_stats;
  st = PolylineStats{};

  // Sorted distinct pixels with multiplicities: the result does not depend on the input order.
  std::vector<Point2> sorted = edge_pixels;
  std::sort(sorted.begin(), sorted.end(),
            [](const Point2& a, const Point2& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  std::vector<Point2> pixels;
  std::vector<double> mass;
  for (const Point2& p : sorted) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y))
      throw ReconstructionError(ReconstructionStage::polylines, "edge pixel with a non-finite coordinate");
    if (!pixels.empty() && pixels.back().x == p.x && pixels.back().y == p.y) {
      mass.back() += 1.0;
    } else {
      pixels.push_back(p);
      mass.push_back(1.0);
    }
  }
  st.pixels = pixels.size();
  if (pixels.size() < 2) return {};

  // Delaunay triangulation of the pixels; vertex info = pixel index.
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Vb = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
  using Tds = CGAL::Triangulation_data_structure_2<Vb>;
  using Delaunay = CGAL::Delaunay_triangulation_2<K, Tds>;
  std::vector<std::pair<K::Point_2, int>> input;
  input.reserve(pixels.size());
  for (std::size_t i = 0; i < pixels.size(); ++i)
    input.push_back({K::Point_2(pixels[i].x, pixels[i].y), static_cast<int>(i)});
  Delaunay dt;
  dt.insert(input.begin(), input.end());

  std::vector<std::pair<int, int>> all_edges;
  std::vector<double> nearest(pixels.size(), std::numeric_limits<double>::infinity());
  for (auto e = dt.finite_edges_begin(); e != dt.finite_edges_end(); ++e) {
    const int a = e->first->vertex(Delaunay::cw(e->second))->info();
    const int b = e->first->vertex(Delaunay::ccw(e->second))->info();
    const double d = std::sqrt(dist2(pixels[a], pixels[b]));
    nearest[a] = std::min(nearest[a], d);
    nearest[b] = std::min(nearest[b], d);
    all_edges.push_back({std::min(a, b), std::max(a, b)});
  }
  double r = params.resolution;
  if (r <= 0.0) {
    std::vector<double> finite;
    for (double d : nearest)
      if (std::isfinite(d)) finite.push_back(d);
    if (finite.empty()) return {};
    std::nth_element(finite.begin(), finite.begin() + finite.size() / 2, finite.end());
    r = finite[finite.size() / 2];
  }
  st.resolution = r;
  const double link = params.link_pixels * r;
  std::vector<std::pair<int, int>> links;
  for (const auto& [a, b] : all_edges)
    if (dist2(pixels[a], pixels[b]) <= link * link) links.push_back({a, b});
  std::sort(links.begin(), links.end());
  st.initial_edges = links.size();

  double total_mass = 0.0;
  for (double m : mass) total_mass += m;
  const double budget = sq(params.max_cost * r) * total_mass;  // RMS transport distance <= eps_c pixels
  const double cover = std::max(params.max_hausdorff, 0.5 * link);
  const PixelGrid grid(pixels, params.max_hausdorff);
  Simplifier simplifier(pixels, mass, params.max_hausdorff, cover, budget, params.relocate ? &grid : nullptr,
                        params);
  simplifier.build(links);
  // Relocation can unblock collapses (a corner bevel whose vertices moved onto the fitted lines), so
  // collapse and relocate again until nothing changes (a few rounds at most: relocate_rounds).
  for (std::size_t round = 0; round < params.relocate_rounds; ++round) {
    const std::size_t done = simplifier.run();
    st.collapses += done;
    if (!params.relocate || (round > 0 && done == 0)) break;
    simplifier.relocate_all();
  }
  st.rms_transport = std::sqrt(std::max(0.0, simplifier.total_cost()) / total_mass);
  st.max_pixel_distance = simplifier.max_pixel_distance();

  // Edge filtering: solid edges only, and only connected groups long enough.
  const auto& pos = simplifier.positions();
  std::vector<std::pair<int, int>> solid;
  for (const auto& e : simplifier.edges())
    if (e.alive && e.solid) solid.push_back({e.a, e.b});
  std::sort(solid.begin(), solid.end());
  detail::UnionFind groups(pos.size());
  for (const auto& [a, b] : solid) groups.join(a, b);
  std::unordered_map<std::size_t, double> group_length;
  for (const auto& [a, b] : solid) group_length[groups.find(a)] += std::sqrt(dist2(pos[a], pos[b]));
  std::vector<std::pair<int, int>> kept;
  for (const auto& [a, b] : solid)
    if (group_length[groups.find(a)] >= params.min_polyline_length) kept.push_back({a, b});
  st.filtered_edges = solid.size() - kept.size();

  std::vector<Polyline2> polylines = trace_polylines(pos, kept);
  log_debug("polylines: " + std::to_string(polylines.size()) + " polylines from " +
            std::to_string(pixels.size()) + " pixels (" + std::to_string(st.collapses) +
            " collapses, r = " + std::to_string(r) + " m)");
  return polylines;
}

}  // namespace city3d
