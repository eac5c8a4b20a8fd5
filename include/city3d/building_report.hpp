// The per-building report: what happened to one input footprint (or single-building cloud), the
// model's figures and its 3DBAG-style attributes. Filled by the pipeline and the batch run, written
// by the reports (CSV, JSON, GeoPackage, HTML) and kept in the resume journal.
#pragma once

#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "city3d/types.hpp"

namespace city3d {

/// What happened to one input footprint (or single-building cloud).
enum class BuildingStatus {
  ok,        ///< reconstructed at the requested level
  fallback,  ///< reconstructed at a lower rung of the ladder (see reason)
  skipped,   ///< not reconstructed: nothing to reconstruct (invalid footprint, no points)
  failed,    ///< every rung failed (see stage and reason)
  /// reconstructed (at any rung) from points that cover too little of its footprint: the tiles
  /// given leave part of it out (BuildingReport::coverage, the run's min_coverage); see reason
  partial,
};

/// The rung of the fallback ladder a model comes from.
enum class ModelLevel {
  none,
  lod22,                  ///< full LoD2: inferred walls, roof planes, face selection
  lod22_footprint_walls,  ///< LoD2 with footprint walls only
  lod12,                  ///< LoD1 block: footprint extruded to a robust roof height
};

const char* status_name(BuildingStatus status);
const char* level_name(ModelLevel level);
/// The status or level a name gives (status_name(), level_name()); nothing for another text.
std::optional<BuildingStatus> status_from_name(const std::string& name);
std::optional<ModelLevel> level_from_name(const std::string& name);
/// CityJSON LoD string of a level ("2.2", "1.2"; empty for none).
const char* cityjson_lod(ModelLevel level);

/// What the rebuilds of a LoD2 model did (explain_more, src/pipeline/rebuild.hpp): why they ran, which
/// variant replaced the model, and how faithful the model was before and after, both ways. The
/// report's note says the same in words; these fields are for programs and tests.
struct RebuildOutcome {
  enum class Result {
    none,       ///< not asked for: the model explained its points and carried no unsupported surface
    too_large,  ///< not rebuilt: its hypothesis had more candidate faces than the rebuilds' work limit
    rebuilt,    ///< a variant replaced the model
    no_better,  ///< no variant was more faithful and closer both ways: the model was kept
  };
  /// A variant: of the hypothesis (the first three) and of the selection (the last two).
  struct Variant {
    bool smaller_planes = false;   ///< roof planes of half min_points
    bool wide_outline = false;     ///< without a footprint, an outline closing wider gaps
    bool left_out = false;         ///< roofs for the points left out
    bool without_prior = false;    ///< the selection without the face prior
    bool half_complexity = false;  ///< the selection with half the complexity weight
  };
  Result result = Result::none;
  bool unexplained = false;  ///< asked for by the points left out (more than retry_unexplained_share)
  bool unsupported = false;  ///< asked for by the surface no point supports (more than retry_unsupported_area)
  Variant variant;           ///< the variant kept (result rebuilt)
  std::size_t far_before = 0, far_after = 0;                 ///< points farther than kUnexplainedDistance
  double unsupported_before = 0.0, unsupported_after = 0.0;  ///< m2 of surface no point supports
  /// Variants of the hypothesis not selected over: more candidate faces than the work limit (their count).
  std::vector<std::pair<Variant, std::size_t>> over_limit;
  bool stopped = false;  ///< the opt-in time limit stopped the rebuilds before every variant was tried
};

/// One row of the report.
struct BuildingReport {
  BuildingId id;
  BuildingStatus status = BuildingStatus::failed;
  ModelLevel level = ModelLevel::none;
  std::string stage;   ///< stage of the last failure ("crop", "planes", ..., "lod1"), empty when ok
  std::string reason;  ///< why it fell back, was skipped or failed; empty when ok
  std::string note;    ///< anything else worth knowing, e.g. the footprint was repaired
  std::size_t points = 0;
  std::size_t ground_points = 0;
  double ground_z = 0.0;  ///< world z of the floor
  std::string ground_method;
  double roof_z = 0.0;    ///< world z of the LoD1 roof (70th percentile by default)
  std::size_t planes = 0;
  std::size_t walls = 0;
  std::size_t candidate_faces = 0;
  std::size_t faces = 0;
  double rmse = -1.0;     ///< metres, points to model; -1 when there is no model or no points
  bool valid = false;     ///< the written model passes every val3dity rule (validate_as_written)
  /// val3dity codes of the models the ladder built, as rounded, before repair ("104,204"), with the
  /// rung they came from ("LoD2.2: 204"); empty when every model built was valid as it came.
  std::string validity_found;
  std::string repairs;    ///< what was repaired to make the written model valid, or empty
  double seconds = 0.0;      ///< wall clock of reconstruct_building()
  /// CPU time of reconstruct_building(): its thread's, plus the solver processes it started. Unlike
  /// the wall clock it does not grow when other work shares the machine.
  double cpu_seconds = 0.0;

