// LoD1 block: footprint polygons extruded between two heights into a closed polygonal solid. Caps of
// polygons with holes are split into convex pieces (hole bridging, ear clipping, Hertel-Mehlhorn
// merging) that only use ring vertices, so the walls and caps meet without T-junctions.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <utility>

#include "city3d/error.hpp"
#include "city3d/lod1.hpp"
#include "city3d/model_io.hpp"

namespace city3d {
namespace {

// Moves the sorted `from` into the sorted `into`, which stays sorted.
template <typename T>
void merge_sorted(std::vector<T>& into, std::vector<T>& from) {
  std::vector<T> out;
  out.reserve(into.size() + from.size());
  std::merge(into.begin(), into.end(), from.begin(), from.end(), std::back_inserter(out));
  into = std::move(out);
  std::vector<T>().swap(from);
}

using Loop = std::vector<std::uint32_t>;  // indices into the polygon's 2D vertices

double orient(const Point2& a, const Point2& b, const Point2& c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

double signed_area(const Ring2& ring) {
  double twice = 0.0;
  for (std::size_t k = 0; k < ring.size(); ++k) {
    const Point2& a = ring[k];
    const Point2& b = ring[(k + 1) % ring.size()];
    twice += (a.x - b.x) * (a.y + b.y);
  }
  return 0.5 * twice;  // trapezoid sum: (x_k - x_k+1)(y_k + y_k+1) totals twice the CCW area
}

bool same(const Point2& a, const Point2& b) { return a.x == b.x && a.y == b.y; }

/// Drops repeated consecutive vertices (and a repeated closing vertex) and orients the ring.
Ring2 clean_ring(const Ring2& ring, bool counter_clockwise, const std::string& what, const BuildingId& id) {
  Ring2 out;
  for (const Point2& v : ring) {
    if (!std::isfinite(v.x) || !std::isfinite(v.y))
      throw ReconstructionError(ReconstructionStage::lod1, "building " + id + ": " + what + " has a non-finite vertex");
    if (out.empty() || !same(out.back(), v)) out.push_back(v);
  }
  while (out.size() > 1 && same(out.front(), out.back())) out.pop_back();
  if (out.size() < 3)
    throw ReconstructionError(ReconstructionStage::lod1, "building " + id + ": " + what + " has " + std::to_string(out.size()) +
                              " distinct vertices, need 3");
  const double area = signed_area(out);
  if (area == 0.0) throw ReconstructionError(ReconstructionStage::lod1, "building " + id + ": " + what + " has no area");
  if ((area > 0.0) != counter_clockwise) std::reverse(out.begin(), out.end());
  return out;
}

/// Interior of the loop at corner (a, b, c) (interior on the left) contains the direction b -> q.
bool locally_inside(const Point2& a, const Point2& b, const Point2& c, const Point2& q) {
  if (orient(a, b, c) >= 0.0) return orient(a, b, q) > 0.0 && orient(b, c, q) > 0.0;
  return orient(a, b, q) > 0.0 || orient(b, c, q) > 0.0;
}

/// Closed segments pq and rs share at least one point.
bool segments_touch(const Point2& p, const Point2& q, const Point2& r, const Point2& s) {
  auto on_segment = [](const Point2& a, const Point2& b, const Point2& c) {  // c on ab, given collinear
    return std::min(a.x, b.x) <= c.x && c.x <= std::max(a.x, b.x) && std::min(a.y, b.y) <= c.y &&
           c.y <= std::max(a.y, b.y);
  };
  const double d1 = orient(p, q, r), d2 = orient(p, q, s), d3 = orient(r, s, p), d4 = orient(r, s, q);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
  return (d1 == 0 && on_segment(p, q, r)) || (d2 == 0 && on_segment(p, q, s)) ||
         (d3 == 0 && on_segment(r, s, p)) || (d4 == 0 && on_segment(r, s, q));
}

/// The bridge segment from vertex v to hole vertex m is usable when no edge other than those at v
/// or m touches it, and no vertex lies on it.
bool bridge_is_clear(const std::vector<Point2>& pts, const std::vector<const Loop*>& loops, std::uint32_t v,
                     std::uint32_t m) {
  for (const Loop* loop : loops) {
    for (std::size_t k = 0; k < loop->size(); ++k) {
      const std::uint32_t a = (*loop)[k], b = (*loop)[(k + 1) % loop->size()];
      const bool at_v = a == v || b == v, at_m = a == m || b == m;
      if (at_v && at_m) continue;  // the bridge itself, once merged
      if (at_v || at_m) {
        // Sharing an endpoint: only a collinear overlap blocks the bridge.
        const std::uint32_t other = (a == v || a == m) ? b : a;
        const Point2& o = pts[other];
        if (orient(pts[v], pts[m], o) == 0.0 &&
            (o.x - pts[v].x) * (pts[m].x - pts[v].x) + (o.y - pts[v].y) * (pts[m].y - pts[v].y) > 0.0 &&
            (o.x - pts[m].x) * (pts[v].x - pts[m].x) + (o.y - pts[m].y) * (pts[v].y - pts[m].y) > 0.0)
          return false;
        continue;
      }
      if (segments_touch(pts[v], pts[m], pts[a], pts[b])) return false;
    }
  }
  return true;
}

/// Merges the holes (clockwise) into the outer loop (counter-clockwise) with zero-width bridges, in
/// decreasing order of each hole's rightmost vertex (Eberly, "Triangulation by Ear Clipping"). The
/// bridge goes to the nearest outer vertex that sees the hole's rightmost vertex, tested by brute
/// force, which is fine at footprint sizes.
Loop bridge_holes(const std::vector<Point2>& pts, Loop outer, std::vector<Loop> holes, const BuildingId& id) {
  auto rightmost = [&](const Loop& loop) {
    std::size_t best = 0;
    for (std::size_t k = 1; k < loop.size(); ++k) {
      const Point2 &p = pts[loop[k]], &b = pts[loop[best]];
      if (p.x > b.x || (p.x == b.x && p.y > b.y)) best = k;
    }
    return best;
  };
  std::stable_sort(holes.begin(), holes.end(), [&](const Loop& l, const Loop& r) {
    const Point2 &a = pts[l[rightmost(l)]], &b = pts[r[rightmost(r)]];
    return a.x > b.x || (a.x == b.x && a.y > b.y);
  });
  for (std::size_t h = 0; h < holes.size(); ++h) {
    Loop& hole = holes[h];
    std::rotate(hole.begin(), hole.begin() + static_cast<std::ptrdiff_t>(rightmost(hole)), hole.end());
    const std::uint32_t m = hole[0];
    const Point2& mp = pts[m];

    std::vector<const Loop*> obstacles{&outer};
    for (std::size_t k = h; k < holes.size(); ++k) obstacles.push_back(&holes[k]);

    std::vector<std::size_t> order(outer.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    auto distance2 = [&](std::size_t k) {
      const Point2& p = pts[outer[k]];
      return (p.x - mp.x) * (p.x - mp.x) + (p.y - mp.y) * (p.y - mp.y);
    };
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t l, std::size_t r) { return distance2(l) < distance2(r); });

    bool bridged = false;
    for (std::size_t k : order) {
      const std::uint32_t v = outer[k];
      const Point2& vp = pts[v];
      if (same(vp, mp)) continue;
      const Point2& before = pts[outer[(k + outer.size() - 1) % outer.size()]];
      const Point2& after = pts[outer[(k + 1) % outer.size()]];
      if (!locally_inside(before, vp, after, mp)) continue;
      if (!locally_inside(pts[hole.back()], mp, pts[hole[1]], vp)) continue;
      if (!bridge_is_clear(pts, obstacles, v, m)) continue;
      // outer[..k] (ends at v), the hole from m around to m, v again, outer[k+1..].
      Loop merged(outer.begin(), outer.begin() + static_cast<std::ptrdiff_t>(k) + 1);
      merged.insert(merged.end(), hole.begin(), hole.end());
      merged.push_back(m);
      merged.push_back(v);
      merged.insert(merged.end(), outer.begin() + static_cast<std::ptrdiff_t>(k) + 1, outer.end());
      outer = std::move(merged);
      bridged = true;
      break;
    }
    if (!bridged)
      throw ReconstructionError(ReconstructionStage::lod1, "building " + id +
                                ": cannot connect a hole to the outer ring "
                                "(rings intersect or touch)");
  }
  return outer;
}

/// Ear clipping of a (weakly) simple counter-clockwise loop. An ear's triangle must be strictly
/// convex and hold no other vertex inside or on its boundary, so no vertex ends up on a diagonal.
std::vector<Loop> ear_clip(const std::vector<Point2>& pts, const Loop& loop, const BuildingId& id) {
  const std::size_t n = loop.size();
  std::vector<std::size_t> prev(n), next(n);
  for (std::size_t k = 0; k < n; ++k) {
    prev[k] = (k + n - 1) % n;
    next[k] = (k + 1) % n;
  }
  auto is_ear = [&](std::size_t c) {
    const std::uint32_t ia = loop[prev[c]], ib = loop[c], ic = loop[next[c]];
    const Point2 &a = pts[ia], &b = pts[ib], &cc = pts[ic];
    if (orient(a, b, cc) <= 0.0) return false;
    for (std::size_t k = next[next[c]]; k != prev[c]; k = next[k]) {
      const std::uint32_t iq = loop[k];
      if (iq == ia || iq == ib || iq == ic) continue;
      const Point2& q = pts[iq];
      if (orient(a, b, q) >= 0.0 && orient(b, cc, q) >= 0.0 && orient(cc, a, q) >= 0.0) return false;
    }
    return true;
  };
  std::vector<Loop> triangles;
  std::size_t remaining = n, current = 0, failures = 0;
  while (remaining > 3) {
    if (is_ear(current)) {
      triangles.push_back({loop[prev[current]], loop[current], loop[next[current]]});
      next[prev[current]] = next[current];
      prev[next[current]] = prev[current];
      current = prev[current];
      --remaining;
      failures = 0;
    } else {
      current = next[current];
      if (++failures > remaining)
        throw ReconstructionError(ReconstructionStage::lod1, "building " + id + ": cannot split a roof with holes (no ear among " +
                                  std::to_string(remaining) + " vertices; self-intersecting rings?)");
    }
  }
  if (orient(pts[loop[prev[current]]], pts[loop[current]], pts[loop[next[current]]]) <= 0.0)
    throw ReconstructionError(ReconstructionStage::lod1, "building " + id + ": roof with holes ends in a degenerate triangle");
  triangles.push_back({loop[prev[current]], loop[current], loop[next[current]]});
  return triangles;
}

/// Hertel-Mehlhorn: removes diagonals while both of their ends stay strictly convex, giving convex
/// pieces (at most four times the minimum number). Pieces share only whole edges.
std::vector<Loop> merge_convex(const std::vector<Point2>& pts, std::vector<Loop> pieces) {
  auto key = [](std::uint32_t a, std::uint32_t b) { return (std::uint64_t{a} << 32) | b; };
  std::map<std::uint64_t, std::size_t> owner;  // directed edge -> piece
  for (std::size_t p = 0; p < pieces.size(); ++p)
    for (std::size_t k = 0; k < pieces[p].size(); ++k)
      owner[key(pieces[p][k], pieces[p][(k + 1) % pieces[p].size()])] = p;
  std::vector<bool> alive(pieces.size(), true);

  // Candidate diagonals in a fixed order: the edges of the triangles as ear clipping produced them.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> diagonals;
  for (const Loop& t : pieces)
    for (std::size_t k = 0; k < t.size(); ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % t.size()];
      if (a < b && owner.count(key(b, a))) diagonals.push_back({a, b});
    }
  for (const auto& [a, b] : diagonals) {
    const std::size_t pa = owner.at(key(a, b)), pb = owner.at(key(b, a));
    if (pa == pb) continue;
    Loop first = pieces[pa], second = pieces[pb];
    // first = [b, ..., a], second = [a, ..., b].
    std::rotate(first.begin(), std::find(first.begin(), first.end(), b), first.end());
    std::rotate(second.begin(), std::find(second.begin(), second.end(), a), second.end());
    if (first.back() != a || second.back() != b) continue;
    const Point2 &pa_prev = pts[first[first.size() - 2]], &pa_next = pts[second[1]];
    const Point2 &pb_prev = pts[second[second.size() - 2]], &pb_next = pts[first[1]];
    if (orient(pa_prev, pts[a], pa_next) <= 0.0 || orient(pb_prev, pts[b], pb_next) <= 0.0) continue;
    Loop merged = first;
    merged.insert(merged.end(), second.begin() + 1, second.end() - 1);
    owner.erase(key(a, b));
    owner.erase(key(b, a));
    pieces[pa] = merged;
    alive[pb] = false;
    for (std::size_t k = 0; k < merged.size(); ++k)
      owner[key(merged[k], merged[(k + 1) % merged.size()])] = pa;
  }
  std::vector<Loop> out;
  for (std::size_t p = 0; p < pieces.size(); ++p)
    if (alive[p]) out.push_back(std::move(pieces[p]));
  return out;
}

}  // namespace

