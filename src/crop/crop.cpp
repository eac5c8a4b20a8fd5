// Cropping: a uniform grid over the footprints' (buffered) bounding boxes finds candidate footprints
// per point; an exact even-odd test decides containment; ground points around each footprint are
// kept for its floor height.
#include "city3d/crop.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <limits>
#include <numeric>
#include <sstream>
#include <utility>

#include "city3d/error.hpp"
#include "city3d/log.hpp"

namespace city3d {
namespace detail {

namespace {

/// An edge with its endpoints in a canonical (y, then x) order, so that two footprints sharing an
/// edge evaluate exactly the same floating-point expression for it, whatever their ring directions.
struct CanonicalEdge {
  Point2 lo;
  Point2 hi;
};

bool box_contains(const Box2& b, double x, double y) {
  return x >= b.min.x && x <= b.max.x && y >= b.min.y && y <= b.max.y;
}

Box2 expanded(const Box2& b, double d) {
  Box2 e = b;
  e.min.x -= d;
  e.min.y -= d;
  e.max.x += d;
  e.max.y += d;
  return e;
}

double segment_distance2(const CanonicalEdge& e, double x, double y) {
  const double dx = e.hi.x - e.lo.x;
  const double dy = e.hi.y - e.lo.y;
  const double len2 = dx * dx + dy * dy;
  double t = 0.0;
  if (len2 > 0.0) t = std::clamp(((x - e.lo.x) * dx + (y - e.lo.y) * dy) / len2, 0.0, 1.0);
  const double ex = e.lo.x + t * dx - x;
  const double ey = e.lo.y + t * dy - y;
  return ex * ex + ey * ey;
}

}  // namespace

/// One footprint prepared for queries: its edges grouped by polygon, and its boxes.
struct PreparedFootprint {
  std::vector<CanonicalEdge> edges;
  std::vector<std::uint32_t> polygon_end;  ///< edges of polygon k: [end[k-1], end[k])
  Box2 box;       ///< tight bounding box (world); empty when the footprint has no usable ring
  Box2 near_box;  ///< box expanded by the ground buffer
  Box2 wide_box;  ///< box expanded by the wide ground buffer
  Point3 origin;

  /// Even-odd crossing test per polygon (all rings together, so holes are excluded), half-open in
  /// y: an edge counts when lo.y <= y < hi.y and it lies strictly right of the point. Horizontal
  /// edges never count. A point on an edge is decided by the sign of one cross product that both
  /// footprints sharing the edge compute identically, so it lands in exactly one of them.
  bool contains(double x, double y) const {
    std::uint32_t begin = 0;
    for (std::uint32_t end : polygon_end) {
      bool inside = false;
      for (std::uint32_t k = begin; k < end; ++k) {
        const CanonicalEdge& e = edges[k];
        if (e.lo.y <= y && y < e.hi.y) {
          const double cross = (e.hi.x - e.lo.x) * (y - e.lo.y) - (x - e.lo.x) * (e.hi.y - e.lo.y);
          if (cross > 0.0) inside = !inside;
        }
      }
      if (inside) return true;
      begin = end;
    }
    return false;
  }

  /// Whether (x, y) is within sqrt(d2) of an edge: the least squared distance to an edge is at most
  /// d2 exactly when one edge's is, so the walk stops at the first.
  bool near_boundary(double x, double y, double d2) const {
    for (const CanonicalEdge& e : edges)
      if (segment_distance2(e, x, y) <= d2) return true;
    return false;
  }
};

/// What one footprint has collected so far (local coordinates, input order).
struct Collected {
  std::vector<Point3> building;
  std::vector<double> near_ground;  ///< heights of the ground points within ground_buffer of the polygon
  std::vector<double> wide_ground;  ///< in the wide box but not near; kept only while near is short
  PointPresence presence;           ///< cells of the footprint's box where a point of any class fell
  /// Building points also inside another footprint, and the first such footprint: footprints that
  /// overlap (a parcel or block polygon among the buildings', a footprint given twice, shifted).
  std::size_t shared = 0;
  std::uint32_t shared_with = 0;
};

/// An empty presence lattice over a footprint's box: 0.25 m cells, doubled until they are few enough.
PointPresence presence_over(const Box2& box) {
  PointPresence p;
  if (box.empty()) return p;
  for (;;) {
    p.i0 = static_cast<std::int64_t>(std::floor(box.min.x / p.cell));
    p.j0 = static_cast<std::int64_t>(std::floor(box.min.y / p.cell));
    p.nx = static_cast<std::int64_t>(std::floor(box.max.x / p.cell)) - p.i0 + 1;
    p.ny = static_cast<std::int64_t>(std::floor(box.max.y / p.cell)) - p.j0 + 1;
    if (p.nx * p.ny <= kMaxPresenceCells) break;
    p.cell *= 2;
  }
  p.marked.assign(static_cast<std::size_t>(p.nx * p.ny), false);
  return p;
}

void mark(PointPresence& p, double x, double y) {
  const auto i = static_cast<std::int64_t>(std::floor(x / p.cell)) - p.i0;
  const auto j = static_cast<std::int64_t>(std::floor(y / p.cell)) - p.j0;
  if (i >= 0 && j >= 0 && i < p.nx && j < p.ny) p.marked[static_cast<std::size_t>(j * p.nx + i)] = true;
}

/// A uniform grid over the wide boxes; each cell lists the footprints (ascending index) whose wide
/// box overlaps it.
struct CropIndex {
  std::vector<Footprint> footprints;
  std::vector<PreparedFootprint> prepared;
  std::vector<Collected> collected;

