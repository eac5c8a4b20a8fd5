// Surface support (include/city3d/surface_support.hpp): the local top of the points in plan, face
// sampling, and the unsupported area of a model.
#include "city3d/surface_support.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "city3d/building_report.hpp"
#include "city3d/error.hpp"
#include "city3d/evaluation.hpp"

namespace city3d {
namespace {

// A vertical face (a wall) as columns: at every `spacing` along its foot, the heights it spans there.
// All the samples of a column share their position in plan, and so their local top: a column costs one
// search instead of one per sample, and its unsupported part is measured exactly, not sampled.
struct Column {
  Point2 at;
  double u = 0.0;  // the column's centre along the foot, from the face's first vertex
  double width = 0.0;
  std::vector<std::pair<double, double>> spans;  // (low, high) heights inside the face, ascending
};

// Newell's normal of a polygon: twice its vector area, robust for non-convex polygons.
Point3 newell_normal(const std::vector<Point3>& face) {
  Point3 n{0.0, 0.0, 0.0};
  for (std::size_t i = 0; i < face.size(); ++i) {
    const Point3 &a = face[i], &b = face[(i + 1) % face.size()];
    n.x += (a.y - b.y) * (a.z + b.z);
    n.y += (a.z - b.z) * (a.x + b.x);
    n.z += (a.x - b.x) * (a.y + b.y);
  }
  return n;
}

// The columns of `face` when it is vertical (its normal within ~0.06 degrees of horizontal); false
// otherwise. With `range` (along the foot, as Column::u), only the part of the face within it.
bool vertical_columns(const std::vector<Point3>& face, double spacing, std::vector<Column>& columns,
                      const std::pair<double, double>* range = nullptr) {
  columns.clear();
  const std::size_t n = face.size();
  if (n < 3 || !(spacing > 0.0)) return false;
  const auto [nx, ny, nz] = newell_normal(face);
  const double length = std::sqrt(nx * nx + ny * ny + nz * nz);
  const double plan = std::hypot(nx, ny);
  if (!(length > 0.0) || !(plan > 0.0) || std::abs(nz) > 1e-3 * length) return false;
  const Point2 h{-ny / plan, nx / plan};  // along the foot of the wall
  const Point3& o = face[0];
  std::vector<double> u(n);
  double u0 = std::numeric_limits<double>::infinity(), u1 = -u0;
  for (std::size_t i = 0; i < n; ++i) {
    u[i] = (face[i].x - o.x) * h.x + (face[i].y - o.y) * h.y;
    u0 = std::min(u0, u[i]), u1 = std::max(u1, u[i]);
  }
  if (range != nullptr) u0 = std::max(u0, range->first), u1 = std::min(u1, range->second);
  if (!(u1 > u0)) return true;  // no width: no area
  const long count = std::max(1L, static_cast<long>(std::ceil((u1 - u0) / spacing)));
  const double width = (u1 - u0) / static_cast<double>(count);
  std::vector<double> crossings;
  for (long k = 0; k < count; ++k) {
    const double c = u0 + (static_cast<double>(k) + 0.5) * width;
    crossings.clear();
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t j = (i + 1) % n;
      if ((u[i] <= c) == (u[j] <= c)) continue;
      crossings.push_back(face[i].z + (c - u[i]) / (u[j] - u[i]) * (face[j].z - face[i].z));
    }
    std::sort(crossings.begin(), crossings.end());
    Column column{{o.x + c * h.x, o.y + c * h.y}, c, width, {}};
    for (std::size_t i = 0; i + 1 < crossings.size(); i += 2) column.spans.emplace_back(crossings[i], crossings[i + 1]);
    if (!column.spans.empty()) columns.push_back(std::move(column));
  }
  return true;
}

}  // namespace

void SurfaceSupportParams::validate() const {
  std::string problems;
  const auto add = [&](const std::string& p) { problems += (problems.empty() ? "" : "; ") + p; };
  if (!(sample_spacing > 0.0) || !std::isfinite(sample_spacing)) add("sample_spacing must be > 0 (metres)");
  if (!(radius > 0.0) || !std::isfinite(radius)) add("radius must be > 0 (metres)");
  if (!(tolerance >= 0.0) || !std::isfinite(tolerance)) add("tolerance must be >= 0 (metres)");
  if (refine < 1 || refine % 2 == 0) add("refine must be odd and >= 1");
  if (!problems.empty()) throw ConfigError("surface support: " + problems);
}

