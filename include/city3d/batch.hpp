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

namespace city3d {

/// Everything run_batch() needs.
struct BatchOptions {
  std::vector<std::string> point_clouds;  ///< LAS/LAZ/PLY files, or folders of them
  std::string footprints;                 ///< footprint source; empty = single-building clouds
  FootprintReadOptions footprint;
  CropParams crop;
  ReconstructionParams reconstruction;
  std::optional<double> ground_z;         ///< single-building mode: floor height (world z)

  std::string output_dir = "city3d_out";
  MeshFormat format = MeshFormat::obj;
  bool local_coordinates = false;
  bool per_building_files = true;   ///< models/<id>.<ext>
  bool merged_file = false;         ///< models.<ext> with every building
  bool cityjson = true;             ///< buildings.city.json
  bool cityjson_seq = false;        ///< buildings.city.jsonl
  bool gpkg = false;                ///< buildings.gpkg (footprints with the report, LoD2.2 roof parts)
  bool html = true;                 ///< report.html, the run overview
  bool timings_in_cityjson = false; ///< add "seconds" to CityJSON attributes (breaks byte-identity)
  int threads = 1;
  /// Footprints are cropped and reconstructed in square blocks of this size (metres, by their
  /// bounding-box centres), so memory follows one block's points, not the whole footprint set; the
  /// tiles overlapping a block are streamed once per block. 0 = everything in one block. The output
  /// does not depend on it.
  double block_size = 1000.0;
  bool progress = false;            ///< progress line on stderr
  /// Skip buildings a previous run with the same inputs and parameters finished (resume.journal in
  /// the output folder); false recomputes everything.
  bool resume = true;
};

/// Counts of one batch run.
struct BatchSummary {
  std::size_t buildings = 0, ok = 0, fallback = 0, skipped = 0, failed = 0;
  double seconds = 0.0;
  std::string report_path;
};

/// Runs the whole job. Throws IoError / ConfigError only when the run itself cannot go on
/// (unreadable footprints or point clouds, unwritable output); a bad building never stops it.
BatchSummary run_batch(const BatchOptions& options);

}  // namespace city3d