  double x0 = 0.0, y0 = 0.0, cell = 1.0, inv_cell = 1.0;
  std::int64_t nx = 0, ny = 0;
  std::vector<std::uint32_t> cell_start;  ///< nx*ny + 1 offsets into cell_items
  std::vector<std::uint32_t> cell_items;

  std::int64_t column(double x) const {
    return std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor((x - x0) * inv_cell)), 0, nx - 1);
  }
  std::int64_t row(double y) const {
    return std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor((y - y0) * inv_cell)), 0, ny - 1);
  }

  void build_grid() {
    Box2 extent;
    double extent_sum = 0.0;
    std::size_t usable = 0;
    for (const PreparedFootprint& f : prepared) {
      if (f.box.empty()) continue;
      extent.add(f.wide_box.min);
      extent.add(f.wide_box.max);
      extent_sum += std::max(f.near_box.max.x - f.near_box.min.x, f.near_box.max.y - f.near_box.min.y);
      ++usable;
    }
    if (usable == 0) return;  // nx = ny = 0: every point is skipped
    const double width = std::max(extent.max.x - extent.min.x, 1e-6);
    const double height = std::max(extent.max.y - extent.min.y, 1e-6);
    // A cell about the size of an average footprint with its ground buffer keeps the candidates per
    // point few (a cell the size of the wide boxes gave twice the candidates and 1.6x the time on a
    // dense synthetic city) while each footprint's wide box spans only a handful of cells. Widely scattered
    // footprints would make that grid huge, so the cell count is capped at a few per footprint.
    const double max_cells = std::min(std::max(1024.0, 4.0 * static_cast<double>(usable)), 16.0e6);
    cell = std::max(extent_sum / static_cast<double>(usable), 1e-3);
    if ((width / cell) * (height / cell) > max_cells) cell = std::sqrt(width * height / max_cells) * 1.01;
    inv_cell = 1.0 / cell;
    x0 = extent.min.x;
    y0 = extent.min.y;
    nx = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(width * inv_cell)));
    ny = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(height * inv_cell)));

    std::vector<std::uint32_t> counts(static_cast<std::size_t>(nx * ny) + 1, 0);
    auto for_cells = [&](const Box2& b, auto&& visit) {
      for (std::int64_t r = row(b.min.y); r <= row(b.max.y); ++r)
        for (std::int64_t c = column(b.min.x); c <= column(b.max.x); ++c)
          visit(static_cast<std::size_t>(r * nx + c));
    };
    for (const PreparedFootprint& f : prepared)
      if (!f.box.empty()) for_cells(f.wide_box, [&](std::size_t k) { ++counts[k + 1]; });
    std::partial_sum(counts.begin(), counts.end(), counts.begin());
    cell_start = counts;
    cell_items.resize(cell_start.back());
    std::vector<std::uint32_t> fill(cell_start.begin(), cell_start.end() - 1);
    for (std::uint32_t i = 0; i < prepared.size(); ++i)
      if (!prepared[i].box.empty())
        for_cells(prepared[i].wide_box, [&](std::size_t k) { cell_items[fill[k]++] = i; });
  }
};

}  // namespace detail