LocalTop::LocalTop(const std::vector<Point3>& points, double radius) : radius_(radius) {
  Box2 box;
  for (const Point3& p : points)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) box.add({p.x, p.y});
  if (box.empty() || !(radius > 0.0)) return;
  origin_ = box.min;
  // Bins of half the radius: a query visits at most 7 x 7 of them, and most inner ones whole.
  size_ = radius / 2.0;
  const double w = box.max.x - box.min.x, h = box.max.y - box.min.y;
  while ((w / size_ + 1.0) * (h / size_ + 1.0) > 4e6) size_ *= 2.0;
  nx_ = static_cast<long>(w / size_) + 1;
  ny_ = static_cast<long>(h / size_) + 1;
  std::vector<std::uint32_t> count(static_cast<std::size_t>(nx_ * ny_) + 1, 0);
  const auto bin_of = [&](const Point3& p) {
    const long i = std::clamp(static_cast<long>((p.x - origin_.x) / size_), 0L, nx_ - 1);
    const long j = std::clamp(static_cast<long>((p.y - origin_.y) / size_), 0L, ny_ - 1);
    return static_cast<std::size_t>(j * nx_ + i);
  };
  for (const Point3& p : points)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) ++count[bin_of(p) + 1];
  std::partial_sum(count.begin(), count.end(), count.begin());
  points_.resize(count.back());
  bins_.resize(static_cast<std::size_t>(nx_ * ny_));
  std::vector<std::uint32_t> next(count.begin(), count.end() - 1);
  for (const Point3& p : points)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) points_[next[bin_of(p)]++] = p;
  for (std::size_t b = 0; b < bins_.size(); ++b) {
    bins_[b] = {count[b], count[b + 1]};
    std::sort(points_.begin() + count[b], points_.begin() + count[b + 1], [](const Point3& a, const Point3& c) {
      return a.z > c.z || (a.z == c.z && (a.x < c.x || (a.x == c.x && a.y < c.y)));
    });
  }
  // Each bin's lower bound: the points within radius - half the diagonal of its centre lie within
  // radius of every position in the bin.
  const double inner = radius_ - size_ * std::sqrt(0.5);
  bound_.assign(bins_.size(), -std::numeric_limits<double>::infinity());
  if (inner > 0.0)
    for (long j = 0; j < ny_; ++j)
      for (long i = 0; i < nx_; ++i) {
        const double z = search(origin_.x + (static_cast<double>(i) + 0.5) * size_,
                                origin_.y + (static_cast<double>(j) + 0.5) * size_, inner);
        if (!std::isnan(z)) bound_[static_cast<std::size_t>(j * nx_ + i)] = z;
      }
}

double LocalTop::at(double x, double y) const { return search(x, y, radius_); }

double LocalTop::lower_bound(double x, double y) const {
  if (bins_.empty()) return -std::numeric_limits<double>::infinity();
  const double fi = std::floor((x - origin_.x) / size_), fj = std::floor((y - origin_.y) / size_);
  if (!(fi >= 0.0 && fj >= 0.0 && fi < static_cast<double>(nx_) && fj < static_cast<double>(ny_)))
    return -std::numeric_limits<double>::infinity();
  return bound_[static_cast<std::size_t>(static_cast<long>(fj) * nx_ + static_cast<long>(fi))];
}

double LocalTop::lower_bound_in(const Box2& box) const {
  const double none = -std::numeric_limits<double>::infinity();
  if (bins_.empty() || box.empty()) return none;
  const double fi0 = std::floor((box.min.x - origin_.x) / size_), fi1 = std::floor((box.max.x - origin_.x) / size_);
  const double fj0 = std::floor((box.min.y - origin_.y) / size_), fj1 = std::floor((box.max.y - origin_.y) / size_);
  if (!(fi0 >= 0.0 && fj0 >= 0.0 && fi1 < static_cast<double>(nx_) && fj1 < static_cast<double>(ny_))) return none;
  double low = std::numeric_limits<double>::infinity();
  for (long j = static_cast<long>(fj0); j <= static_cast<long>(fj1); ++j)
    for (long i = static_cast<long>(fi0); i <= static_cast<long>(fi1); ++i)
      low = std::min(low, bound_[static_cast<std::size_t>(j * nx_ + i)]);
  return low;
}