void Lod1Params::validate() const {
  std::vector<std::string> problems;
  if (!(roof_percentile >= 0.0 && roof_percentile <= 100.0))
    problems.push_back("roof_percentile = " + std::to_string(roof_percentile) + " (0-100)");
  if (!(min_height > 0.0) || !std::isfinite(min_height))
    problems.push_back("min_height = " + std::to_string(min_height) + " (metres, > 0)");
  if (!(join_distance > 0.0) || !std::isfinite(join_distance))
    problems.push_back("join_distance = " + std::to_string(join_distance) + " (metres, > 0)");
  if (problems.empty()) return;
  std::string message = "lod1: invalid parameters: ";
  for (std::size_t i = 0; i < problems.size(); ++i) message += (i ? "; " : "") + problems[i];
  throw ConfigError(message);
}

Lod1Heights lod1_heights(const BuildingInput& input, const Lod1Params& params) {
  params.validate();
  if (input.points.empty()) throw ReconstructionError(ReconstructionStage::lod1, "building " + input.id + " has no points");
  std::vector<double> heights;
  heights.reserve(input.points.size());
  for (const Point3& p : input.points) heights.push_back(p.z);
  Lod1Heights h;
  h.floor_z = input.ground_z;
  h.roof_z = percentile(heights, params.roof_percentile);
  if (h.roof_z < h.floor_z + params.min_height) {
    std::ostringstream note;
    note << "roof raised from " << h.roof_z << " to " << h.floor_z + params.min_height << " (min_height "
         << params.min_height << " m above ground " << h.floor_z << ")";
    h.note = note.str();
    h.roof_z = h.floor_z + params.min_height;
  }
  return h;
}

