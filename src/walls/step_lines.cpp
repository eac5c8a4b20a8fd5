// Step lines: the horizontal lines where one roof plane's points end and another plane's begin at a
// different height (a step edge: a lower roof beside a higher one, a dormer, an annex). They become
// inner walls like the heightmap's lines; the heightmap misses steps lower than its Canny thresholds
// and steps whose TIN triangles smear them, and roof-roof intersection lines cannot stand in for them
// (two planes at a step meet far away, or never when they are parallel).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/log.hpp"
#include "city3d/walls.hpp"

namespace city3d {
namespace {

double plane_height(const Plane3& p, double x, double y) { return -(p.a * x + p.b * y + p.d) / p.c; }

// The distance between two points as std::hypot(dx, dy) returns it, with hypot called only where a
// comparison needs it (hypot was about half of the step lines' CPU). The squared distance
// s = dx^2 + dy^2 has a relative error below 2^-51 and hypot one of at most 1 ulp, so when two
// squared distances differ by more than a relative 1e-9 (a margin that also covers the rounding of
// the test itself) the two hypot values compare the same way; only closer cases call hypot. Below
// s = 1e-250 (never for coordinates in metres) underflow would void the error bound, and hypot
// decides there too.
class Distance {
 public:
  Distance(double dx, double dy) : dx_(dx), dy_(dy), sq_(dx * dx + dy * dy) {}
  double squared() const { return sq_; }
  double value() const {
    if (!known_) value_ = std::hypot(dx_, dy_), known_ = true;
    return value_;
  }
  bool operator<(const Distance& o) const {
    if (clearly_less(sq_, o.sq_)) return true;
    if (clearly_less(o.sq_, sq_)) return false;
    return value() < o.value();
  }

 private:
  static bool clearly_less(double s, double t) { return t >= 1e-250 && s < t * (1.0 - 1e-9); }
  double dx_, dy_, sq_;
  mutable double value_ = 0.0;
  mutable bool known_ = false;
};

// d.value() <= r for many d, decided as Distance's comparisons are: from the squared distance
// unless it is within a relative 1e-9 of r^2.
class Radius {
 public:
  explicit Radius(double r) : r_(r) {
    const double r2 = r * r;
    if (r2 < 1e-250) return;  // hypot decides every case
    surely_in_ = r2 * (1.0 - 1e-9);
    surely_out_ = r2 * (1.0 + 1e-9);
  }
  bool contains(const Distance& d) const {
    if (d.squared() < surely_in_) return true;
    if (d.squared() > surely_out_) return false;
    return d.value() <= r_;
  }

