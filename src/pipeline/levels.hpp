// The report's figures of a building and the levels of detail made from its model: the heights of its
// points (describe_points), LoD1.2 and LoD1.3 derived from the LoD2.2 model with each level's volume
// and RMSE (add_levels_of_detail).
#pragma once

#include <optional>

#include "pipeline/rebuild.hpp"

namespace city3d::detail {

/// Heights, footprint area (`footprint_area`, of input.footprint.polygons) and point density of the
/// report (3DBAG's b3_h_* attributes).
void describe_points(const BuildingInput& input, const ReconstructionParams& params, double footprint_area,
                     BuildingReport& r);

/// LoD1.2 and LoD1.3 derived from the LoD2.2 model (or only the LoD1.2 block when the ladder ended
/// there), each valid as written; volumes and RMSE per level; the model OBJ/PLY get is the highest
/// level asked for. `lod2_fit`: the LoD2 model's distances to the points, when already measured.
void add_levels_of_detail(const BuildingInput& input, const ReconstructionParams& params,
                          const std::optional<ModelFit>& lod2_fit, BuildingResult& result);

/// The RMSE of the model the OBJ/PLY files hold (the highest level written), already measured for its
/// level's attribute.
double highest_level_rmse(const BuildingReport& r);

}  // namespace city3d::detail