PolygonMesh extrude_polygons(const std::vector<Polygon2>& polygons, double floor_z, double roof_z,
                             const BuildingId& id) {
  if (!(roof_z > floor_z))
    throw ReconstructionError(ReconstructionStage::lod1, "building " + id + ": roof z " + std::to_string(roof_z) +
                              " is not above floor z " + std::to_string(floor_z));
  PolygonMesh mesh;
  for (std::size_t p = 0; p < polygons.size(); ++p) {
    const std::string name = "polygon " + std::to_string(p);
    // Flatten the rings into one vertex list; loops index into it.
    std::vector<Point2> pts;
    Loop outer;
    std::vector<Loop> holes;
    auto add_ring = [&](const Ring2& ring) {
      Loop loop;
      for (const Point2& v : ring) {
        loop.push_back(static_cast<std::uint32_t>(pts.size()));
        pts.push_back(v);
      }
      return loop;
    };
    outer = add_ring(clean_ring(polygons[p].outer, true, name + " outer ring", id));
    for (std::size_t h = 0; h < polygons[p].holes.size(); ++h)
      holes.push_back(
          add_ring(clean_ring(polygons[p].holes[h], false, name + " hole " + std::to_string(h), id)));

    // Vertex k of the polygon is mesh vertex base + k at the floor and base + n + k at the roof.
    const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
    const auto n = static_cast<std::uint32_t>(pts.size());
    for (const Point2& v : pts) mesh.vertices.push_back({v.x, v.y, floor_z});
    for (const Point2& v : pts) mesh.vertices.push_back({v.x, v.y, roof_z});
    const auto bottom = [&](std::uint32_t k) { return base + k; };
    const auto top = [&](std::uint32_t k) { return base + n + k; };

    // Walls: the solid lies left of every ring edge (outer CCW, holes CW), so the quad
    // (bottom a, bottom b, top b, top a) faces right of the edge: out of the solid.
    auto add_walls = [&](const Loop& loop) {
      for (std::size_t k = 0; k < loop.size(); ++k) {
        const std::uint32_t a = loop[k], b = loop[(k + 1) % loop.size()];
        mesh.faces.push_back({bottom(a), bottom(b), top(b), top(a)});
      }
    };
    add_walls(outer);
    for (const Loop& hole : holes) add_walls(hole);

    std::vector<Loop> caps;
    if (holes.empty()) {
      caps.push_back(outer);
    } else {
      caps = merge_convex(pts, ear_clip(pts, bridge_holes(pts, outer, holes, id), id));
    }
    for (const Loop& cap : caps) {  // roof: counter-clockwise from above
      std::vector<std::uint32_t> face;
      for (std::uint32_t k : cap) face.push_back(top(k));
      mesh.faces.push_back(std::move(face));
    }
    for (const Loop& cap : caps) {  // floor: the same pieces reversed, facing down
      std::vector<std::uint32_t> face;
      for (auto it = cap.rbegin(); it != cap.rend(); ++it) face.push_back(bottom(*it));
      mesh.faces.push_back(std::move(face));
    }
  }
  return mesh;
}

