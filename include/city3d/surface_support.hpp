// Surface support: how much of a model's surface its points ask for (issue 23). The RMSE measures one
// direction only, from each point to the model: a face that no point is near costs nothing there, so a
// model can carry a steep blade metres above its roof and still fit its points. This measures the other
// direction, from the model to the points:
//
//   - every face but the ground is sampled, area-weighted, no two neighbouring samples farther apart
//     than sample_spacing (a square grid of that spacing in the face's plane, each sample carrying an
//     equal share of the face's area);
//   - a sample's local top is the highest point within radius of it in plan;
//   - the unsupported area is the area of the samples more than tolerance above their local top, and
//     the height excess the largest height of such a sample above its local top (0 when there is none);
//   - the unpointed roof area is the area of the roof samples with no point within radius in plan.
//
// unexplained_points (points farther than 1 m from the model) asks the same question the other way:
// a model faithful both ways has neither.
//
// The hypothesis (src/hypothesis/cell_planes.cpp) uses the same measure on each candidate roof face, so
// that a plane is not lifted onto a cell where its face would rise over no point.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "city3d/types.hpp"

namespace city3d {

/// The measure's parameters. Distances in metres.
struct SurfaceSupportParams {
  double sample_spacing = 0.25;  ///< largest distance between neighbouring samples of a face, > 0
  double radius = 1.5;           ///< plan distance of the points that make a sample's local top, > 0
  double tolerance = 1.0;        ///< height above the local top from which a sample is unsupported, >= 0
  /// An unsupported sample or column is measured again at 1/refine of the spacing (refine^2 samples in
  /// its square, refine columns in its width), odd (the middle one stands where the sample stood) and
  /// >= 1: a gap in the points narrower than the spacing, next to a wall, then counts for its own width,
  /// not for the spacing's (Delft b112715ef: a 0.25 m column 4.5 m high over one such gap was 1.1 m2 of
  /// a 1.4 m2 total). Only unsupported samples are refined: the cost stays with them.
  int refine = 5;
  /// Throws ConfigError listing every invalid field.
  void validate() const;
};

/// The highest of a set of points within a radius in plan of a position. Built once per building (a
/// grid of bins of radius / 2, each bin's points by descending height), then queried in about a
/// microsecond: a bin is skipped when its highest point cannot beat the best so far, taken whole when
/// it lies inside the disc, and searched from the top otherwise. Each bin also keeps a lower bound of the
/// local top anywhere in it (the highest point within radius minus half the bin's diagonal of its
/// centre: within radius of every position in the bin), so that a sample well below it is known to be
/// supported without a search.
class LocalTop {
 public:
  LocalTop(const std::vector<Point3>& points, double radius);
  /// The highest z of the points within radius of (x, y) in plan (boundary included); NaN when there is
  /// none.
  double at(double x, double y) const;
  /// A lower bound of at(x, y), -inf when none is known (no point near the bin's centre).
  double lower_bound(double x, double y) const;
  /// A lower bound of at() over `box`, -inf when none is known somewhere in it.
  double lower_bound_in(const Box2& box) const;
  double radius() const { return radius_; }

 private:
  struct Bin {
    std::uint32_t begin = 0, end = 0;  // range of `points_` (by descending z)
  };
  double search(double x, double y, double radius) const;
  double radius_;
  Point2 origin_{0.0, 0.0};
  double size_ = 1.0;
  long nx_ = 0, ny_ = 0;
  std::vector<Bin> bins_;
  std::vector<Point3> points_;  // grouped by bin, each bin by descending z (then x, y)
  std::vector<double> bound_;   // per bin: the lower bound of at() in it, -inf: none
};

/// The local top on a raster, for the many candidate faces of the hypothesis (the selection's E_u and the
/// support cuts): each cell of `cell` metres over `region` stands for the local top at its centre, so the
/// many samples of a face near one another cost one search, at the price of reading the local top up to
/// cell / sqrt(2) away in plan. A cell's top is searched the first time it is read (a face well below
/// the lower bounds of LocalTop is passed over without sampling, and a sample without a search), and
/// kept. Not for concurrent use. Measures of a model (report, evaluate) use LocalTop itself. `local_top`
/// must outlive the raster.
class LocalTopRaster {
 public:
  LocalTopRaster(const LocalTop& local_top, const Box2& region, double cell);
  /// The local top at the centre of the cell holding (x, y); NaN outside the region or where no point is
  /// near.
  double at(double x, double y) const;
  /// A lower bound of at() over `box`, -inf when none is known somewhere in it.
  double lower_bound_in(const Box2& box) const;
  /// Whether z lies more than `tolerance` above at(x, y) (false where at() is NaN). Where the lower
  /// bound of the top at the cell's centre leaves z at most `tolerance` above it, the answer is known
  /// without a search: at() (a float) is at least that bound rounded to a float.
  bool above(double x, double y, double z, double tolerance) const;
  /// The area of the polygon `face` more than params.tolerance above its local top, sampled as
  /// sample_polygon does at params.sample_spacing.
  double unsupported_area(const std::vector<Point3>& face, const struct SurfaceSupportParams& params) const;