double LocalTop::search(double x, double y, double radius) const {
  double best = -std::numeric_limits<double>::infinity();
  if (bins_.empty()) return std::numeric_limits<double>::quiet_NaN();
  const double r2 = radius * radius;
  const long i0 = std::max(0L, static_cast<long>(std::floor((x - radius - origin_.x) / size_)));
  const long i1 = std::min(nx_ - 1, static_cast<long>(std::floor((x + radius - origin_.x) / size_)));
  const long j0 = std::max(0L, static_cast<long>(std::floor((y - radius - origin_.y) / size_)));
  const long j1 = std::min(ny_ - 1, static_cast<long>(std::floor((y + radius - origin_.y) / size_)));
  // Two passes: the bins wholly inside the disc first (their highest point counts as it is), then the
  // others, searched from their top only while it can beat the best so far: on a roof the first pass
  // usually leaves little for the second.
  for (int pass = 0; pass < 2; ++pass)
    for (long j = j0; j <= j1; ++j) {
      const double y0 = origin_.y + static_cast<double>(j) * size_, y1 = y0 + size_;
      const double dy_far = std::max(std::abs(y - y0), std::abs(y - y1));
      for (long i = i0; i <= i1; ++i) {
        const Bin& bin = bins_[static_cast<std::size_t>(j * nx_ + i)];
        if (bin.begin == bin.end || points_[bin.begin].z <= best) continue;
        const double x0 = origin_.x + static_cast<double>(i) * size_, x1 = x0 + size_;
        const double dx_far = std::max(std::abs(x - x0), std::abs(x - x1));
        const bool whole = dx_far * dx_far + dy_far * dy_far <= r2;  // the whole bin lies in the disc
        if (pass == 0) {
          if (whole) best = points_[bin.begin].z;
          continue;
        }
        if (whole) continue;  // taken in the first pass
        for (std::uint32_t k = bin.begin; k < bin.end; ++k) {
          const Point3& p = points_[k];
          if (p.z <= best) break;
          if ((p.x - x) * (p.x - x) + (p.y - y) * (p.y - y) <= r2) {
            best = p.z;
            break;
          }
        }
      }
    }
  return std::isfinite(best) ? best : std::numeric_limits<double>::quiet_NaN();
}

LocalTopRaster::LocalTopRaster(const LocalTop& local_top, const Box2& region, double cell) : local_top_(&local_top) {
  if (region.empty() || !(cell > 0.0)) return;
  cell_ = cell;
  origin_ = region.min;
  const double w = region.max.x - region.min.x, h = region.max.y - region.min.y;
  // A bound on the memory: a region of more than ~16M cells is read at a coarser cell.
  while ((w / cell_ + 1.0) * (h / cell_ + 1.0) > 16e6) cell_ *= 2.0;
  nx_ = static_cast<long>(w / cell_) + 1;
  ny_ = static_cast<long>(h / cell_) + 1;
  top_.assign(static_cast<std::size_t>(nx_ * ny_), std::numeric_limits<float>::quiet_NaN());
  known_.assign(top_.size(), 0);
}

long LocalTopRaster::cell_of(double x, double y) const {
  const double fi = std::floor((x - origin_.x) / cell_), fj = std::floor((y - origin_.y) / cell_);
  if (!(fi >= 0.0 && fj >= 0.0 && fi < static_cast<double>(nx_) && fj < static_cast<double>(ny_))) return -1;
  return static_cast<long>(fj) * nx_ + static_cast<long>(fi);
}

double LocalTopRaster::at(double x, double y) const {
  const long k = cell_of(x, y);
  if (k < 0) return std::numeric_limits<double>::quiet_NaN();
  const auto c = static_cast<std::size_t>(k);
  if (!known_[c]) {
    const long i = k % nx_, j = k / nx_;
    const double z = local_top_->at(origin_.x + (static_cast<double>(i) + 0.5) * cell_,
                                    origin_.y + (static_cast<double>(j) + 0.5) * cell_);
    top_[c] = std::isnan(z) ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(z);
    known_[c] = 1;
  }
  return top_[c];
}