void CropParams::validate() const {
  std::vector<std::string> problems;
  auto bad = [&](const std::string& field, double value, const std::string& rule) {
    std::ostringstream s;
    s << field << " = " << value << " (" << rule << ")";
    problems.push_back(s.str());
  };
  if (!(ground_buffer >= 0.0) || !std::isfinite(ground_buffer))
    bad("ground_buffer", ground_buffer, "metres, >= 0");
  if (!(wide_buffer_factor >= 1.0) || !std::isfinite(wide_buffer_factor))
    bad("wide_buffer_factor", wide_buffer_factor, ">= 1");
  if (!(ground_percentile >= 0.0 && ground_percentile <= 100.0))
    bad("ground_percentile", ground_percentile, "0-100");
  if (min_ground_points < 1) bad("min_ground_points", 0, ">= 1");
  if (building_classes.empty() && use_classes != ClassUse::never)
    problems.push_back("building_classes is empty");
  if (use_classes != ClassUse::never &&
      std::find(building_classes.begin(), building_classes.end(), ground_class) != building_classes.end())
    problems.push_back("ground_class = " + std::to_string(ground_class) +
                       " (also a building class: its points would be the building's, none the ground's)");
  if (problems.empty()) return;
  std::string message = "crop: invalid parameters: ";
  for (std::size_t i = 0; i < problems.size(); ++i) message += (i ? "; " : "") + problems[i];
  throw ConfigError(message);
}

namespace {

// Linear interpolation between closest ranks: rank h = (n - 1) p / 100, between the values of ranks
// floor(h) and floor(h) + 1.
double rank_of(std::size_t n, double p) {
  return (static_cast<double>(n) - 1.0) * std::clamp(p, 0.0, 100.0) / 100.0;
}
double between(double below, double above, double h, std::size_t lower) {
  return below + (h - static_cast<double>(lower)) * (above - below);
}

}  // namespace

double percentile(std::vector<double>& values, double p) {
  assert(!values.empty());
  const double h = rank_of(values.size(), p);
  const auto lower = static_cast<std::size_t>(std::floor(h));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(lower), values.end());
  const double below = values[lower];
  if (lower + 1 >= values.size()) return below;
  const double above =
      *std::min_element(values.begin() + static_cast<std::ptrdiff_t>(lower) + 1, values.end());
  return between(below, above, h, lower);
}

double sorted_percentile(const std::vector<double>& sorted, double p) {
  assert(!sorted.empty());
  const double h = rank_of(sorted.size(), p);
  const auto lower = static_cast<std::size_t>(std::floor(h));
  if (lower + 1 >= sorted.size()) return sorted[lower];
  return between(sorted[lower], sorted[lower + 1], h, lower);
}

Cropper::Cropper(std::vector<Footprint> footprints, CropParams params)
    : index_(std::make_unique<detail::CropIndex>()), params_(std::move(params)) {
  params_.validate();
  detail::CropIndex& index = *index_;
  index.footprints = std::move(footprints);
  index.prepared.resize(index.footprints.size());
  index.collected.resize(index.footprints.size());
  const double wide = params_.ground_buffer * params_.wide_buffer_factor;
  for (std::size_t i = 0; i < index.footprints.size(); ++i) {
    const Footprint& fp = index.footprints[i];
    detail::PreparedFootprint& f = index.prepared[i];
    Box2 all_vertices;
    for (const Polygon2& polygon : fp.polygons) {
      auto add_ring = [&](const Ring2& ring) {
        for (const Point2& v : ring) all_vertices.add(v);
        if (ring.size() < 3) return;  // not a ring: contributes no area
        for (std::size_t k = 0; k < ring.size(); ++k) {
          Point2 a = ring[k], b = ring[(k + 1) % ring.size()];
          if (b.y < a.y || (b.y == a.y && b.x < a.x)) std::swap(a, b);
          f.edges.push_back({a, b});
        }
      };
      if (polygon.outer.size() < 3) continue;
      add_ring(polygon.outer);
      for (const Ring2& hole : polygon.holes) add_ring(hole);
      f.polygon_end.push_back(static_cast<std::uint32_t>(f.edges.size()));
      for (const Point2& v : polygon.outer) f.box.add(v);
    }
    const bool finite = !f.box.empty() && std::isfinite(f.box.min.x) && std::isfinite(f.box.min.y) &&
                        std::isfinite(f.box.max.x) && std::isfinite(f.box.max.y);
    if (!finite) {
      log_warning("crop: footprint " + fp.id + " has no usable polygon; it gets no points");
      f.box = Box2{};
      f.edges.clear();
      f.polygon_end.clear();
    } else {
      f.near_box = detail::expanded(f.box, params_.ground_buffer);
      f.wide_box = detail::expanded(f.box, wide);
      index.collected[i].presence = detail::presence_over(f.box);
    }
    // The origin comes from every vertex we have, so that even an unusable footprint gets one.
    if (!all_vertices.empty() && std::isfinite(all_vertices.min.x) && std::isfinite(all_vertices.max.y)) {
      f.origin = {std::round(0.5 * (all_vertices.min.x + all_vertices.max.x)),
                  std::round(0.5 * (all_vertices.min.y + all_vertices.max.y)), 0.0};
    }
  }
  index.build_grid();
  log_debug("crop: " + std::to_string(index.footprints.size()) + " footprints in a " +
            std::to_string(index.nx) + " x " + std::to_string(index.ny) + " grid of " +
            std::to_string(index.cell) + " m cells");
}

