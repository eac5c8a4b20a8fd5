// Private interface of the footprint readers (one source file per format) and the ring clean-up
// both of them apply, so that OGR and OBJ footprints come out in the same normal form.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "city3d/footprint_io.hpp"
#include "city3d/rings.hpp"
#include "city3d/types.hpp"

namespace city3d::detail {

/// How read_ogr_footprints() hands out what it reads: kept in the returned set (no sink), or each
/// kept footprint passed to `sink` and not kept (a source too large to hold); `quiet` turns the
/// per-feature warnings and the summary into debug messages (a second read of the same features);
/// `keep_duplicates` keeps a footprint whose id an earlier one has (a read of a region, where the
/// earlier holder may be outside it or come later in the spatial index's order).
struct FootprintReadMode {
  const std::function<void(Footprint&&)>* sink = nullptr;
  bool quiet = false;
  bool keep_duplicates = false;
};

/// Reads an OGR vector source (see read_footprints). Throws IoError.
FootprintSet read_ogr_footprints(const std::string& path, const FootprintReadOptions& options,
                                 const FootprintReadMode& mode = {});

/// summarise_fields() for an OGR vector source. Throws IoError.
std::vector<FieldSummary> summarise_ogr_fields(const std::string& path, const FootprintReadOptions& options,
                                               std::size_t max_features, std::size_t& features);

/// Layer names of an OGR vector source. Throws IoError.
std::vector<std::string> list_ogr_layers(const std::string& path);

/// Reads a City3D OBJ polygon file: every face is one footprint. Throws IoError.
FootprintSet read_obj_footprints(const std::string& path, const FootprintReadOptions& options);

/// What became of one footprint geometry: its usable polygons, or why there are none.
struct RepairedPolygons {
  std::vector<Polygon2> polygons;  ///< empty when the footprint must be skipped
  std::string skip_reason;         ///< set when skipped
  std::string repair_note;         ///< set when repaired (the validity problem GEOS reported)
};

/// Checks polygons read by any footprint reader (rings as stored, in any orientation) with GEOS and
/// repairs invalid ones with MakeValid (when `repair`), exactly as OGR sources are treated, so that a
/// bow-tie gives the same footprint from GeoJSON and from an OBJ file. Rings come out normalised.
RepairedPolygons check_and_repair(const std::vector<Polygon2>& polygons, bool repair);

/// Drops the closing vertex and consecutive duplicate vertices (exact comparison: the readers
/// must not move a vertex). A ring of fewer than 3 vertices afterwards is degenerate.
inline Ring2 clean_ring(const Ring2& ring) {
  Ring2 cleaned;
  cleaned.reserve(ring.size());
  for (const Point2& p : ring) {
    if (!cleaned.empty() && cleaned.back().x == p.x && cleaned.back().y == p.y) continue;
    cleaned.push_back(p);
  }
  while (cleaned.size() > 1 && cleaned.front().x == cleaned.back().x &&
         cleaned.front().y == cleaned.back().y) {
    cleaned.pop_back();
  }
  return cleaned;
}

/// Reverses a ring's orientation while keeping its first vertex first, so that the same ring read
/// from two formats that store it in opposite orientations comes out vertex for vertex equal.
inline void reverse_ring(Ring2& ring) {
  if (ring.size() > 2) std::reverse(ring.begin() + 1, ring.end());
}

/// Cleans the rings of a polygon and orients them (outer counter-clockwise, holes clockwise).
/// Degenerate holes are dropped. Returns false when the outer ring is degenerate (fewer than 3
/// distinct vertices or zero area), in which case the polygon must be dropped.
inline bool normalise_polygon(Polygon2& polygon) {
  polygon.outer = clean_ring(polygon.outer);
  const double outer_area = twice_signed_area(polygon.outer);
  if (polygon.outer.size() < 3 || outer_area == 0.0) return false;
  if (outer_area < 0.0) reverse_ring(polygon.outer);
  std::vector<Ring2> holes;
  holes.reserve(polygon.holes.size());
  for (const Ring2& hole : polygon.holes) {
    Ring2 cleaned = clean_ring(hole);
    const double hole_area = twice_signed_area(cleaned);
    if (cleaned.size() < 3 || hole_area == 0.0) continue;
    if (hole_area > 0.0) reverse_ring(cleaned);
    holes.push_back(std::move(cleaned));
  }
  polygon.holes = std::move(holes);
  return true;
}

/// Why polygons cannot be a building's footprint for their size (their bounding box wider or longer
/// than `max_extent` metres), or empty.
inline std::string extent_problem(const std::vector<Polygon2>& polygons, double max_extent) {
  double min_x = 0, max_x = 0, min_y = 0, max_y = 0;
  bool first = true;
  for (const Polygon2& p : polygons)
    for (const Point2& v : p.outer) {
      min_x = first ? v.x : std::min(min_x, v.x);
      max_x = first ? v.x : std::max(max_x, v.x);
      min_y = first ? v.y : std::min(min_y, v.y);
      max_y = first ? v.y : std::max(max_y, v.y);
      first = false;
    }
  const double extent = std::max(max_x - min_x, max_y - min_y);
  if (extent <= max_extent) return {};
  char text[160];
  std::snprintf(text, sizeof text, "%.6g m across, more than the %.6g m a building can be (wrong unit or CRS?)",
                extent, max_extent);
  return text;
}

}  // namespace city3d::detail
