// k nearest neighbours: a grid over x and y, with CGAL's kd-tree search where the grid cannot tell
// which list that search would give (neighbours.hpp).
#include "planes/neighbours.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Shape_detection/Region_growing/Region_growing_on_point_set/K_neighbor_query.h>
#include <CGAL/property_map.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace city3d::detail {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using PointWithNormal = std::pair<Kernel::Point_3, Kernel::Vector_3>;
using PointRange = std::vector<PointWithNormal>;
using PointMap = CGAL::First_of_pair_property_map<PointWithNormal>;
using TreeQuery = CGAL::Shape_detection::Point_set::K_neighbor_query<Kernel, PointRange, PointMap>;

// The grid's cells hold about this many points, so that the 3 x 3 cells around a point usually
// hold the k + 1 = 13 the search needs at the default k.
constexpr double kPointsPerCell = 2.0;
// Metres taken off every distance in plan to a cell, at least: a point's cell and the cell bounds are
// rounded apart by a few units in the last place of the coordinates (Grid::margin_ grows with them).
constexpr double kMargin = 1e-9;
// Relative gap below which the k-th and (k+1)-th distances count as tied (neighbours.hpp): far
// above the rounding of the tree's incremental box distances (a few units in the last place).
constexpr double kTieGap = 1e-9;

/// The points sorted into square cells over x and y (a counting sort: within a cell, by index).
class Grid {
 public:
  /// False when the points span no area and no length in plan (all above one another), or one of
  /// them is not finite.
  bool build(const std::vector<Point3>& points) {
    const std::size_t n = points.size();
    x0_ = y0_ = std::numeric_limits<double>::infinity();
    double x1 = -x0_, y1 = -y0_;
    for (const Point3& p : points) {
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return false;
      x0_ = std::min(x0_, p.x);
      y0_ = std::min(y0_, p.y);
      x1 = std::max(x1, p.x);
      y1 = std::max(y1, p.y);
    }
    const double w = x1 - x0_, h = y1 - y0_;
    margin_ = kMargin + 16.0 * std::numeric_limits<double>::epsilon() *
                            std::max({std::abs(x0_), std::abs(x1), std::abs(y0_), std::abs(y1)});
    cell_ = std::sqrt(w * h * kPointsPerCell / static_cast<double>(n));
    if (!(cell_ > 0.0)) cell_ = std::max(w, h) * kPointsPerCell / static_cast<double>(n);
    if (!(cell_ > 0.0) || !std::isfinite(cell_)) return false;
    // A thin strip gives tiny cells: at most about four per point.
    const double max_cells = std::min(4.0 * static_cast<double>(n) + 64.0, double{1 << 28});
    while ((std::floor(w / cell_) + 1.0) * (std::floor(h / cell_) + 1.0) > max_cells) cell_ *= 1.5;
    nx_ = static_cast<int>(std::floor(w / cell_)) + 1;
    ny_ = static_cast<int>(std::floor(h / cell_)) + 1;
    std::vector<std::size_t> cell_of(n);
    start_.assign(static_cast<std::size_t>(nx_) * ny_ + 1, 0);
    for (std::size_t i = 0; i < n; ++i) {
      cell_of[i] = cell(column(points[i].x), row(points[i].y));
      ++start_[cell_of[i] + 1];
    }
    for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
    x_.resize(n);
    y_.resize(n);
    z_.resize(n);
    id_.resize(n);
    std::vector<std::uint32_t> next(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t at = next[cell_of[i]]++;
      x_[at] = points[i].x;
      y_[at] = points[i].y;
      z_[at] = points[i].z;
      id_[at] = static_cast<std::uint32_t>(i);
    }
    return true;
  }

  /// The k + 1 nearest of `q` (sorted by squared distance, `found` entries in `d` and `id`): rings
  /// of cells around q's cell until no point outside them can be nearer than the (k+1)-th; once k + 1
  /// are found, a cell farther in plan than the (k+1)-th is passed over.
  void nearest(const Point3& q, std::size_t k1, double* d, std::uint32_t* id, std::size_t& found) const {
    found = 0;
    const int cx = column(q.x), cy = row(q.y);
    const double fx = q.x - (x0_ + cx * cell_), fy = q.y - (y0_ + cy * cell_);  // q within its cell
    const auto visit = [&](int ix, int iy) {
      if (found == k1) {  // the cell's distance in plan, less the rounding margin
        const int ox = ix - cx, oy = iy - cy;
        const double gx = ox > 0 ? ox * cell_ - fx : ox < 0 ? fx - (ox + 1) * cell_ : 0.0;
        const double gy = oy > 0 ? oy * cell_ - fy : oy < 0 ? fy - (oy + 1) * cell_ : 0.0;
        const double sx = std::max(gx - margin_, 0.0), sy = std::max(gy - margin_, 0.0);
        if (sx * sx + sy * sy > d[k1 - 1]) return;
      }
      scan(q, cell(ix, iy), k1, d, id, found);
    };
    for (int r = 0;; ++r) {
      const int ix0 = std::max(cx - r, 0), ix1 = std::min(cx + r, nx_ - 1);
      for (int iy = std::max(cy - r, 0); iy <= std::min(cy + r, ny_ - 1); ++iy) {
        if (iy == cy - r || iy == cy + r) {  // the ring's bottom and top rows, whole
          for (int ix = ix0; ix <= ix1; ++ix) visit(ix, iy);
        } else {  // its left and right columns
          if (cx - r >= 0) visit(cx - r, iy);
          if (cx + r <= nx_ - 1) visit(cx + r, iy);
        }
      }
      // The nearest a point outside the rings searched can be, in plan (a lower bound in 3D);
      // sides at the grid's edge have nothing beyond them.
      double gap = std::numeric_limits<double>::infinity();
      if (cx - r > 0) gap = std::min(gap, fx + r * cell_);
      if (cx + r < nx_ - 1) gap = std::min(gap, (r + 1) * cell_ - fx);
      if (cy - r > 0) gap = std::min(gap, fy + r * cell_);
      if (cy + r < ny_ - 1) gap = std::min(gap, (r + 1) * cell_ - fy);
      if (gap == std::numeric_limits<double>::infinity()) return;  // every cell searched
      const double safe = gap - margin_;
      if (found == k1 && safe > 0.0 && safe * safe > d[k1 - 1]) return;
    }
  }