Cropper::~Cropper() = default;
Cropper::Cropper(Cropper&&) noexcept = default;
Cropper& Cropper::operator=(Cropper&&) noexcept = default;

std::size_t Cropper::footprint_count() const { return index_->footprints.size(); }

void Cropper::add(const PointCloud& chunk) {
  if (finished_) throw Error("crop: add() called after finish()");
  const std::size_t n = chunk.points.size();
  const bool has_classes = !chunk.classification.empty();
  if (has_classes && chunk.classification.size() != n) {
    throw Error("crop: chunk has " + std::to_string(n) + " points but " +
                std::to_string(chunk.classification.size()) + " classes");
  }
  if (!has_classes && n > 0 && params_.use_classes == ClassUse::always)
    throw Error("crop: classes required (use_classes = always) but the chunk has none");
  const bool use_classes = has_classes && params_.use_classes != ClassUse::never;

  enum Kind : std::uint8_t { kOther, kBuilding, kGround };
  std::array<std::uint8_t, 256> kind_of{};
  for (std::uint8_t c : params_.building_classes) kind_of[c] = kBuilding;
  if (kind_of[params_.ground_class] == kOther) kind_of[params_.ground_class] = kGround;

  detail::CropIndex& index = *index_;
  stats_.points_seen += n;
  if (index.nx == 0) return;
  const double near2 = params_.ground_buffer * params_.ground_buffer;
  const std::size_t min_ground = params_.min_ground_points;

  for (std::size_t i = 0; i < n; ++i) {
    const Point3& p = chunk.points[i];
    const Kind kind = use_classes ? static_cast<Kind>(kind_of[chunk.classification[i]]) : kBuilding;
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) continue;
    if (p.x < index.x0 || p.y < index.y0 || p.x > index.x0 + static_cast<double>(index.nx) * index.cell ||
        p.y > index.y0 + static_cast<double>(index.ny) * index.cell)
      continue;
    const std::size_t k = static_cast<std::size_t>(index.row(p.y) * index.nx + index.column(p.x));
    const std::uint32_t* first = index.cell_items.data() + index.cell_start[k];
    const std::uint32_t* last = index.cell_items.data() + index.cell_start[k + 1];
    // One walk over the cell's footprints: every point in a footprint's box, whatever its class, says
    // that the tiles have data there; building and ground points are then tested against its rings.
    bool inside_any = false;
    std::array<std::uint32_t, 4> holders;  // the first footprints holding this building point
    std::size_t held = 0;
    for (const std::uint32_t* it = first; it != last; ++it) {
      const detail::PreparedFootprint& f = index.prepared[*it];
      if (!detail::box_contains(f.box, p.x, p.y)) continue;
      detail::mark(index.collected[*it].presence, p.x, p.y);
      if (kind == kOther || !f.contains(p.x, p.y)) continue;
      inside_any = true;
      if (kind == kBuilding) {
        index.collected[*it].building.push_back({p.x - f.origin.x, p.y - f.origin.y, p.z - f.origin.z});
        ++stats_.building_points;
        if (held < holders.size()) holders[held++] = *it;
      }
    }
    for (std::size_t h = 0; held > 1 && h < held; ++h) {
      detail::Collected& c = index.collected[holders[h]];
      if (c.shared++ == 0) c.shared_with = holders[h == 0 ? 1 : 0];
    }
    // Without classes, every point outside the footprints may be ground: the buffer's percentile then
    // takes the ground from under the cars, trees and fences there (the lowest building point, the
    // ladder's next rung, is the eaves where only the roof has points).
    if (inside_any || (use_classes && kind != kGround)) continue;

    for (const std::uint32_t* it = first; it != last; ++it) {
      const detail::PreparedFootprint& f = index.prepared[*it];
      if (!detail::box_contains(f.wide_box, p.x, p.y)) continue;
      detail::Collected& c = index.collected[*it];
      const double local_z = p.z - f.origin.z;
      if (detail::box_contains(f.near_box, p.x, p.y) && f.near_boundary(p.x, p.y, near2)) {
        c.near_ground.push_back(local_z);
        ++stats_.ground_points;
        // Once the near buffer has enough points the wide buffer can never be used: free it. The
        // near count only grows, so this cannot depend on the chunking.
        if (c.near_ground.size() == min_ground) {
          stats_.ground_points -= c.wide_ground.size();
          std::vector<double>().swap(c.wide_ground);
        }
      } else if (c.near_ground.size() < min_ground) {
        c.wide_ground.push_back(local_z);
        ++stats_.ground_points;
      }
    }
  }
}

