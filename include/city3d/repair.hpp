// Repair of a reconstructed model as the writers will write it: rounded to the output grid, validated
// under val3dity's rules (evaluation.hpp), and when that fails, repaired by the mildest change that
// passes them.
#pragma once

#include <string>
#include <vector>

#include "city3d/evaluation.hpp"
#include "city3d/types.hpp"

namespace city3d {

/// Rounds every vertex of `model` to the output grid as the writers write it (world coordinate =
/// local + origin, rounded to a multiple of `grid` metres), merges vertices that become equal, drops
/// repeated consecutive vertices and faces left with fewer than three, and drops unused vertices.
/// `model.surfaces` follows the faces. grid <= 0 leaves the coordinates as they are.
void round_to_grid(BuildingModel& model, double grid);

/// What validate_as_written() found and did.
struct WrittenValidity {
  std::vector<ValidityError> found;      ///< errors of the model as rounded, before any repair
  std::vector<ValidityError> remaining;  ///< errors left (of the model as rounded when the repair failed)
  std::string repairs;                   ///< what was repaired ("removed 2 spikes; split 1 face"), or empty
};

/// Makes `model` what the writers will write (round_to_grid), validates it part by part
/// (validate_model), and when that fails tries three repairs, mildest first, each followed by the grid
/// rounding and the check; the first that leaves a valid model is kept: (1) faces that are not planar
/// as rounded (203, 204) or not simple are split into triangles of their own vertices; (2) vertices
/// within the snap tolerance become one (102), then (1); (3) zero-width spikes are cut off (104),
/// then (1). The model is changed in place; when no repair works it stays as rounded.
WrittenValidity validate_as_written(BuildingModel& model, double grid, const ValidityParams& params = {});

}  // namespace city3d