 private:
  double r_;
  double surely_in_ = -1.0, surely_out_ = std::numeric_limits<double>::infinity();
};

// A uniform grid over xy positions for radius searches: each bin's points in one array (a bin's
// points ascending, or, with labels, grouped by label and ascending within a label).
class Grid {
 public:
  // With `labels` (one per point), near_other() can pass over a bin's points of one label in a step.
  Grid(const std::vector<Point2>& xy, double cell, const std::vector<int>* labels = nullptr)
      : xy_(xy), labels_(labels), cell_(cell) {
    Box2 box;
    for (const Point2& p : xy) box.add(p);
    if (box.empty()) return;
    origin_ = box.min;
    nx_ = static_cast<long>((box.max.x - box.min.x) / cell_) + 1;
    ny_ = static_cast<long>((box.max.y - box.min.y) / cell_) + 1;
    start_.assign(static_cast<std::size_t>(nx_ * ny_) + 1, 0);
    std::vector<std::uint32_t> bin_of(xy.size());
    for (std::size_t i = 0; i < xy.size(); ++i)
      ++start_[(bin_of[i] = static_cast<std::uint32_t>(index(xy[i]))) + 1];
    std::partial_sum(start_.begin(), start_.end(), start_.begin());
    ids_.resize(xy.size());
    std::vector<std::uint32_t> next(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < xy.size(); ++i) ids_[next[bin_of[i]]++] = static_cast<std::uint32_t>(i);
    if (!labels) return;
    run_end_.resize(xy.size());
    for (std::size_t b = 0; b + 1 < start_.size(); ++b) {
      const auto first = ids_.begin() + start_[b], last = ids_.begin() + start_[b + 1];
      std::stable_sort(first, last,
                       [labels](std::uint32_t u, std::uint32_t v) { return (*labels)[u] < (*labels)[v]; });
      for (std::uint32_t pos = start_[b + 1]; pos-- > start_[b];)
        run_end_[pos] = pos + 1 < start_[b + 1] && (*labels)[ids_[pos + 1]] == (*labels)[ids_[pos]]
                            ? run_end_[pos + 1]
                            : pos + 1;
    }
  }
  // visit(k, distance) for every point k within `radius` of p.
  template <typename Visit>
  void near(const Point2& p, double radius, Visit visit) const {
    near(p, radius, [](std::uint32_t) { return true; }, visit);
  }
  // The same for the points k with wanted(k), which is tested first (it is cheaper).
  template <typename Wanted, typename Visit>
  void near(const Point2& p, double radius, Wanted wanted, Visit visit) const {
    for_bins(p, radius, [&](std::uint32_t begin, std::uint32_t end, const Radius& within) {
      for (std::uint32_t pos = begin; pos < end; ++pos) {
        const std::uint32_t k = ids_[pos];
        if (!wanted(k)) continue;
        const Distance d(xy_[k].x - p.x, xy_[k].y - p.y);
        if (within.contains(d)) visit(k, d);
      }
    });
  }
  // The same for the points whose label is not `own` (a grid made with labels): the points of label
  // `own` are passed over a run at a time, not one by one.
  template <typename Visit>
  void near_other(const Point2& p, double radius, int own, Visit visit) const {
    const std::vector<int>& label = *labels_;
    for_bins(p, radius, [&](std::uint32_t begin, std::uint32_t end, const Radius& within) {
      for (std::uint32_t pos = begin; pos < end;) {
        const std::uint32_t k = ids_[pos];
        if (label[k] == own) {
          pos = run_end_[pos];
          continue;
        }
        ++pos;
        const Distance d(xy_[k].x - p.x, xy_[k].y - p.y);
        if (within.contains(d)) visit(k, d);
      }
    });
  }

