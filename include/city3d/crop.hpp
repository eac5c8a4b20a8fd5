// Cropping: streams point-cloud chunks against the footprints and yields one BuildingInput per
// footprint (its points and nearby ground points in a local frame, plus a ground height).
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "city3d/point_cloud_io.hpp"
#include "city3d/types.hpp"

namespace city3d {

/// Where the tiles have points, of any class, over one footprint's bounding box: a lattice of square
/// cells of `cell` metres aligned to multiples of it in world coordinates, cell (i, j) covering
/// [i cell, (i + 1) cell) x [j cell, (j + 1) cell). What coverage counts cells with points in
/// (FootprintCoverage): it tells where the data has no points at all from where the building class
/// has none (trees over a roof, points classified otherwise).
struct PointPresence {
  double cell = 0.25;             ///< metres: 0.25, doubled until the box has at most kMaxPresenceCells
  std::int64_t i0 = 0, j0 = 0;    ///< the first cell's lattice indices
  std::int64_t nx = 0, ny = 0;    ///< cells across and up; 0 for a footprint without a usable ring
  std::vector<bool> marked;       ///< nx * ny, row by row from (i0, j0)
  /// True when a point fell in lattice cell (i, j); false outside the box.
  bool at(std::int64_t i, std::int64_t j) const {
    return i >= i0 && j >= j0 && i < i0 + nx && j < j0 + ny && marked[static_cast<std::size_t>((j - j0) * nx + (i - i0))];
  }
};

/// The most cells a footprint's PointPresence has (512 KB of bits).
constexpr std::int64_t kMaxPresenceCells = std::int64_t{1} << 22;

/// Everything the per-building stages need about one building, in a local frame.
///
/// The local frame: world = local + origin. `origin` is the centre of the footprint's bounding box
/// rounded to the metre, with z = 0 (heights stay absolute, e.g. NAP). Subtracting an integer origin
/// from world coordinates of similar magnitude is exact in double, so local + origin gives back the
/// world coordinates bit for bit.
struct BuildingInput {
  BuildingId id;
  Footprint footprint;                ///< the footprint moved to the local frame (same id, fid, rings)
  bool footprint_given = true;        ///< false for single-building clouds: `footprint` is only their hull
  Point3 origin;                      ///< world = local + origin; z = 0
  std::vector<Point3> points;         ///< building points inside the footprint, local, in input order
  /// Heights (local z) of the ground points that gave ground_z (see ground_method), in input order.
  /// Only their heights: the crop holds every footprint's ground points at once, and x and y would
  /// double what they take.
  std::vector<double> ground_heights;
  double ground_z = 0.0;              ///< floor height, local (= world, since origin.z = 0), metres
  std::string ground_method;          ///< "ground percentile", "ground percentile (wide buffer)",
                                      ///< "lowest building point" or "none"
  /// true when ground_z is measured (ground points, a footprint attribute, the user's --ground-z);
  /// false when it is only the lowest building point, an upper bound of the ground (a roof-only
  /// cloud has its lowest point at the eaves), or unknown.
  bool ground_measured = false;
  /// Where the tiles have points (any class) over the footprint's box, for its coverage; empty for
  /// single-building clouds.
  PointPresence presence;
};

/// How points are classified while cropping.
enum class ClassUse {
  automatic,  ///< per chunk: use classes when the chunk has them, else as `never`
  always,     ///< require classes; a chunk without them throws Error
  /// ignore classes: every point inside a footprint is a building point, and every point outside them
  /// (within the buffers) a ground point
  never,
};

/// Parameters of the crop stage.
struct CropParams {
  std::vector<std::uint8_t> building_classes{6};  ///< LAS classes of building points
  std::uint8_t ground_class = 2;                  ///< LAS class of ground points
  ClassUse use_classes = ClassUse::automatic;
  /// Ground points within this distance (metres, >= 0) of the footprint polygon, and outside every
  /// footprint, give the ground height.
  double ground_buffer = 3.0;
  /// Fallback neighbourhood when the buffer holds too few ground points: the footprint's bounding box
  /// expanded by ground_buffer x wide_buffer_factor (>= 1), again outside every footprint.
  double wide_buffer_factor = 4.0;
  double ground_percentile = 10.0;     ///< percentile (0-100) of ground z taken as the floor height
  std::size_t min_ground_points = 10;  ///< ground points needed (>= 1) in the buffer or wide buffer

