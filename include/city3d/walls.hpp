// Walls: the vertical planes of a building, from its footprint (outer walls), from regularised
// heightmap lines (inner walls, or every wall without a footprint) or from detected wall lines
// (paper sections 3.2 and 4.6).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "city3d/regularise.hpp"
#include "city3d/types.hpp"

namespace city3d {

/// One vertical plane: the points p with dot(normal, p) == offset (in xy), over the extent a-b.
struct VerticalPlane {
  Point2 a, b;          ///< extent of the wall line in xy, local frame, metres
  Point2 normal;        ///< unit, horizontal; points out of the building for outer walls; for inner walls
                        ///< it is the left normal of a -> b
  double offset = 0.0;  ///< dot(normal, a) == dot(normal, b)
  bool outer = false;   ///< on the building's outline (footprint ring, or inferred outline)
  enum class Source { footprint, inferred, detected } source = Source::inferred;
};

/// Where the walls come from.
enum class WallMode {
  automatic,  ///< footprint when one is given; else detected when plentiful (see infer_walls); else inferred
  footprint,  ///< outer walls = footprint edges, inner walls = inferred lines inside the footprint
  inferred,   ///< every wall from the regularised lines (footprint ignored)
  detected,   ///< every wall from the detected wall lines (footprint only used to tell outer from inner)
};

/// Parameters of the wall stage. Distances in metres.
struct WallParams {
  WallMode mode = WallMode::automatic;
  /// Walls (and the inner part of inferred lines) shorter than this are dropped. >= 0.
  double min_wall_length = 0.5;
  /// Inner lines within this of the footprint boundary are dropped: the footprint wall already covers
  /// them. >= 0.
  double footprint_margin = 0.3;
  /// Automatic mode without a footprint picks the detected lines when they are at least this many
  /// and their total length is at least detected_length_ratio x the total length of the regularised
  /// lines.
  int min_detected_lines = 3;
  double detected_length_ratio = 0.5;  ///< >= 0

  /// Throws ConfigError listing every invalid field.
  void validate() const;
};

/// Builds the vertical planes of one building (local frame).
///
/// With a footprint (modes footprint/automatic): one outer wall per footprint edge, consecutive
/// collinear edges merged (within 1 mm), normals pointing out of the polygon (holes included: their
/// walls face into the hole); then inner walls: the parts of the regularised lines inside the
/// footprint, kept when at least min_wall_length of them is farther than footprint_margin from the
/// footprint boundary (a line along the boundary duplicates a footprint wall).
///
/// Without a footprint (mode inferred, or detected), the outline is not closed into a polygon: a line
/// is an outer wall when, from most of three points along it (1/4, 1/2, 3/4), a perpendicular ray to
/// one side crosses no other line (it faces the outside); the normal points to that side. Lines
/// enclosed on both sides are inner walls. This suits the closed outlines the heightmap gives; a
/// concave hull would cut into courtyards.
///
/// Throws ConfigError for invalid params or for mode footprint without a footprint, and
/// ReconstructionError for mode detected without detected lines.
std::vector<VerticalPlane> infer_walls(const RegularisationResult& lines,
                                       const std::vector<Polygon2>* footprint_local,
                                       const std::vector<std::pair<Point2, Point2>>& detected_wall_lines,
                                       const WallParams& params);

}  // namespace city3d