double LocalTopRaster::lower_bound_in(const Box2& box) const {
  if (box.empty()) return -std::numeric_limits<double>::infinity();
  // A sample reads the top at its cell's centre, up to half a cell away.
  Box2 grown = box;
  grown.add({box.min.x - cell_, box.min.y - cell_});
  grown.add({box.max.x + cell_, box.max.y + cell_});
  return local_top_->lower_bound_in(grown);
}

bool LocalTopRaster::above(double x, double y, double z, double tolerance) const {
  const long k = cell_of(x, y);
  if (k < 0) return false;  // at() is NaN outside the region
  const double cx = origin_.x + (static_cast<double>(k % nx_) + 0.5) * cell_;
  const double cy = origin_.y + (static_cast<double>(k / nx_) + 0.5) * cell_;
  // LocalTop::at(cx, cy) >= the bound, so its float (at()'s value) >= the bound's float: rounding to
  // nearest and subtracting are monotone, and z - at() cannot exceed z - that float.
  const double bound = static_cast<float>(local_top_->lower_bound(cx, cy));
  if (!(z - bound > tolerance)) return false;
  const double top = at(x, y);
  return !std::isnan(top) && z - top > tolerance;
}

double LocalTopRaster::unsupported_area(const std::vector<Point3>& face, const SurfaceSupportParams& params) const {
  Box2 box;
  double highest = -std::numeric_limits<double>::infinity();
  for (const Point3& p : face) {
    box.add({p.x, p.y});
    highest = std::max(highest, p.z);
  }
  // No sample of the face can rise more than the tolerance above a top that is at least this high.
  if (!(highest - lower_bound_in(box) > params.tolerance)) return 0.0;
  std::vector<Column> columns;
  if (vertical_columns(face, params.sample_spacing, columns)) {
    double area = 0.0;
    for (const Column& column : columns) {
      const long k = cell_of(column.at.x, column.at.y);
      if (k < 0) continue;
      const double cx = origin_.x + (static_cast<double>(k % nx_) + 0.5) * cell_;
      const double cy = origin_.y + (static_cast<double>(k / nx_) + 0.5) * cell_;
      const double bar = local_top_->lower_bound(cx, cy) + params.tolerance;
      if (!(column.spans.back().second > bar)) continue;  // below a known lower bound
      const double top = at(column.at.x, column.at.y);
      if (std::isnan(top)) continue;
      for (const auto& [low, high] : column.spans)
        area += column.width * std::max(0.0, high - std::max(low, top + params.tolerance));
    }
    return area;
  }
  std::vector<Point3> samples;
  const double piece = sample_polygon(face, params.sample_spacing, samples);
  std::size_t unsupported = 0;
  for (const Point3& p : samples) {
    const long k = cell_of(p.x, p.y);
    if (k < 0) continue;
    const double cx = origin_.x + (static_cast<double>(k % nx_) + 0.5) * cell_;
    const double cy = origin_.y + (static_cast<double>(k / nx_) + 0.5) * cell_;
    if (!(p.z - local_top_->lower_bound(cx, cy) > params.tolerance)) continue;  // below a known lower bound
    const double top = at(p.x, p.y);
    unsupported += !std::isnan(top) && p.z - top > params.tolerance;
  }
  return piece * static_cast<double>(unsupported);
}

