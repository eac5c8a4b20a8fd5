// Height map of one building (paper section 3.2): 2D Delaunay TIN of the points, rasterised at
// resolution r, small holes closed morphologically, then Canny edge pixels at height steps.
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "city3d/types.hpp"

namespace city3d {

/// Parameters of rasterise_tin() and detect_edges().
struct HeightmapParams {
  /// Pixel size r, metres; >= 0. 0 = automatic: r = resolution_per_spacing / sqrt(density), density
  /// in points/m2 measured on the TIN (vertices / area of the kept triangles), clamped to
  /// [min_resolution, max_resolution].
  double resolution = 0.0;
  /// The automatic resolution in mean point spacings (1/sqrt(density)), > 0. 0.775 is the paper's
  /// r = 0.20 m at AHN3's ~15 points/m2; it also gives 0.29 m for Vaihingen (7 pts/m2; paper 0.25)
  /// and 0.13 m for DALES (35 pts/m2; paper 0.15).
  double resolution_per_spacing = 0.775;
  /// Bounds of the automatic resolution, metres, 0 < min_resolution <= max_resolution.
  double min_resolution = 0.05;
  double max_resolution = 2.0;
  /// Triangles with an edge longer than this (metres, > 0) are not rasterised, so that concave
  /// outlines and courtyards are not filled. 3 m is about 12 point spacings at AHN3 density:
  /// long enough to bridge gaps (dark roofs, occlusion), short enough to keep an L's notch.
  double max_edge_length = 3.0;
  /// Side of the square structuring element of the morphological closing, pixels; 0 (off) or odd.
  /// 3 fills holes of one pixel (two along a straight line) without moving a straight outline.
  int closing_size = 3;
  /// Canny hysteresis thresholds, metres of height step. The measure is the Sobel-smoothed height
  /// difference between a pixel's two neighbours (2 r apart), so a sharp step of h metres scores
  /// h, and a roof of slope angle a scores 2 r tan(a) (0.40 m at 45 deg, 0.69 m at 60 deg for
  /// r = 0.2). Pixels above canny_high start an edge; pixels above canny_low extend it.
  double canny_low = 0.6;
  double canny_high = 1.5;
  /// Where a footprint's walls are the outline, the edge pixels within this many pixels (rows and columns) of
  /// a pixel without data are left out of the polylines (edges_off_the_rim); >= 0. They are the drop from the
  /// roof to no data, the outline of the points, which the footprint's walls already give: 85% of the Delft
  /// block's edge pixels (docs/BENCHMARKS.md). 1: Canny puts the edge of that drop on the pixel either side
  /// of it.
  int rim_pixels = 1;

  /// Throws ConfigError listing every invalid field ("heightmap: invalid parameters: ...; ...").
  void validate() const;
};

/// A height raster in the local frame of the points. Pixel (col, row) covers
/// [origin.x + col r, origin.x + (col + 1) r) x [origin.y + row r, origin.y + (row + 1) r);
/// row 0 is the southern-most row (y grows with row). z is row-major: z[row * width + col].
struct Heightmap {
  Point2 origin;            ///< south-west corner of pixel (0, 0), metres
  double resolution = 0.0;  ///< pixel size r, metres
  int width = 0;            ///< columns
  int height = 0;           ///< rows
  std::vector<float> z;     ///< heights relative to the points' frame, metres; NaN outside the data

  /// Height of pixel (col, row); NaN without data. Precondition: inside [0, width) x [0, height).
  float at(int col, int row) const { return z[static_cast<std::size_t>(row) * width + col]; }
  /// Centre of pixel (col, row) in the local frame, metres.
  Point2 pixel_centre(int col, int row) const {
    return {origin.x + (col + 0.5) * resolution, origin.y + (row + 0.5) * resolution};
  }
};

/// The automatic resolution for a point density (points/m2): resolution_per_spacing / sqrt(density),
/// clamped to [min_resolution, max_resolution] (0.775 / sqrt(density) in [0.05, 2] m by default).
/// Throws ConfigError when density is not positive and finite.
double automatic_resolution(double points_per_m2, const HeightmapParams& params = {});

/// Rasterises the 2D Delaunay TIN of `local_points` (xy triangulated, z interpolated linearly
/// inside each triangle at pixel centres). Points with equal xy keep the highest z. Triangles with
/// an edge longer than max_edge_length are left out. Then a grey-level morphological closing fills
/// small holes: pixels without data take part as a level far below the data, so only holes
/// enclosed by data are filled and a straight outline does not move. The raster has one empty
/// pixel of margin on every side, so outline edges are found in detect_edges().
/// Points must be in a local metric frame. Throws ConfigError (invalid params) or
/// ReconstructionError (fewer than 3 distinct xy, no triangle short enough, non-finite
/// coordinates, or a raster above 50 million pixels).
/// Lowest and highest data height of a heightmap; {+inf, -inf} when it has none.
std::pair<float, float> height_range(const Heightmap& map);

Heightmap rasterise_tin(const std::vector<Point3>& local_points, const HeightmapParams& params);

/// Canny edge pixels of the height field: the height steps between roof parts and the building's
/// outline (pixels without data count as a level below the lowest data, at least 5 m and at least
/// 2 canny_high lower, so the outline always gives a strong edge). Returns the centres of the
/// edge pixels in the heightmap's metric frame, row by row (south to north), west to east.
/// Throws ConfigError (invalid params).
std::vector<Point2> detect_edges(const Heightmap& heightmap, const HeightmapParams& params);

/// `edges` (pixel centres, as detect_edges() gives them) without those within params.rim_pixels
/// pixels (rows and columns) of a pixel without data: the edges inside the data, away from its rim.
/// The raster's empty margin counts as without data. Order is kept. Throws ConfigError (invalid
/// params).
std::vector<Point2> edges_off_the_rim(const Heightmap& heightmap, const std::vector<Point2>& edges,
                                      const HeightmapParams& params);

/// The outline of the building for a cloud without footprint. The points are binned into the
/// heightmap's pixel grid and the occupancy closed morphologically over about `gap_spacings` point
/// spacings (1.5; the spacing from the points per heightmap data area), so the outline follows the points and not
/// the TIN, whose long triangles cut inner corners. The outer boundary of each connected region runs
/// through its boundary pixels' centres, simplified by Douglas-Peucker with `tolerance` metres plus
/// the point spacing, then moved outward by half a pixel and half a point spacing (where the true
/// wall lies on average); regions under `min_area` m2 are dropped. Polygons are counter-clockwise, in the heightmap's
/// (local) frame, without holes; largest first.
std::vector<Polygon2> infer_outline(const Heightmap& heightmap, const std::vector<Point3>& local_points,
                                    double tolerance = 0.25, double min_area = 2.0, double gap_spacings = 1.5);

}  // namespace city3d
