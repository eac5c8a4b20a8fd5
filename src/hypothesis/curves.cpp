// Face hypothesis, step 1: the input curves of the 2D arrangement (paper section 3.3: the roof planes
// are intersected pairwise, and the faces cropped by the outer walls). The footprint rings are the
// outer walls; the inner walls are extended at both ends; every pair of roof planes gives its
// intersection line only where both planes have points nearby (otherwise every pair would cut the
// whole footprint); nearly coincident lines are merged; dangling ends are extended to the next curve.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/log.hpp"
#include "hypothesis/steps.hpp"

namespace city3d::detail {
namespace {

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

// The xy projection of the intersection line of roof planes si and sj (where their heights are
// equal), clipped to where both planes have points within line_support_margin (xy) of it: each
// plane's nearby points are projected onto the line and the two intervals intersected; the result is
// extended by line_support_margin at both ends. Appends nothing for (nearly) parallel planes, or
// when the intervals do not overlap by min_line_overlap.
void clip_roof_line(const std::vector<Point3>& points, const PlanarSegment& si, const PlanarSegment& sj,
                    const HypothesisParams& params, std::vector<InputCurve>& roof_lines) {
  const double margin = params.line_support_margin;
  const Plane3& p = si.plane;
  const Plane3& q = sj.plane;
  const double A = p.a / p.c - q.a / q.c, B = p.b / p.c - q.b / q.c, C = p.d / p.c - q.d / q.c;
  const double norm = std::hypot(A, B);
  const double cross = std::sqrt(std::pow(p.b * q.c - p.c * q.b, 2) + std::pow(p.c * q.a - p.a * q.c, 2) +
                                 std::pow(p.a * q.b - p.b * q.a, 2));
  if (cross < params.parallel_tolerance || norm < 1e-12) return;
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
  const auto a = interval(si);
  const auto b = interval(sj);
  const double lo = std::max(a.first, b.first), hi = std::min(a.second, b.second);
  if (!(lo <= hi) || hi - lo < params.min_line_overlap) return;
  roof_lines.push_back({{origin.x + (lo - margin) * dir.x, origin.y + (lo - margin) * dir.y},
                        {origin.x + (hi + margin) * dir.x, origin.y + (hi + margin) * dir.y},
                        CurveKind::roof_line,
                        -1});
}

// Nearly coincident roof lines (both ends of one within merge_distance of the other's line,
// overlapping along it) become one: the longer line, extended over both. Longest first, ties in
// input order (deterministic).
void merge_coincident_lines(std::vector<InputCurve>& roof_lines, double merge_distance) {
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
      if (across(c.a) > merge_distance || across(c.b) > merge_distance) continue;
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

}  // namespace

std::vector<InputCurve> arrangement_curves(const std::vector<Point3>& points, const std::vector<PlanarSegment>& roofs,
                                           const std::vector<VerticalPlane>& walls,
                                           const std::vector<Polygon2>& footprint_local,
                                           const HypothesisParams& params, std::size_t& line_count) {
  std::vector<InputCurve> curves;
  for (const auto& poly : footprint_local) {
    std::vector<const Ring2*> rings{&poly.outer};
    for (const auto& h : poly.holes) rings.push_back(&h);
    for (const Ring2* ring : rings)
      for (std::size_t i = 0; i < ring->size(); ++i)
        curves.push_back({(*ring)[i], (*ring)[(i + 1) % ring->size()], CurveKind::footprint, -1});
  }
  if (curves.size() < 3) throw ReconstructionError(ReconstructionStage::hypothesis, "empty footprint");
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
  for (std::size_t i = 0; i < roofs.size(); ++i)
    for (std::size_t j = i + 1; j < roofs.size(); ++j) clip_roof_line(points, roofs[i], roofs[j], params, roof_lines);
  if (params.line_merge_distance > 0.0) merge_coincident_lines(roof_lines, params.line_merge_distance);
  line_count = roof_lines.size();
  curves.insert(curves.end(), roof_lines.begin(), roof_lines.end());
  extend_dangling_ends(curves, footprint_local, 2.0 * margin);
  return curves;
}

}  // namespace city3d::detail