namespace {

constexpr double kMaxFaceSamples = 4e6;

// The in-plane axes of sample_polygon's grid: samples are the spacing apart along u and along v.
struct SampleAxes {
  Point3 u{0.0, 0.0, 0.0}, v{0.0, 0.0, 0.0};
};

double sample_polygon_axes(const std::vector<Point3>& face, double spacing, std::vector<Point3>& out,
                           SampleAxes* axes) {
  out.clear();
  const std::size_t n = face.size();
  if (n < 3 || !(spacing > 0.0)) return 0.0;
  auto [nx, ny, nz] = newell_normal(face);
  const double twice = std::sqrt(nx * nx + ny * ny + nz * nz);
  if (!(twice > 0.0) || !std::isfinite(twice)) return 0.0;
  const double area = 0.5 * twice;
  nx /= twice, ny /= twice, nz /= twice;
  // A face too large for its samples to be held (a cloud in millimetres read as metres makes blocks of
  // kilometres) is sampled coarser: at most kMaxFaceSamples, about 250,000 m2 at 0.25 m.
  spacing = std::max(spacing, std::sqrt(area / kMaxFaceSamples));
  // The frame: u along the longest edge (a thin face then runs along the rows), v = n x u.
  std::size_t longest = 0;
  double longest2 = -1.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Point3 &a = face[i], &b = face[(i + 1) % n];
    const double d2 = (b.x - a.x) * (b.x - a.x) + (b.y - a.y) * (b.y - a.y) + (b.z - a.z) * (b.z - a.z);
    if (d2 > longest2) longest2 = d2, longest = i;
  }
  const Point3& o = face[longest];
  const Point3& e = face[(longest + 1) % n];
  const double el = std::sqrt(longest2);
  if (!(el > 0.0)) return 0.0;
  const double ux = (e.x - o.x) / el, uy = (e.y - o.y) / el, uz = (e.z - o.z) / el;
  const double vx = ny * uz - nz * uy, vy = nz * ux - nx * uz, vz = nx * uy - ny * ux;
  std::vector<double> pu(n), pv(n);
  double u0 = std::numeric_limits<double>::infinity(), u1 = -u0, v0 = u0, v1 = -u0;
  for (std::size_t i = 0; i < n; ++i) {
    const double dx = face[i].x - o.x, dy = face[i].y - o.y, dz = face[i].z - o.z;
    pu[i] = dx * ux + dy * uy + dz * uz;
    pv[i] = dx * vx + dy * vy + dz * vz;
    u0 = std::min(u0, pu[i]), u1 = std::max(u1, pu[i]);
    v0 = std::min(v0, pv[i]), v1 = std::max(v1, pv[i]);
  }
  // A square grid of the spacing in the face's plane, cell centres inside the polygon (even-odd, row by
  // row). A face too thin for a row of the grid is scanned with rows closer together (up to 64 times),
  // its samples still the spacing apart along u.
  std::vector<std::pair<double, double>> samples;  // (u, v)
  std::vector<double> crossings;
  for (double row = spacing; samples.empty() && row >= spacing / 64.0; row /= 2.0) {
    const long rows = std::max(1L, static_cast<long>(std::ceil((v1 - v0) / row)));
    const double first_v = v0 + 0.5 * ((v1 - v0) - static_cast<double>(rows - 1) * row);
    for (long j = 0; j < rows; ++j) {
      const double v = first_v + static_cast<double>(j) * row;
      crossings.clear();
      for (std::size_t i = 0; i < n; ++i) {
        const std::size_t k = (i + 1) % n;
        if ((pv[i] <= v) == (pv[k] <= v)) continue;
        crossings.push_back(pu[i] + (v - pv[i]) / (pv[k] - pv[i]) * (pu[k] - pu[i]));
      }
      std::sort(crossings.begin(), crossings.end());
      for (std::size_t c = 0; c + 1 < crossings.size(); c += 2) {
        // Columns of the grid anchored at u0; a run shorter than the spacing still gets its middle.
        const double a = crossings[c], b = crossings[c + 1];
        long i0 = static_cast<long>(std::ceil((a - u0) / spacing - 0.5));
        const long i1 = static_cast<long>(std::floor((b - u0) / spacing - 0.5));
        if (i0 > i1) {
          samples.emplace_back(0.5 * (a + b), v);
          continue;
        }
        for (; i0 <= i1; ++i0) samples.emplace_back(u0 + (static_cast<double>(i0) + 0.5) * spacing, v);
      }
    }
  }
  if (samples.empty()) return 0.0;
  out.reserve(samples.size());
  for (const auto& [u, v] : samples) out.push_back({o.x + u * ux + v * vx, o.y + u * uy + v * vy, o.z + u * uz + v * vz});
  if (axes != nullptr) *axes = {{ux, uy, uz}, {vx, vy, vz}};
  return area / static_cast<double>(samples.size());
}

}  // namespace

double sample_polygon(const std::vector<Point3>& face, double spacing, std::vector<Point3>& out) {
  return sample_polygon_axes(face, spacing, out, nullptr);
}