BuildingModel make_lod1_block(const BuildingInput& input, const Lod1Params& params) {
  const Lod1Heights heights = lod1_heights(input, params);
  BuildingModel model;
  model.id = input.id;
  model.origin = input.origin;
  model.mesh = extrude_polygons(input.footprint.polygons, heights.floor_z, heights.roof_z, input.id);
  return model;
}

}  // namespace city3d

// LoD1.3 (and LoD1.2 from an LoD2 outline): the roof parts of an LoD2 model, clustered by height
// and extruded, with step walls between clusters.
namespace city3d {
namespace {

struct Key2 {
  double x, y;
  bool operator<(const Key2& o) const { return x < o.x || (x == o.x && y < o.y); }
};

// Distance from p to segment ab, and the parameter of its projection.
double segment_distance(const Point2& a, const Point2& b, const Point2& p, double& t) {
  const double dx = b.x - a.x, dy = b.y - a.y, l2 = dx * dx + dy * dy;
  t = l2 > 0 ? ((p.x - a.x) * dx + (p.y - a.y) * dy) / l2 : 0.0;
  const double cx = a.x + t * dx - p.x, cy = a.y + t * dy - p.y;
  return std::sqrt(cx * cx + cy * cy);
}

bool inside_ring(const std::vector<Point2>& ring, double x, double y) {
  bool in = false;
  for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) {
    const Point2 &a = ring[i], &b = ring[j];
    if ((a.y > y) != (b.y > y) && x < a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y)) in = !in;
  }
  return in;
}