  // 3DBAG-style attributes (see README, "Attributes"); world heights in metres, NaN when unknown.
  std::string lods;                 ///< levels written, e.g. "1.2,1.3,2.2"
  std::string lods_reconstructed;   ///< levels that are reconstructions of this building's points
  double footprint_area = 0.0;      ///< square metres, plan view
  double point_density = 0.0;       ///< building points per square metre of footprint
  /// Share (0-1) of the footprint's area inside the tiles' extents, of its cells holding a point of
  /// any class, and of those cells holding one of its building points (FootprintCoverage, crop.hpp);
  /// NaN for single-building clouds and for footprints skipped as they were read. Set by the batch
  /// run, which knows the tiles.
  double coverage = std::numeric_limits<double>::quiet_NaN();
  double point_coverage = std::numeric_limits<double>::quiet_NaN();
  double building_coverage = std::numeric_limits<double>::quiet_NaN();
  double h_roof_50p = std::numeric_limits<double>::quiet_NaN();  ///< median z of the building points
  double h_roof_70p = std::numeric_limits<double>::quiet_NaN();  ///< 70th percentile (LoD1.2 roof)
  double h_roof_min = std::numeric_limits<double>::quiet_NaN();
  double h_roof_max = std::numeric_limits<double>::quiet_NaN();
  double h_ridge = std::numeric_limits<double>::quiet_NaN();     ///< highest LoD2.2 roof vertex
  std::string roof_type;            ///< "horizontal", "multiple horizontal", "slanted", "no points", "could not be detected"
  double volume_lod12 = std::numeric_limits<double>::quiet_NaN();  ///< cubic metres
  double volume_lod13 = std::numeric_limits<double>::quiet_NaN();
  double volume_lod22 = std::numeric_limits<double>::quiet_NaN();
  double rmse_lod12 = std::numeric_limits<double>::quiet_NaN();    ///< metres, points to the model
  double rmse_lod13 = std::numeric_limits<double>::quiet_NaN();
  double rmse_lod22 = std::numeric_limits<double>::quiet_NaN();
  /// Building points farther than kUnexplainedDistance from the model written (parts of the
  /// building the model leaves out, or stray points), count and share of all points; NaN without a
  /// model.
  double unexplained_points = std::numeric_limits<double>::quiet_NaN();
  double unexplained_share = std::numeric_limits<double>::quiet_NaN();
  /// The same question the other way (surface_support.hpp), of the model written: square metres of
  /// its surface more than 1 m above the highest building point within 1.5 m in plan, and the largest
  /// height of its surface above that point, metres; NaN without a model.
  double unsupported_area = std::numeric_limits<double>::quiet_NaN();
  double height_excess = std::numeric_limits<double>::quiet_NaN();
  /// The rebuilds of the LoD2 model written (none for a LoD1 block).
  RebuildOutcome rebuild;
};

/// Adds `note` to the report's notes ("; " between them) unless it is there already (a rung can run
/// twice).
void add_note(BuildingReport& report, const std::string& note);

/// A point farther than this from its building's model is "unexplained" (BuildingReport), metres:
/// well beyond the noise of airborne LiDAR roofs (a few cm) and the misfit of a roof plane over a
/// slightly bent roof (tens of cm), so what it counts is structure the model does not have.
constexpr double kUnexplainedDistance = 1.0;

}  // namespace city3d