SurfaceSupport surface_support(const PolygonMesh& mesh, const std::vector<SurfaceType>& types,
                               const LocalTop& local_top, const SurfaceSupportParams& params) {
  params.validate();
  SurfaceSupport out;
  out.face_unsupported_area.assign(mesh.faces.size(), 0.0);
  std::vector<Point3> polygon, samples;
  std::vector<Column> columns, narrow;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const SurfaceType type = f < types.size() ? types[f] : SurfaceType::wall;
    if (type == SurfaceType::ground) continue;
    const auto& face = mesh.faces[f];
    if (std::any_of(face.begin(), face.end(), [&](std::uint32_t v) { return v >= mesh.vertices.size(); })) continue;
    polygon.clear();
    for (const std::uint32_t v : face) polygon.push_back(mesh.vertices[v]);
    double unsupported = 0.0;
    if (type == SurfaceType::wall && vertical_columns(polygon, params.sample_spacing, columns)) {
      // The unsupported part of a column (0 when supported or without a point near), its excess and
      // its sample.
      const auto measure = [&](const Column& column) {
        const double highest = column.spans.back().second;
        if (!(highest - local_top.lower_bound(column.at.x, column.at.y) > params.tolerance)) return 0.0;
        const double top = local_top.at(column.at.x, column.at.y);
        if (std::isnan(top) || !(highest - top > params.tolerance)) return 0.0;
        double part = 0.0;
        for (const auto& [low, high] : column.spans)
          part += column.width * std::max(0.0, high - std::max(low, top + params.tolerance));
        out.height_excess = std::max(out.height_excess, highest - top);
        out.unsupported_samples.push_back({column.at.x, column.at.y, highest});
        return part;
      };
      for (const Column& column : columns) {
        for (const auto& [low, high] : column.spans) out.sampled_area += column.width * (high - low);
        const double highest = column.spans.back().second;
        if (!(highest - local_top.lower_bound(column.at.x, column.at.y) > params.tolerance)) continue;
        const double top = local_top.at(column.at.x, column.at.y);
        if (std::isnan(top) || !(highest - top > params.tolerance)) continue;
        const std::pair<double, double> range{column.u - 0.5 * column.width, column.u + 0.5 * column.width};
        vertical_columns(polygon, column.width / params.refine, narrow, &range);
        for (const Column& part : narrow) unsupported += measure(part);
      }
      out.face_unsupported_area[f] = unsupported;
      out.unsupported_area += unsupported;
      continue;
    }
    SampleAxes axes;
    const double area = sample_polygon_axes(polygon, params.sample_spacing, samples, &axes);
    const double step = params.sample_spacing / params.refine;
    // Whether a finer sample lies inside the face (even-odd, in the grid's axes): those beyond its edge
    // are not of it. The face in those axes is made on the first unsupported sample.
    std::vector<std::pair<double, double>> plane;
    const auto inside = [&](const Point3& q) {
      if (plane.empty())
        for (const Point3& c : polygon)
          plane.emplace_back(c.x * axes.u.x + c.y * axes.u.y + c.z * axes.u.z, c.x * axes.v.x + c.y * axes.v.y + c.z * axes.v.z);
      const double qu = q.x * axes.u.x + q.y * axes.u.y + q.z * axes.u.z;
      const double qv = q.x * axes.v.x + q.y * axes.v.y + q.z * axes.v.z;
      bool in = false;
      for (std::size_t i = 0, k = plane.size() - 1; i < plane.size(); k = i++) {
        const auto &a = plane[i], &b = plane[k];
        if ((a.second > qv) != (b.second > qv) && qu < a.first + (qv - a.second) / (b.second - a.second) * (b.first - a.first))
          in = !in;
      }
      return in;
    };
    for (const Point3& p : samples) {
      out.sampled_area += area;
      // Below a known lower bound of its local top (a point is near): supported, without a search.
      if (!(p.z - local_top.lower_bound(p.x, p.y) > params.tolerance)) continue;
      const double top = local_top.at(p.x, p.y);
      if (std::isnan(top)) {
        if (type == SurfaceType::roof) out.unpointed_roof_area += area;
        continue;
      }
      if (!(p.z - top > params.tolerance)) continue;
      for (int i = 0; i < params.refine; ++i) {
        for (int j = 0; j < params.refine; ++j) {
          const double du = (i - params.refine / 2) * step, dv = (j - params.refine / 2) * step;
          const Point3 q{p.x + du * axes.u.x + dv * axes.v.x, p.y + du * axes.u.y + dv * axes.v.y,
                         p.z + du * axes.u.z + dv * axes.v.z};
          if (!(q.z - local_top.lower_bound(q.x, q.y) > params.tolerance) || !inside(q)) continue;
          const double sub_top = local_top.at(q.x, q.y);
          if (std::isnan(sub_top) || !(q.z - sub_top > params.tolerance)) continue;
          unsupported += area / (params.refine * params.refine);
          out.height_excess = std::max(out.height_excess, q.z - sub_top);
          out.unsupported_samples.push_back(q);
        }
      }
    }
    out.face_unsupported_area[f] = unsupported;
    out.unsupported_area += unsupported;
    if (type == SurfaceType::roof) out.unsupported_roof_area += unsupported;
  }
  return out;
}

