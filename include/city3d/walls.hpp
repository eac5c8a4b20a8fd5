// Walls: the vertical planes of a building, from its footprint (outer walls), from regularised
// heightmap lines (inner walls, or every wall without a footprint) or from detected wall lines
// (paper sections 3.2 and 4.6).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "city3d/planes.hpp"
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

/// Where the walls come from. The pipeline passes footprint for automatic, with a cloud's inferred
/// outline as the footprint.
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
  /// Inner lines are sampled this far apart to tell their parts inside the footprint and away from
  /// its boundary, metres, > 0.
  double sample_step = 0.1;
  /// Without a footprint, a line is an outer wall when at least this many of the 15 rays cast from
  /// one of its sides escape past every other line (and more than from its other side), in [1, 15].
  int min_escaping_rays = 3;
  /// The rays from each of the three points fan out at 0, +-ray_fan_step and +-2 ray_fan_step degrees
  /// from the line's normal, in (0, 45].
  double ray_fan_step = 30.0;
  /// A detected wall along the footprint faces away from the footprint's inside as seen at a point
  /// this far beyond footprint_margin off its middle, metres, > 0.
  double side_probe = 0.05;

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
/// is an outer wall when, of the rays cast from three points along it (1/4, 1/2, 3/4) to one side, in a
/// fan about the normal (ray_fan_step), at least min_escaping_rays cross no other line, and more than
/// from its other side (it faces the outside); the normal points to that side. Lines enclosed on both
/// sides are inner walls. This suits the closed outlines the heightmap gives; a
/// concave hull would cut into courtyards.
///
/// Throws ConfigError for invalid params or for mode footprint without a footprint, and
/// ReconstructionError for mode detected without detected lines.
std::vector<VerticalPlane> infer_walls(const RegularisationResult& lines,
                                       const std::vector<Polygon2>* footprint_local,
                                       const std::vector<std::pair<Point2, Point2>>& detected_wall_lines,
                                       const WallParams& params);

/// Parameters of detect_step_lines().
struct StepLineParams {
  bool enabled = true;
  /// Two planes whose heights differ by at least this where their points meet make a step, metres,
  /// > 0. 0.5 m: above the 0.3 m support distance (a smaller difference is one roof within the
  /// points' spread) and below the heightmap's Canny thresholds (0.6 / 1.5 m), whose edges take the
  /// larger steps only where the TIN does not smear them.
  double min_step = 0.5;
  /// Radius of the search for the other plane's points, in point spacings (sqrt(1 / density)), > 0.
  /// 3 spacings bridge the one or two unsegmented points that usually line a step.
  double search_spacings = 3.0;
  /// Boundary samples within this distance of a line belong to it, metres, > 0 (the polylines'
  /// eps_d).
  double line_tolerance = 0.25;
  double min_length = 1.0;  ///< shorter step lines are dropped, metres, >= 0
  int min_samples = 4;      ///< boundary samples a step line needs, >= 2
  /// Share of the two planes' points beside a step line (within the search radius) that must lie on
  /// their own plane's side of it, in [0.5, 1] (0.5 = no test): a line that does not separate the
  /// planes (their points interleave, as on a sawtooth roof grown into few planes) is no step.
  /// 0.65, not stricter: unsegmented points and refitted planes make real step borders ragged
  /// (0.8 lost half of the step lines' gain on the Delft block, docs/BENCHMARKS.md), while
  /// interleaved strips score about 0.5 (AHN3/07163: 1,972 step lines without the test, 592 with it).
  double min_separation = 0.65;

  /// Throws ConfigError listing every invalid field.
  void validate() const;
};

/// The step lines of one building (local frame): where points of one roof plane meet points of
/// another (within search_spacings x point_spacing in xy) and the two planes' heights differ by
/// min_step or more, with the same sign, at both points (a step, not a crease between them), the
/// midpoints are boundary samples of that pair of planes; straight
/// runs of them (within line_tolerance, no gap wider than the search radius, min_samples samples and
/// min_length long, separating the two planes' points, see min_separation) are the step lines, as
/// two-point polylines, to be regularised with the
/// heightmap's lines. Pairs whose planes meet at about the same height are left to the roof-roof
/// intersection lines of the hypothesis. Deterministic. Throws ConfigError for invalid params.
std::vector<Polyline2> detect_step_lines(const std::vector<Point3>& local_points,
                                         const std::vector<PlanarSegment>& roof_planes, double point_spacing,
                                         const StepLineParams& params);

}  // namespace city3d