// The boundary loops of a set of parts (directed edges whose reverse is not in the set), when every
// vertex has one outgoing boundary edge and every loop is counter-clockwise; else empty.
std::vector<Loop> boundary_loops(const std::vector<Loop>& parts, const std::vector<std::size_t>& members,
                                 const std::vector<Point2>& pts) {
  std::set<std::pair<std::uint32_t, std::uint32_t>> edges;
  for (std::size_t p : members)
    for (std::size_t k = 0; k < parts[p].size(); ++k) edges.insert({parts[p][k], parts[p][(k + 1) % parts[p].size()]});
  std::map<std::uint32_t, std::uint32_t> next;
  for (const auto& e : edges) {
    if (edges.count({e.second, e.first})) continue;
    if (!next.emplace(e.first, e.second).second) return {};  // a pinch: two loops through one vertex
  }
  std::vector<Loop> loops;
  std::set<std::uint32_t> used;
  for (const auto& [start, unused] : next) {
    if (used.count(start)) continue;
    Loop loop;
    for (std::uint32_t v = start; !used.count(v);) {
      used.insert(v);
      loop.push_back(v);
      const auto it = next.find(v);
      if (it == next.end()) return {};
      v = it->second;
    }
    if (loop.size() < 3 || loop.front() != next.at(loop.back())) return {};
    Ring2 ring;
    for (std::uint32_t v : loop) ring.push_back(pts[v]);
    if (signed_area(ring) <= 0) return {};  // a hole: a face of one ring cannot have it
    loops.push_back(std::move(loop));
  }
  return loops;
}

}  // namespace