std::vector<BuildingInput> Cropper::finish() {
  if (finished_) throw Error("crop: finish() called twice");
  finished_ = true;
  detail::CropIndex& index = *index_;
  std::vector<BuildingInput> result(index.footprints.size());
  const std::size_t min_ground = params_.min_ground_points;

  for (std::size_t i = 0; i < result.size(); ++i) {
    BuildingInput& b = result[i];
    detail::Collected& c = index.collected[i];
    const Point3 origin = index.prepared[i].origin;
    b.id = index.footprints[i].id;
    b.origin = origin;
    b.footprint = std::move(index.footprints[i]);
    for (Polygon2& polygon : b.footprint.polygons) {
      auto to_local = [&](Ring2& ring) {
        for (Point2& v : ring) v = {v.x - origin.x, v.y - origin.y};
      };
      to_local(polygon.outer);
      for (Ring2& hole : polygon.holes) to_local(hole);
    }
    b.points = std::move(c.building);
    b.presence = std::move(c.presence);
    // Footprints that overlap: both models hold the points of the overlap, and the ground points there
    // are no one's (they lie inside a footprint).
    if (c.shared > 0 && c.shared * 100 >= b.points.size()) {
      std::ostringstream note;
      note << c.shared << " of its " << b.points.size() << " points lie in footprint "
           << (c.shared_with < i ? result[c.shared_with].id : index.footprints[c.shared_with].id)
           << " too: the footprints overlap";
      b.footprint.note += (b.footprint.note.empty() ? "" : "; ") + note.str();
    }

    // The ground ladder: buffer percentile, wide-buffer percentile, lowest building point, nothing.
    b.ground_heights = std::move(c.near_ground);
    if (b.ground_heights.size() < min_ground)
      b.ground_heights.insert(b.ground_heights.end(), c.wide_ground.begin(), c.wide_ground.end());
    if (b.ground_heights.size() >= min_ground) {
      std::vector<double> heights = b.ground_heights;  // percentile reorders its argument
      b.ground_z = percentile(heights, params_.ground_percentile);
      b.ground_method = c.wide_ground.empty() ? "ground percentile" : "ground percentile (wide buffer)";
      b.ground_measured = true;
    }
    // A ground above half of the building's points is not its ground (ground points in another height
    // datum than the building's, a tile of other heights beside): as the ground field's (input_check.hpp),
    // it is not taken, and the note says so.
    if (b.ground_measured && !b.points.empty()) {
      std::vector<double> z;
      z.reserve(b.points.size());
      for (const Point3& p : b.points) z.push_back(p.z);
      const double median = percentile(z, 50.0);
      if (b.ground_z > median) {
        std::ostringstream note;
        note << std::fixed << std::setprecision(3) << "its ground points (" << b.ground_method << " "
             << b.ground_z + origin.z << " m) lie above half of its points (median " << median + origin.z
             << " m): heights of another datum? the floor is its lowest point instead";
        b.footprint.note += (b.footprint.note.empty() ? "" : "; ") + note.str();
        b.ground_measured = false;
      }
    }
    if (!b.ground_measured && !b.points.empty()) {
      b.ground_z = std::min_element(b.points.begin(), b.points.end(), [](const Point3& a, const Point3& q) {
                     return a.z < q.z;
                   })->z;
      if (b.ground_heights.size() < min_ground)
        b.footprint.note +=
            std::string(b.footprint.note.empty() ? "" : "; ") +
            "no ground point near it: the floor is its lowest point (the eaves where only its roof "
            "has points)";
      b.ground_method = "lowest building point";
    } else if (!b.ground_measured) {
      b.ground_z = 0.0;
      b.ground_method = "none";
    }
    c = detail::Collected{};
  }
  return result;
}

}  // namespace city3d