  /// The points in the grid's order (cell by cell): searching them in this order keeps each search's
  /// cells in cache from the previous one's.
  std::size_t size() const { return id_.size(); }
  Point3 point(std::size_t j) const { return {x_[j], y_[j], z_[j]}; }
  std::uint32_t index(std::size_t j) const { return id_[j]; }

 private:
  // Offers cell c's points to the sorted k1 nearest so far.
  void scan(const Point3& q, std::size_t c, std::size_t k1, double* d, std::uint32_t* id,
            std::size_t& found) const {
    for (std::uint32_t j = start_[c]; j < start_[c + 1]; ++j) {
      // CGAL's Euclidean_distance in 3D: square(q - p) per coordinate, added x, y, z.
      const double dx = q.x - x_[j], dy = q.y - y_[j], dz = q.z - z_[j];
      double dist = dx * dx;
      dist += dy * dy;
      dist += dz * dz;
      if (found == k1 && !(dist < d[k1 - 1])) continue;
      std::size_t at = found < k1 ? found++ : k1 - 1;
      while (at > 0 && dist < d[at - 1]) {
        d[at] = d[at - 1];
        id[at] = id[at - 1];
        --at;
      }
      d[at] = dist;
      id[at] = id_[j];
    }
  }

  std::size_t cell(int ix, int iy) const {
    return static_cast<std::size_t>(iy) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(ix);
  }
  int column(double x) const { return std::min(static_cast<int>((x - x0_) / cell_), nx_ - 1); }
  int row(double y) const { return std::min(static_cast<int>((y - y0_) / cell_), ny_ - 1); }

  double x0_ = 0.0, y0_ = 0.0, cell_ = 0.0, margin_ = kMargin;
  int nx_ = 0, ny_ = 0;
  std::vector<std::uint32_t> start_;  // cell c's points at [start_[c], start_[c + 1])
  std::vector<double> x_, y_, z_;     // by cell
  std::vector<std::uint32_t> id_;     // by cell: the point's index
};

}  // namespace

std::vector<std::uint32_t> k_nearest_lists(const std::vector<Point3>& points, std::size_t k,
                                           NeighbourStats* stats) {
  const std::size_t n = points.size();
  const std::size_t count = std::min(k, n);
  std::vector<std::uint32_t> lists(n * count);
  std::vector<std::uint32_t> to_tree;
  Grid grid;
  if (k >= 1 && n >= k + 2 && grid.build(points)) {
    const std::size_t k1 = k + 1;
    std::vector<double> d(k1);
    std::vector<std::uint32_t> id(k1);
    for (std::size_t j = 0; j < grid.size(); ++j) {
      const std::size_t i = grid.index(j);
      std::size_t found = 0;
      grid.nearest(grid.point(j), k1, d.data(), id.data(), found);
      bool settled = found == k1 && d[k] - d[k - 1] > kTieGap * d[k];
      for (std::size_t t = 0; settled && t + 1 < k; ++t) settled = d[t] < d[t + 1];
      if (!settled) {
        to_tree.push_back(static_cast<std::uint32_t>(i));
        continue;
      }
      std::copy(id.begin(), id.begin() + static_cast<std::ptrdiff_t>(k),
                lists.begin() + static_cast<std::ptrdiff_t>(i * k));
    }
  } else {
    to_tree.resize(n);
    for (std::size_t i = 0; i < n; ++i) to_tree[i] = static_cast<std::uint32_t>(i);
  }
  if (stats) {
    stats->from_grid = n - to_tree.size();
    stats->from_tree = to_tree.size();
  }
  if (to_tree.empty() || count == 0) return lists;
  PointRange range;
  range.reserve(n);
  for (const Point3& p : points)
    range.emplace_back(Kernel::Point_3(p.x, p.y, p.z), Kernel::Vector_3(0, 0, 1));
  const TreeQuery search(range, k, PointMap());
  std::vector<std::size_t> neighbours;
  for (std::uint32_t i : to_tree) {
    search(i, neighbours);  // always min(k, n) of them: the search fills its k from the whole tree
    std::copy(neighbours.begin(), neighbours.end(), lists.begin() + static_cast<std::ptrdiff_t>(i * count));
  }
  return lists;
}

}  // namespace city3d::detail