  /// Throws ConfigError listing every invalid field.
  void validate() const;
};

/// Counters of one crop run, for logging.
struct CropStats {
  std::uint64_t points_seen = 0;      ///< points passed to add()
  std::uint64_t building_points = 0;  ///< (point, footprint) assignments of building points
  std::uint64_t ground_points = 0;    ///< (point, footprint) assignments to ground buffers (kept now)
};

namespace detail {
struct CropIndex;
}

/// Streams chunks of a point cloud against a set of footprints.
///
/// Points are assigned in xy to every footprint that contains them (even-odd rule over all rings of
/// a polygon, so holes are excluded; a multipolygon contains what any of its polygons contains).
/// A point exactly on an edge shared by two footprints goes to exactly one of them, always the same
/// (half-open crossing rule evaluated on canonically ordered edges). Only points relevant to some
/// footprint are kept, so memory follows the footprints, not the tiles. The result does not depend
/// on how the cloud is split into chunks.
class Cropper {
 public:
  /// Prepares the spatial index over `footprints` (world coordinates). Throws ConfigError when
  /// `params` is invalid. Footprints without a usable ring still get a BuildingInput, with no points.
  Cropper(std::vector<Footprint> footprints, CropParams params = {});
  ~Cropper();
  Cropper(Cropper&&) noexcept;
  Cropper& operator=(Cropper&&) noexcept;
  Cropper(const Cropper&) = delete;
  Cropper& operator=(const Cropper&) = delete;

  /// Assigns the points of `chunk` (world coordinates). Points with non-finite coordinates are
  /// ignored. Throws Error when the chunk's classification vector has the wrong length, when classes
  /// are required but absent, or after finish().
  void add(const PointCloud& chunk);

  /// Computes the ground heights and returns one BuildingInput per footprint, in input order. Call
  /// once, after the last add(); the collected points are moved out. Throws Error on a second call.
  std::vector<BuildingInput> finish();

  const CropStats& stats() const { return stats_; }
  std::size_t footprint_count() const;

 private:
  std::unique_ptr<detail::CropIndex> index_;
  CropParams params_;
  CropStats stats_;
  bool finished_ = false;
};

/// How much of a footprint the points can speak for. A footprint the tiles given only partly cover
/// (a tile forgotten at a seam) is built from the points of the part they cover, and its model is
/// wrong in a way nothing else shows (README, "Coverage").
struct FootprintCoverage {
  /// Share (0-1) of the footprint's area inside the tiles' extents (tile_extent()).
  double area = std::numeric_limits<double>::quiet_NaN();
  /// Share (0-1) of its cells (coverage_cell_size(), aligned to multiples of the size in world
  /// coordinates; those whose centres lie inside it) where the tiles have at least one point of
  /// any class; for a footprint that holds no cell centre, 1 when a point fell in its box, else 0.
  double cells = std::numeric_limits<double>::quiet_NaN();
  /// Share (0-1) of those cells with a point where one of the building's own points is: the rest of
  /// them hold only other classes (ground where the footprint outgrows the building, a tile whose
  /// buildings are not classified, trees over a roof). NaN when no cell has a point.
  double building = std::numeric_limits<double>::quiet_NaN();
};

/// A tile's mean point spacing, metres: the square root of its xy box's area per point (0 without
/// points or bounds).
double point_spacing(const Box3& bounds, std::uint64_t points);

/// A tile's extent for coverage, from its header bounds: the xy box grown by half its mean point
/// spacing, so that two tiles that meet with a gap of less than a point spacing between their
/// outermost points (Delft's tiles: 2 mm at x = 85000) leave no gap between their extents. Empty
/// for a tile without points or bounds.
Box2 tile_extent(const Box3& bounds, std::uint64_t points);

/// The cell size coverage counts points in, metres, for tiles of mean point spacing `spacing` and
/// a presence lattice of `presence_cell`: three times the spacing (about nine points per cell, so
/// that an empty cell means missing data rather than chance), at least 1 m, rounded up to a
/// multiple of `presence_cell`.
double coverage_cell_size(double spacing, double presence_cell);

/// The coverage of a building's footprint (`input.footprint.polygons`, local) by the tile
/// `extents` (local) and by the points of `input.presence`, counted in cells for tiles of mean
/// point spacing `spacing` (the sparsest tile that meets it).
FootprintCoverage footprint_coverage(const BuildingInput& input, const std::vector<Box2>& extents, double spacing);

/// The p-th percentile (0-100) of `values` with linear interpolation between closest ranks (as
/// numpy's default). Precondition: `values` is not empty. The vector is reordered.
double percentile(std::vector<double>& values, double p);

/// The same of values already sorted ascending, without reordering them: the same number as
/// percentile() gives for any order of these values.
double sorted_percentile(const std::vector<double>& sorted, double p);

}  // namespace city3d