std::vector<SurfaceType> surface_types_unoriented(const PolygonMesh& mesh) {
  double lowest = std::numeric_limits<double>::infinity();
  for (const Point3& v : mesh.vertices) lowest = std::min(lowest, v.z);
  std::vector<SurfaceType> types;
  types.reserve(mesh.faces.size());
  for (const auto& face : mesh.faces) {
    double nx = 0.0, ny = 0.0, nz = 0.0;  // Newell's normal
    bool ground = true;
    for (std::size_t i = 0; i < face.size(); ++i) {
      if (face[i] >= mesh.vertices.size() || face[(i + 1) % face.size()] >= mesh.vertices.size()) {
        ground = false;
        break;
      }
      const Point3& a = mesh.vertices[face[i]];
      const Point3& b = mesh.vertices[face[(i + 1) % face.size()]];
      nx += (a.y - b.y) * (a.z + b.z);
      ny += (a.z - b.z) * (a.x + b.x);
      nz += (a.x - b.x) * (a.y + b.y);
      ground = ground && a.z - lowest <= 0.01;
    }
    const double length = std::sqrt(nx * nx + ny * ny + nz * nz);
    const bool vertical = !(length > 0.0) || std::abs(nz) / length <= 0.1;
    types.push_back(vertical ? SurfaceType::wall : ground ? SurfaceType::ground : SurfaceType::roof);
  }
  return types;
}

std::vector<bool> points_beneath_unsupported(const SurfaceSupport& support, const std::vector<Point3>& points,
                                             const SurfaceSupportParams& params) {
  std::vector<bool> beneath(points.size(), false);
  if (support.unsupported_samples.empty() || points.empty()) return beneath;
  // The highest unsupported sample near each point is all that matters: a LocalTop of the samples.
  const LocalTop highest_sample(support.unsupported_samples, params.radius);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double z = highest_sample.at(points[i].x, points[i].y);
    beneath[i] = !std::isnan(z) && z - points[i].z > params.tolerance;
  }
  return beneath;
}

double ModelFit::unfaithful(double points_per_m2) const {
  return static_cast<double>(far) + support.unsupported_area * points_per_m2;
}

double ModelFit::squares_both_ways(double points_per_m2) const {
  return squares + support.unsupported_area * points_per_m2 * kUnexplainedDistance * kUnexplainedDistance;
}

ModelFit fit_of_points(const PolygonMesh& mesh, const std::vector<Point3>& points,
                       std::vector<double>* distances_out) {
  ModelFit fit;
  const std::vector<double> distances = point_distances(mesh, points);
  for (const double d : distances) {
    fit.far += d > kUnexplainedDistance;
    fit.squares += d * d;
  }
  if (distances_out) *distances_out = distances;
  return fit;
}

ModelFit fit_both_ways(const PolygonMesh& mesh, const std::vector<SurfaceType>& types,
                       const std::vector<Point3>& points, const LocalTop& local_top,
                       const SurfaceSupportParams& params, std::vector<double>* distances_out) {
  ModelFit fit = fit_of_points(mesh, points, distances_out);
  fit.support = surface_support(mesh, types, local_top, params);
  return fit;
}

}  // namespace city3d
