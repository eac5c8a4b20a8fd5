// Debug output (--debug DIR): each stage's intermediate result of one building, written for a person
// to look at (PNG images, coloured PLY points, OBJ lines and faces). The geometry modules do no file
// IO: the pipeline hands one DebugTrace through a building's stages, which give it their results. Every writer throws IoError naming the file
// when it cannot be written.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "city3d/heightmap.hpp"
#include "city3d/hypothesis.hpp"
#include "city3d/planes.hpp"
#include "city3d/polylines.hpp"
#include "city3d/regularise.hpp"
#include "city3d/types.hpp"
#include "city3d/walls.hpp"

namespace city3d {

/// `<debug_dir>/<id made file-safe>/<name>`, creating the building's folder.
std::string debug_path(const std::string& debug_dir, const BuildingId& id, const std::string& name);

/// The points as an ASCII PLY, coloured by planar segment (a fixed colour per segment, grey for points
/// in none), with the segment index as a property (-1: none).
void write_planes_ply(const std::string& path, const std::vector<Point3>& points,
                      const std::vector<PlanarSegment>& segments);

/// The heightmap as an 8-bit grey PNG, north up: lowest data 1, highest 255, no data 0.
void write_heightmap_png(const Heightmap& heightmap, const std::string& path);

/// The heightmap (grey, as above) with `edges` (points in the heightmap's frame, e.g. from
/// detect_edges()) painted red, as an RGB PNG, north up. Edges outside the raster are ignored.
void write_edges_png(const Heightmap& heightmap, const std::vector<Point2>& edges, const std::string& path);

/// Polylines as OBJ vertices and `l i j ...` lines at height `z`.
void write_polylines_obj(const std::string& path, const std::vector<Polyline2>& polylines, double z = 0.0);

/// Segments as OBJ vertices at height `z`, one `l i j` per segment.
void write_segments_obj(const std::string& path, const std::vector<Segment2>& segments, double z = 0.0);

/// Walls as vertical OBJ quads from z0 to z1 (outer and inner alike).
void write_walls_obj(const std::string& path, const std::vector<VerticalPlane>& walls, double z0, double z1);

/// The candidate faces as OBJ, one object per face named by kind and index.
void write_candidates_obj(const std::string& path, const CandidateFaces& candidates);

/// The selection over the candidate faces as CSV, one row per face in face order: its kind, roof plane,
/// cell or edge, area, height range, support, the terms the energy gives it, whether the face prior or
/// another rule fixed it, and whether it was selected (what to read when a model holds a face that no
/// point asks for).
void write_selection_csv(const std::string& path, const CandidateFaces& candidates, const std::vector<bool>& selected,
                         const SelectionParams& energy);

/// The debug output of one building (--debug DIR): a rung's stages each leave their result here as
/// they go, and write_debug_trace() writes what they left, in one place, when the rung has ended
/// (with a model or not). File names in README, "Debug output".
struct DebugTrace {
  std::string dir;                            ///< --debug DIR
  BuildingId id;
  double ground_z = 0.0;                      ///< lines and walls are drawn from the floor's height
  const std::vector<Point3>* points = nullptr;
  std::optional<std::vector<PlanarSegment>> planes;     ///< planes.ply: the points coloured by plane
  std::optional<std::vector<Polyline2>> step_lines;     ///< step_lines.obj
  /// heightmap.png, edges.png, polylines.obj (with the step lines) and regularised.obj
  std::shared_ptr<const Heightmap> heightmap;
  std::shared_ptr<const std::vector<Point2>> edges;
  std::optional<std::vector<Polyline2>> polylines;
  std::optional<std::vector<Segment2>> regularised;
  /// walls<part>.obj and candidates<part>.obj, by the part's suffix ("" or "_part1")
  std::vector<std::pair<std::string, std::vector<VerticalPlane>>> walls;
  std::vector<std::pair<std::string, CandidateFaces>> candidates;
  /// selection<part>.csv: the part's candidates, the faces selected and the energy's parameters
  struct Selection {
    std::string suffix;
    CandidateFaces candidates;
    std::vector<bool> selected;
    SelectionParams energy;
  };
  std::vector<Selection> selections;
  /// rejected_<rung>.obj: a model not valid as written, in local coordinates
  std::vector<std::pair<std::string, BuildingModel>> rejected;
};

/// Writes what `trace` holds into `<dir>/<id>/` and empties it (the next rung fills it anew). Throws
/// IoError as the writers above do.
void write_debug_trace(DebugTrace& trace);

}  // namespace city3d