 private:
  long cell_of(double x, double y) const;  // -1 outside the region
  const LocalTop* local_top_;
  Point2 origin_{0.0, 0.0};
  double cell_ = 1.0;
  long nx_ = 0, ny_ = 0;
  mutable std::vector<float> top_;           // per cell, NaN: none
  mutable std::vector<unsigned char> known_;  // per cell: top_ searched
};

/// Samples the polygon `face` (simple, planar, any orientation; non-convex allowed) on a square grid of
/// `spacing` in its plane, cell centres inside it (a face thinner than the spacing is scanned with closer
/// rows, its samples still `spacing` apart along it): replaces `samples` with them, in a deterministic
/// order, and returns the area each carries (the polygon's area over their count; 0 and no sample for a
/// polygon without area). A face of more than 4 million spacing squares (250,000 m2 at 0.25 m: a cloud
/// in millimetres read as metres) is sampled at the spacing that gives 4 million: its samples are held.
double sample_polygon(const std::vector<Point3>& face, double spacing, std::vector<Point3>& samples);

/// What surface_support() measured. Areas in m2, heights in metres.
struct SurfaceSupport {
  double unsupported_area = 0.0;     ///< samples more than tolerance above their local top
  double unsupported_roof_area = 0.0;  ///< of it, on roof faces
  double height_excess = 0.0;        ///< the largest height of those samples above their local top; 0: none
  double unpointed_roof_area = 0.0;  ///< roof samples with no point within radius in plan
  double sampled_area = 0.0;         ///< every face sampled (the ground excluded)
  /// Per face of the mesh: its unsupported area (0 for the ground).
  std::vector<double> face_unsupported_area;
  /// The unsupported samples, in sampling order.
  std::vector<Point3> unsupported_samples;
};

/// Measures `mesh` against the points of `local_top` (same frame). `types` gives each face's semantic
/// type (surface_types() of model_io.hpp classifies the faces of a model without semantics by their
/// normal); a face without an entry counts as a wall. Faces with out-of-range indices are skipped.
/// Walls are measured as columns params.sample_spacing wide, other faces as sample_polygon's samples; an
/// unsupported column or sample is measured again at 1/refine of the spacing (its area, its excess and its
/// unsupported samples are those of the finer ones), so that a gap in the points narrower than the
/// spacing counts for its own width. Never throws on bad geometry.
SurfaceSupport surface_support(const PolygonMesh& mesh, const std::vector<SurfaceType>& types,
                               const LocalTop& local_top, const SurfaceSupportParams& params = {});

/// Semantic types of a mesh's faces that do not depend on their orientation (other tools' models, City3D's
/// among them, are not consistently oriented): a face within ~6 degrees of vertical is a wall, a face
/// that lies at the mesh's lowest height (every vertex within 1 cm of it) is the ground, any other a roof.
std::vector<SurfaceType> surface_types_unoriented(const PolygonMesh& mesh);

/// The points beneath surface no point supports: point i is marked when an unsupported sample of
/// `support` lies within params.radius of it in plan and more than params.tolerance above it (the
/// points such a sample's local top was taken from, and those lower). These are the points a model
/// with a blade misrepresents, whatever their distance to it (a low annex beside a wall is near the
/// wall).
std::vector<bool> points_beneath_unsupported(const SurfaceSupport& support, const std::vector<Point3>& points,
                                             const SurfaceSupportParams& params = {});

/// How faithful a model is to the building's points, both ways: from the points to the model, how many
/// lie farther than kUnexplainedDistance (building_report.hpp) and the sum of the squared distances;
/// from the model to the points, its surface no point supports.
struct ModelFit {
  std::size_t far = 0;
  double squares = 0.0;
  SurfaceSupport support;
  /// Both directions in one figure, in points: the points left out, plus the unsupported area at
  /// the building's point density (`points_per_m2`): a square metre of surface no point asks for
  /// weighs as much as a square metre of points the model leaves out (the selection's E_u and E_d).
  double unfaithful(double points_per_m2) const;
  /// The sum of the squared distances, both ways: each square metre of unsupported surface counted as
  /// the points of a square metre lying kUnexplainedDistance off it.
  double squares_both_ways(double points_per_m2) const;
};

/// From the points to the model only (point_distances); `distances_out`, when given, receives each
/// point's distance. `support` stays empty.
ModelFit fit_of_points(const PolygonMesh& mesh, const std::vector<Point3>& points,
                       std::vector<double>* distances_out = nullptr);

/// Both ways: fit_of_points, and surface_support of the faces of `types` against `local_top`.
ModelFit fit_both_ways(const PolygonMesh& mesh, const std::vector<SurfaceType>& types,
                       const std::vector<Point3>& points, const LocalTop& local_top,
                       const SurfaceSupportParams& params, std::vector<double>* distances_out = nullptr);

}  // namespace city3d
