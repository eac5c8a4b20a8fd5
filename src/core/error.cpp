// The names of the reconstruction stages an error comes from (error.hpp).
#include "city3d/error.hpp"

namespace city3d {

void throw_if_invalid(const std::string& module, const std::string& problems) {
  if (!problems.empty()) throw ConfigError(module + ": invalid parameters:" + problems);
}

const char* stage_name(ReconstructionStage stage) {
  switch (stage) {
    case ReconstructionStage::footprint: return "footprint";
    case ReconstructionStage::planes: return "planes";
    case ReconstructionStage::heightmap: return "heightmap";
    case ReconstructionStage::polylines: return "polylines";
    case ReconstructionStage::walls: return "walls";
    case ReconstructionStage::hypothesis: return "hypothesis";
    case ReconstructionStage::selection: return "selection";
    case ReconstructionStage::model: return "model";
    case ReconstructionStage::lod1: return "lod1";
    case ReconstructionStage::lod13: return "lod1.3";
    case ReconstructionStage::evaluation: return "evaluation";
  }
  return "reconstruction";
}

}  // namespace city3d