Lod13Parts lod13_parts(const BuildingModel& lod22, const std::vector<Point3>& points, double join_distance) {
  const std::vector<SurfaceType> types = surface_types(lod22);
  Lod13Parts out;
  out.id = lod22.id;
  out.origin = lod22.origin;
  // Plan-view vertices (equal x, y are one vertex) and the roof parts as loops of them.
  std::vector<Point2>& pts = out.pts;
  std::map<Key2, std::uint32_t> index_of;
  std::vector<Loop>& parts = out.parts;
  std::vector<double>& mean_z = out.mean_z;
  for (std::size_t f = 0; f < lod22.mesh.faces.size(); ++f) {
    if (types[f] != SurfaceType::roof) continue;
    Loop loop;
    double z = 0;
    for (std::uint32_t i : lod22.mesh.faces[f]) {
      const Point3& p = lod22.mesh.vertices[i];
      z += p.z;
      const auto [it, fresh] = index_of.emplace(Key2{p.x, p.y}, static_cast<std::uint32_t>(pts.size()));
      if (fresh) pts.push_back({p.x, p.y});
      if (loop.empty() || loop.back() != it->second) loop.push_back(it->second);
    }
    while (loop.size() > 1 && loop.front() == loop.back()) loop.pop_back();
    Ring2 ring;
    for (std::uint32_t v : loop) ring.push_back(pts[v]);
    if (loop.size() < 3 || signed_area(ring) <= 0) continue;  // seen edge-on or from below: not a roof part
    parts.push_back(std::move(loop));
    mean_z.push_back(z / lod22.mesh.faces[f].size());
  }
  if (parts.empty()) throw ReconstructionError(ReconstructionStage::lod13, "building " + lod22.id + ": the LoD2 model has no roof face");

  // Plan-view vertices lying on another part's edge split that edge, so neighbouring parts share
  // whole edges (a low roof's eave edge against the vertices of the taller part's step wall). "On"
  // within join_distance (half a millimetre by default: the vertices are rounded to the 0.1 mm output
  // grid), but not as near an end of the edge: that is a corner of its own, which would split both
  // edges there.
  for (Loop& loop : parts) {
    Loop split;
    for (std::size_t k = 0; k < loop.size(); ++k) {
      const Point2 &a = pts[loop[k]], &b = pts[loop[(k + 1) % loop.size()]];
      split.push_back(loop[k]);
      std::vector<std::pair<double, std::uint32_t>> between;
      for (std::uint32_t v = 0; v < pts.size(); ++v) {
        if (v == loop[k] || v == loop[(k + 1) % loop.size()]) continue;
        double t = 0;
        if (segment_distance(a, b, pts[v], t) < join_distance && t > 0 && t < 1 &&
            std::hypot(pts[v].x - a.x, pts[v].y - a.y) >= join_distance &&
            std::hypot(pts[v].x - b.x, pts[v].y - b.y) >= join_distance)
          between.push_back({t, v});
      }
      std::sort(between.begin(), between.end());
      for (const auto& [t, v] : between) split.push_back(v);
    }
    loop = std::move(split);
  }

  // Heights: the points above each part.
  std::vector<std::vector<double>>& part_z = out.part_z;
  part_z.resize(parts.size());
  std::vector<std::vector<Point2>> rings(parts.size());
  std::vector<Box2> boxes(parts.size());
  for (std::size_t p = 0; p < parts.size(); ++p)
    for (std::uint32_t v : parts[p]) {
      rings[p].push_back(pts[v]);
      boxes[p].add(pts[v]);
    }
  for (const Point3& q : points)
    for (std::size_t p = 0; p < parts.size(); ++p) {
      if (q.x < boxes[p].min.x || q.x > boxes[p].max.x || q.y < boxes[p].min.y || q.y > boxes[p].max.y) continue;
      if (inside_ring(rings[p], q.x, q.y)) {
        part_z[p].push_back(q.z);
        break;
      }
    }
  out.area.resize(parts.size());
  for (std::size_t p = 0; p < parts.size(); ++p) out.area[p] = signed_area(rings[p]);

  // Adjacent parts (a shared edge in plan view).
  for (std::size_t p = 0; p < parts.size(); ++p)
    for (std::size_t k = 0; k < parts[p].size(); ++k)
      out.part_of_edge[{parts[p][k], parts[p][(k + 1) % parts[p].size()]}] = p;
  for (const auto& [e, p] : out.part_of_edge) {
    const auto it = out.part_of_edge.find({e.second, e.first});
    if (it != out.part_of_edge.end() && it->second != p) out.adjacent.insert(std::minmax(p, it->second));
  }
  return out;
}