 private:
  // bin(begin, end, within) for every bin within `radius` of p, as positions into ids_.
  template <typename Bin>
  void for_bins(const Point2& p, double radius, Bin bin) const {
    if (start_.empty()) return;
    const Radius within(radius);
    const long i0 = std::max(0L, col(p.x - radius)), i1 = std::min(nx_ - 1, col(p.x + radius));
    const long j0 = std::max(0L, row(p.y - radius)), j1 = std::min(ny_ - 1, row(p.y + radius));
    for (long j = j0; j <= j1; ++j)
      for (long i = i0; i <= i1; ++i) {
        const auto b = static_cast<std::size_t>(j * nx_ + i);
        bin(start_[b], start_[b + 1], within);
      }
  }
  long col(double x) const { return static_cast<long>(std::floor((x - origin_.x) / cell_)); }
  long row(double y) const { return static_cast<long>(std::floor((y - origin_.y) / cell_)); }
  std::size_t index(const Point2& p) const {
    return static_cast<std::size_t>(std::clamp(row(p.y), 0L, ny_ - 1) * nx_ + std::clamp(col(p.x), 0L, nx_ - 1));
  }
  const std::vector<Point2>& xy_;
  const std::vector<int>* labels_;
  double cell_;
  Point2 origin_;
  long nx_ = 0, ny_ = 0;
  std::vector<std::uint32_t> start_;    // per bin, where its points begin in ids_ (and one past the last)
  std::vector<std::uint32_t> ids_;      // the points, bin after bin
  std::vector<std::uint32_t> run_end_;  // with labels: per position, the end of its label's run in its bin
};

using Line = std::pair<Point2, Point2>;  // centre and unit direction

// Least-squares line through `pts` (indices into xy): centre and unit direction.
Line fit_line(const std::vector<Point2>& xy, const std::vector<std::uint32_t>& pts) {
  double cx = 0, cy = 0;
  for (auto k : pts) cx += xy[k].x, cy += xy[k].y;
  cx /= pts.size();
  cy /= pts.size();
  double sxx = 0, sxy = 0, syy = 0;
  for (auto k : pts) {
    const double dx = xy[k].x - cx, dy = xy[k].y - cy;
    sxx += dx * dx, sxy += dx * dy, syy += dy * dy;
  }
  const double angle = 0.5 * std::atan2(2 * sxy, sxx - syy);
  return {{cx, cy}, {std::cos(angle), std::sin(angle)}};
}

bool near_line(const Point2& p, const Line& line, double tolerance) {
  return std::abs(-(p.x - line.first.x) * line.second.y + (p.y - line.first.y) * line.second.x) <= tolerance;
}

// Straight pieces through the boundary samples of one pair of planes: repeatedly the line with most
// samples within `tolerance` (candidate lines: the local fit around each sample), refitted, cut at
// gaps wider than `max_gap`; the longest run is kept when long enough, its samples removed.
// A sample's neighbourhood (the samples left within max_gap) only loses the removed samples near it,
// so only the samples within max_gap of a removed one look at theirs again (the test is symmetric:
// Distance of the negated offset is the same bits). The others keep their line, and its count only
// loses the removed samples near the line. Counting every sample for every candidate in every round
// was quadratic, and so was searching every neighbourhood again every round.
template <typename Separates>
void extract_lines(const std::vector<Point2>& samples, const StepLineParams& params, double max_gap,
                   Separates separates, std::vector<Polyline2>& out) {
  std::vector<std::uint32_t> left(samples.size());  // the samples not yet removed, ascending
  std::iota(left.begin(), left.end(), 0u);
  std::vector<char> alive(samples.size(), 1);
  const auto is_alive = [&alive](std::uint32_t k) { return alive[k] != 0; };
  const double tol = params.line_tolerance;
  const Grid grid(samples, std::max(tol, max_gap));
  struct Candidate {
    Line line;              // fitted to the sample's neighbourhood
    std::size_t count = 0;  // samples left near the line
    bool fitted = false;    // false: no line yet, or fewer than 3 samples around it (for good)
  };
  std::vector<Candidate> candidates(samples.size());
  std::vector<char> look_again(samples.size(), 1);  // the neighbourhood may have changed
  std::vector<std::uint32_t> removed;               // the samples the last round removed
  std::vector<std::uint32_t> local;
  for (int round = 0; left.size() >= static_cast<std::size_t>(params.min_samples); ++round) {
    std::size_t best_count = 0;
    Line best_line;
    for (std::uint32_t i : left) {
      Candidate& c = candidates[i];
      if (!look_again[i]) {
        if (!c.fitted) continue;
        for (auto k : removed) c.count -= near_line(samples[k], c.line, tol);
      } else {
        look_again[i] = 0;
        local.clear();
        grid.near(samples[i], max_gap, is_alive,
                  [&](std::uint32_t k, const Distance&) { local.push_back(k); });
        if (local.size() < 3) {  // neighbourhoods only shrink: never a candidate again
          c.fitted = false;
          continue;
        }
        std::sort(local.begin(), local.end());
        c.line = fit_line(samples, local);
        c.count = 0;
        for (auto k : left) c.count += near_line(samples[k], c.line, tol);
        c.fitted = true;
      }
      if (c.count > best_count) best_count = c.count, best_line = c.line;
    }
    if (best_count < static_cast<std::size_t>(params.min_samples)) return;
    const auto inliers_of = [&](const Line& line) {
      std::vector<std::uint32_t> in;
      for (auto k : left)
        if (near_line(samples[k], line, tol)) in.push_back(k);
      return in;
    };
    std::vector<std::uint32_t> in = inliers_of(best_line);
    const auto line = fit_line(samples, in);
    in = inliers_of(line);
    if (in.size() < 2) return;
    // Runs along the line, cut at gaps.
    std::vector<std::pair<double, std::uint32_t>> along;
    for (auto k : in)
      along.push_back(
          {(samples[k].x - line.first.x) * line.second.x + (samples[k].y - line.first.y) * line.second.y, k});
    std::sort(along.begin(), along.end());
    std::size_t best_begin = 0, best_end = 0, begin = 0;
    for (std::size_t k = 1; k <= along.size(); ++k)
      if (k == along.size() || along[k].first - along[k - 1].first > max_gap) {
        if (k - begin > best_end - best_begin) best_begin = begin, best_end = k;
        begin = k;
      }
    const double t0 = along[best_begin].first, t1 = along[best_end - 1].first;
    const Point2 a{line.first.x + t0 * line.second.x, line.first.y + t0 * line.second.y};
    const Point2 b{line.first.x + t1 * line.second.x, line.first.y + t1 * line.second.y};
    if (best_end - best_begin >= static_cast<std::size_t>(params.min_samples) && t1 - t0 >= params.min_length &&
        separates(a, b))
      out.push_back({a, b});
    // Remove the run's samples (also when too short: the search moves on to other lines).
    if (best_end - best_begin == 0) return;
    removed.clear();
    for (std::size_t k = best_begin; k < best_end; ++k) {
      removed.push_back(along[k].second);
      alive[along[k].second] = 0;
    }
    std::sort(removed.begin(), removed.end());
    left.erase(std::remove_if(left.begin(), left.end(), [&](std::uint32_t k) { return !alive[k]; }),
               left.end());
    for (auto k : removed)
      grid.near(samples[k], max_gap, is_alive, [&](std::uint32_t i, const Distance&) { look_again[i] = 1; });
  }
}

}  // namespace

void StepLineParams::validate() const {
  std::vector<std::string> problems;
  if (!(min_step > 0.0)) problems.push_back("min_step must be > 0");
  if (!(line_tolerance > 0.0)) problems.push_back("line_tolerance must be > 0");
  if (!(min_length >= 0.0)) problems.push_back("min_length must be >= 0");
  if (min_samples < 2) problems.push_back("min_samples must be >= 2");
  if (!(min_separation >= 0.5 && min_separation <= 1.0)) problems.push_back("min_separation must be in [0.5, 1]");
  if (!(search_spacings > 0.0)) problems.push_back("search_spacings must be > 0");
  if (problems.empty()) return;
  std::string message = "step lines: invalid parameters: ";
  for (std::size_t i = 0; i < problems.size(); ++i) message += (i ? "; " : "") + problems[i];
  throw ConfigError(message);
}

std::vector<Polyline2> detect_step_lines(const std::vector<Point3>& points, const std::vector<PlanarSegment>& roofs,
                                         double point_spacing, const StepLineParams& params) {
  params.validate();
  std::vector<Polyline2> lines;
  if (!params.enabled || roofs.size() < 2 || !(point_spacing > 0.0)) return lines;
  // Every roof point with its plane.
  std::vector<Point2> xy;
  std::vector<int> label;
  for (std::size_t r = 0; r < roofs.size(); ++r) {
    if (std::abs(roofs[r].plane.c) < 1e-6) continue;
    for (std::uint32_t k : roofs[r].points) {
      xy.push_back({points[k].x, points[k].y});
      label.push_back(static_cast<int>(r));
    }
  }
  const double radius = params.search_spacings * point_spacing;
  const Grid grid(xy, radius, &label);
  // Boundary samples per pair of planes (a < b): from every roof point, the midpoint to the nearest
  // point of each other plane within `radius`, when the two planes' heights differ by min_step or
  // more on both sides. The samples form a band a few spacings wide along the boundary; the line
  // search below finds its middle.
  const std::size_t R = roofs.size();
  std::vector<std::vector<Point2>> samples(R * R);
  std::vector<Distance> nearest(R, Distance(0.0, 0.0));
  std::vector<std::uint32_t> nearest_point(R);
  std::vector<char> found(R);
  for (std::uint32_t i = 0; i < xy.size(); ++i) {
    std::fill(found.begin(), found.end(), 0);
    grid.near_other(xy[i], radius, label[i], [&](std::uint32_t k, const Distance& d) {
      const auto b = static_cast<std::size_t>(label[k]);
      // The nearest, ties to the lowest index (distances within the radius are not NaN).
      if (!found[b] || d < nearest[b] || (!(nearest[b] < d) && k < nearest_point[b]))
        nearest[b] = d, nearest_point[b] = k, found[b] = 1;
    });
    const auto a = static_cast<std::size_t>(label[i]);
    for (std::size_t b = 0; b < R; ++b) {
      if (!found[b]) continue;
      // f = height of a - height of b is linear in xy: where the two planes meet in a crease (a
      // ridge, a hip, a valley) f changes sign between the points, or is small at one of them; at a
      // step it keeps its sign and its size on both sides.
      const Point2& p = xy[i];
      const Point2& q = xy[nearest_point[b]];
      const double fp = plane_height(roofs[a].plane, p.x, p.y) - plane_height(roofs[b].plane, p.x, p.y);
      const double fq = plane_height(roofs[a].plane, q.x, q.y) - plane_height(roofs[b].plane, q.x, q.y);
      if (fp * fq > 0.0 && std::min(std::abs(fp), std::abs(fq)) >= params.min_step)
        samples[std::min(a, b) * R + std::max(a, b)].push_back({(p.x + q.x) / 2, (p.y + q.y) / 2});
    }
  }
  // A step line separates its two planes: beside it (within the search radius, along its extent),
  // at least min_separation of the two planes' points lie on their own plane's side. Planes whose
  // points interleave (strips of a sawtooth roof grown into one plane) give no line.
  const auto separation = [&](std::size_t a, std::size_t b, const Point2& p0, const Point2& p1) {
    const double len = std::hypot(p1.x - p0.x, p1.y - p0.y);
    const Point2 d{(p1.x - p0.x) / len, (p1.y - p0.y) / len};
    const Point2 mid{(p0.x + p1.x) / 2, (p0.y + p1.y) / 2};
    std::size_t a_left = 0, a_right = 0, b_left = 0, b_right = 0;
    const auto of_the_pair = [&](std::uint32_t k) {
      return label[k] == static_cast<int>(a) || label[k] == static_cast<int>(b);
    };
    grid.near(mid, len / 2 + radius, of_the_pair, [&](std::uint32_t k, const Distance&) {
      const auto l = static_cast<std::size_t>(label[k]);
      const double along = (xy[k].x - p0.x) * d.x + (xy[k].y - p0.y) * d.y;
      const double across = -(xy[k].x - p0.x) * d.y + (xy[k].y - p0.y) * d.x;
      if (along < 0.0 || along > len || std::abs(across) > radius) return;
      if (l == a)
        ++(across > 0.0 ? a_left : a_right);
      else
        ++(across > 0.0 ? b_left : b_right);
    });
    const std::size_t total = a_left + a_right + b_left + b_right;
    return total > 0 && static_cast<double>(std::max(a_left + b_right, a_right + b_left)) >=
                            params.min_separation * static_cast<double>(total);
  };
  for (std::size_t a = 0; a < R; ++a)
    for (std::size_t b = a + 1; b < R; ++b)
      if (samples[a * R + b].size() >= static_cast<std::size_t>(params.min_samples))
        extract_lines(samples[a * R + b], params, radius,
                      [&](const Point2& p0, const Point2& p1) { return separation(a, b, p0, p1); }, lines);
  log_debug("walls: " + std::to_string(lines.size()) + " step lines between roof planes");
  return lines;
}

}  // namespace city3d
