// The batch job: run_batch() streams tiles, crops them by footprints, reconstructs buildings in
// parallel (pipeline.hpp) and writes models, CityJSON and a report in input order.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "city3d/crop.hpp"
#include "city3d/footprint_io.hpp"
#include "city3d/model_io.hpp"
#include "city3d/pipeline.hpp"
#include "city3d/run_outputs.hpp"

namespace city3d {

/// Everything run_batch() needs.
struct BatchOptions {
  std::vector<std::string> point_clouds;  ///< LAS/LAZ/PLY files, or folders of them
  std::string footprints;                 ///< footprint source; empty = single-building clouds
  FootprintReadOptions footprint;
  CropParams crop;
  ReconstructionParams reconstruction;
  std::optional<double> ground_z;         ///< single-building mode: floor height (world z)
  /// The CRS of the point clouds' coordinates and heights as the user states it (--crs): "EPSG:7415"
  /// (RD New + NAP height), "EPSG:28992+5709", WKT. Empty: the point clouds' CRS when they record
  /// one, else the footprints' (with a warning naming it). A CRS the point clouds record must agree
  /// with it in plan; footprints in another CRS are reprojected into its horizontal part.
  std::string crs;
  /// The options that describe the run's outputs, as a JSON object of option names (without "--")
  /// and values ({"lambda-data": 0.34, "lod": ["1.2", "1.3", "2.2"], ...}), written into the
  /// CityJSON metadata, run.json and report.html; empty: none. The command line fills it
  /// (run_parameters_json()): it leaves out what does not change the outputs (-j, -o, --shard, ...).
  std::string parameters;
  /// A building whose footprint has less of its area than this inside the tiles' extents
  /// (FootprintCoverage::area) is not ok but `partial`: the tiles given leave part of it out (a tile
  /// forgotten at a seam). Less of its cells with points (FootprintCoverage::cells) gives a note.
  /// 0: never. 0.95 flags the six of Delft's seam footprints that tile 1 alone cuts by more than
  /// 1% of their area (their shares: 0.919, 0.726, 0.460, 0.308, 0.138, 0.041; the seventh 0.999).
  double min_coverage = 0.95;
  /// A building whose own points lie in less than this share of its footprint's cells with points
  /// (FootprintCoverage::building) is `partial` too: the rest of the footprint holds other classes only,
  /// so the model spans ground the building's points never reached (a tile whose buildings are not
  /// classified beside one whose are; a footprint far larger than the building in the points). Less
  /// than min_coverage gives a note. 0: never. Delft's 160 footprints: 0.625 at the least (a
  /// footprint of 8 cells), then 0.781 (b31bc2699, whose low part is classified otherwise).
  double min_building_coverage = 0.5;
  /// A --ground-field value more than this many metres below the ground measured from the points around
  /// the footprint is not taken (heights of another datum, or a field of other numbers, e.g. a level
  /// code): the measured ground stays, and the note says so. A value above half of the building's
  /// points is never taken.
  double ground_field_max_below = 10.0;
  /// A --ground-field value taken that lies more than this many metres above or below the ground
  /// measured around the footprint gets a note saying by how much (a field of another datum, or a
  /// relative level: the floor then stands in the air or under the terrain).
  double ground_field_note_distance = 2.0;

  std::string output_dir = "city3d_out";
  MeshFormat format = MeshFormat::obj;
  bool local_coordinates = false;
  bool per_building_files = true;   ///< models/<id>.<ext>
  bool merged_file = false;         ///< models.<ext> with every building
  bool cityjson = true;             ///< buildings.city.json
  bool cityjson_seq = false;        ///< buildings.city.jsonl
  bool gpkg = false;                ///< buildings.gpkg (footprints with the report; each level's roof parts and solids)
  /// 3dtiles/: a 3D Tiles 1.1 tileset (tileset.json, binary glTF content with EXT_mesh_features and
  /// EXT_structural_metadata), LoD1.2 far and LoD2.2 near, placed on the globe from the run's CRS.
  bool tiles3d = false;
  bool html = true;                 ///< report.html, the run overview
  bool timings_in_cityjson = false; ///< add "seconds" to CityJSON attributes (breaks byte-identity)
  int threads = 1;
  /// Footprints are grouped into square blocks of this size (metres, by their bounding-box
  /// centres): the units shards are made of, and which cropping passes group (group_area). 0 =
  /// everything in one block. The output does not depend on it.
  double block_size = 1000.0;
  /// Consecutive blocks in the order of their home tiles (the tile holding a block's centre) are
  /// cropped together, one stream of their tiles, up to this much footprint area (m2; a block larger
  /// than that alone), so that a tile is not streamed once per block. Memory follows this area (about 0.6 KB per m2 at
  /// AHN3 density: 250,000 m2, 4,600 buildings of Delft's centre, peaked at 272 MB with 2 threads).
  /// 0 = one block per pass. The output does not depend on it.
  double group_area = 250000.0;
  bool progress = false;            ///< progress line on stderr
  /// Skip buildings a previous run with the same inputs and parameters finished (resume.journal in
  /// the output folder); false recomputes everything.
  bool resume = true;
  /// Do only shard `shard` of `shards` (1-based) into output_dir, for merge_shards() to combine:
  /// the blocks (of block_size; for single-building clouds, the clouds) in the order of their home
  /// tiles are cut into `shards` consecutive runs of about equal footprint area (cloud file size),
  /// so every shard computes the same split from the inputs alone. 0 / 0: the whole run.
  int shard = 0;
  int shards = 0;
};

/// Runs the whole job (or one shard of it). Throws IoError / ConfigError only when the run itself
/// cannot go on (unreadable footprints or point clouds, unwritable output); a bad building never
/// stops it. A shard's folder holds its models, journal, report and, once it is finished, run.json.
BatchSummary run_batch(const BatchOptions& options);

/// What merge_shards() needs.
struct MergeOptions {
  std::vector<std::string> shard_dirs;  ///< output folders of `reconstruct --shard K/N` runs
  std::string output_dir;               ///< where the merged outputs go
  int threads = 1;  ///< threads reading the records back (the outputs do not depend on it)
};

/// Combines the folders of every shard of one run into the outputs one process would have written
/// (byte-identical CityJSON, CityJSONSeq, models and models.<ext>, and buildings.gpkg when the run
/// asked for it; report.csv, report.json and report.html differ only in their timings). Throws Error naming the folder when a shard is missing, incomplete (no run.json) or of
/// other inputs or parameters, or a record or model file is damaged.
BatchSummary merge_shards(const MergeOptions& options);

}  // namespace city3d