BuildingModel make_lod13_blocks(const Lod13Parts& roof, double floor_z, double step_height,
                                double roof_percentile, double min_height, bool no_overlapping_walls) {
  const std::vector<Point2>& pts = roof.pts;
  const std::vector<Loop>& parts = roof.parts;
  const std::vector<double>& mean_z = roof.mean_z;
  const std::vector<double>& area = roof.area;
  const std::vector<std::vector<double>>& part_z = roof.part_z;
  const auto& part_of_edge = roof.part_of_edge;
  const auto& adjacent = roof.adjacent;

  // Clusters: merge the adjacent pair of clusters with the smallest height difference while it is
  // below the step height. A cluster keeps its parts (ascending) and its points' heights sorted, so
  // that a merge is a merge of sorted lists and its height needs no selection over all of them.
  std::vector<std::size_t> cluster(parts.size());
  std::vector<std::vector<std::size_t>> members(parts.size());
  std::vector<std::vector<double>> sorted_z(parts.size());
  for (std::size_t p = 0; p < parts.size(); ++p) {
    cluster[p] = p;
    members[p] = {p};
    sorted_z[p] = part_z[p];
    std::sort(sorted_z[p].begin(), sorted_z[p].end());
  }
  const auto cluster_height = [&](std::size_t c) {
    if (!sorted_z[c].empty()) return sorted_percentile(sorted_z[c], roof_percentile);
    double weighted = 0, total = 0;
    for (std::size_t p : members[c]) {
      weighted += mean_z[p] * area[p];
      total += area[p];
    }
    return weighted / total;
  };
  const auto merge_into = [&](std::size_t into, std::size_t from) {
    for (std::size_t p : members[from]) cluster[p] = into;
    merge_sorted(members[into], members[from]);
    merge_sorted(sorted_z[into], sorted_z[from]);
  };
  std::map<std::size_t, double> height;
  for (std::size_t p = 0; p < parts.size(); ++p) height[p] = cluster_height(p);
  for (;;) {
    double best = step_height;
    std::pair<std::size_t, std::size_t> pair{0, 0};
    bool found = false;
    for (const auto& [a, b] : adjacent) {
      const std::size_t ca = cluster[a], cb = cluster[b];
      if (ca == cb) continue;
      const double d = std::fabs(height[ca] - height[cb]);
      if (d < best) {
        best = d;
        pair = std::minmax(ca, cb);
        found = true;
      }
    }
    if (!found) break;
    merge_into(pair.first, pair.second);
    height.erase(pair.second);
    height[pair.first] = cluster_height(pair.first);
  }
  if (no_overlapping_walls) {
    // The walls through a vertex run on its column from the lower side's height (the floor outside)
    // to the taller part's. Where more than two of them overlap (heights A, B, A, B around the vertex,
    // or high, low, higher, low) the column has an edge of more than two faces. The part across the
    // wall of least height there, the first of equals, joins the taller part's cluster; again until no
    // column has such an edge (at most a round per part).
    const auto top_of = [&](std::size_t p) { return std::max(height[cluster[p]], floor_z + min_height); };
    struct Wall {
      double bottom, top;
      std::size_t part, across;  // across = parts.size(): outside
    };
    for (std::size_t round = 0; round < parts.size(); ++round) {
      std::map<std::uint32_t, std::vector<Wall>> walls_at;
      for (std::size_t p = 0; p < parts.size(); ++p)
        for (std::size_t k = 0; k < parts[p].size(); ++k) {
          const std::uint32_t a = parts[p][k], b = parts[p][(k + 1) % parts[p].size()];
          const auto across = part_of_edge.find({b, a});
          const double bottom = across == part_of_edge.end() ? floor_z : top_of(across->second);
          if (!(bottom < top_of(p))) continue;
          const Wall wall{bottom, top_of(p), p, across == part_of_edge.end() ? parts.size() : across->second};
          walls_at[a].push_back(wall);
          walls_at[b].push_back(wall);
        }
      const Wall* joining = nullptr;
      for (const auto& [v, walls] : walls_at) {
        if (walls.size() < 3) continue;
        std::vector<std::pair<double, int>> events;  // (height, +1 a wall begins / -1 it ends), ends first
        for (const Wall& w : walls) events.push_back({w.bottom, 1}), events.push_back({w.top, -1});
        std::sort(events.begin(), events.end());
        int open = 0, most = 0;
        for (const auto& [z, change] : events) most = std::max(most, open += change);
        if (most <= 2) continue;
        for (const Wall& w : walls)
          if (w.across < parts.size() &&
              (!joining || w.top - w.bottom < joining->top - joining->bottom ||
               (w.top - w.bottom == joining->top - joining->bottom &&
                std::make_pair(w.part, w.across) < std::make_pair(joining->part, joining->across))))
            joining = &w;
        if (joining) break;
      }
      if (!joining) break;
      const std::size_t best = joining->across, into = cluster[joining->part];
      const std::size_t from = cluster[best];
      members[from].erase(std::find(members[from].begin(), members[from].end(), best));
      sorted_z[from].clear();
      for (std::size_t p : members[from])
        sorted_z[from].insert(sorted_z[from].end(), part_z[p].begin(), part_z[p].end());
      std::sort(sorted_z[from].begin(), sorted_z[from].end());
      if (members[from].empty())
        height.erase(from);
      else
        height[from] = cluster_height(from);
      std::vector<std::size_t> part{best};
      std::vector<double> z = part_z[best];
      std::sort(z.begin(), z.end());
      cluster[best] = into;
      merge_sorted(members[into], part);
      merge_sorted(sorted_z[into], z);
      height[into] = cluster_height(into);
    }
  }
  for (auto& [c, h] : height) h = std::max(h, floor_z + min_height);

  // The mesh: a column of vertices over every plan-view vertex (the floor and each incident
  // cluster's height), roofs, floors and walls through every column vertex they pass.
  BuildingModel out;
  out.id = roof.id;
  out.origin = roof.origin;
  std::map<std::pair<std::uint32_t, double>, std::uint32_t> vertex_of;
  std::vector<std::set<double>> column(pts.size());
  for (std::size_t p = 0; p < parts.size(); ++p)
    for (std::uint32_t v : parts[p]) {
      column[v].insert(floor_z);
      column[v].insert(height[cluster[p]]);
    }
  const auto vertex = [&](std::uint32_t v, double z) {
    const auto [it, fresh] = vertex_of.emplace(std::make_pair(v, z), static_cast<std::uint32_t>(out.mesh.vertices.size()));
    if (fresh) out.mesh.vertices.push_back({pts[v].x, pts[v].y, z});
    return it->second;
  };
  const auto add_face = [&](std::vector<std::uint32_t> face, SurfaceType type) {
    out.mesh.faces.push_back(std::move(face));
    out.surfaces.push_back(type);
  };
  // Roofs: one face per cluster loop when the cluster's outline is a set of simple loops, else one
  // per part.
  std::vector<std::size_t> cluster_ids;
  for (const auto& [c, h] : height) cluster_ids.push_back(c);
  for (std::size_t c : cluster_ids) {
    std::vector<std::size_t> members;
    for (std::size_t p = 0; p < parts.size(); ++p)
      if (cluster[p] == c) members.push_back(p);
    std::vector<Loop> loops = boundary_loops(parts, members, pts);
    if (loops.empty())
      for (std::size_t p : members) loops.push_back(parts[p]);
    for (const Loop& loop : loops) {
      std::vector<std::uint32_t> face;
      for (std::uint32_t v : loop) face.push_back(vertex(v, height[c]));
      add_face(std::move(face), SurfaceType::roof);
    }
  }
  // Floors: the outline of all parts, facing down.
  {
    std::vector<std::size_t> all(parts.size());
    for (std::size_t p = 0; p < parts.size(); ++p) all[p] = p;
    std::vector<Loop> loops = boundary_loops(parts, all, pts);
    if (loops.empty()) loops = parts;
    for (const Loop& loop : loops) {
      std::vector<std::uint32_t> face;
      for (auto it = loop.rbegin(); it != loop.rend(); ++it) face.push_back(vertex(*it, floor_z));
      add_face(std::move(face), SurfaceType::ground);
    }
  }
  // Walls: right of every part edge (outward), from the neighbour's height (the floor on the outline)
  // up to the part's, when the part is the taller one.
  for (std::size_t p = 0; p < parts.size(); ++p) {
    const double top = height[cluster[p]];
    for (std::size_t k = 0; k < parts[p].size(); ++k) {
      const std::uint32_t a = parts[p][k], b = parts[p][(k + 1) % parts[p].size()];
      const auto it = part_of_edge.find({b, a});
      const double bottom = it == part_of_edge.end() ? floor_z : height[cluster[it->second]];
      if (!(bottom < top)) continue;
      std::vector<std::uint32_t> face{vertex(a, bottom)};
      for (auto z = column[b].lower_bound(bottom); z != column[b].end() && *z <= top; ++z) face.push_back(vertex(b, *z));
      for (auto z = column[a].upper_bound(top); z != column[a].begin();) {
        --z;
        if (*z <= bottom) break;
        face.push_back(vertex(a, *z));
      }
      add_face(std::move(face), SurfaceType::wall);
    }
  }
  return out;
}

BuildingModel make_lod13_blocks(const BuildingModel& lod22, const std::vector<Point3>& points, double floor_z,
                                double step_height, double roof_percentile, double min_height) {
  return make_lod13_blocks(lod13_parts(lod22, points), floor_z, step_height, roof_percentile, min_height);
}

}  // namespace city3d
