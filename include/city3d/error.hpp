// The error hierarchy: every message names the module, the item (file, building, field) and the problem.
#pragma once

#include <stdexcept>
#include <string>

namespace city3d {

/// Base of every error city3d throws on purpose.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A file could not be read or written, or its content is malformed.
class IoError : public Error {
 public:
  using Error::Error;
};

/// Options or parameters are invalid (unknown flag, out-of-range value).
class ConfigError : public Error {
 public:
  using Error::Error;
};

/// Throws ConfigError "<module>: invalid parameters:<problems>" when `problems` (each "<name> must be
/// ...;", a space before each) is not empty: the end of a parameter struct's validate().
void throw_if_invalid(const std::string& module, const std::string& problems);

/// The stage of a building's reconstruction an error comes from, as the report's `stage` column names it
/// (stage_name()).
enum class ReconstructionStage {
  footprint,   ///< "footprint": the footprint's simplification
  planes,      ///< "planes": roof planes
  heightmap,   ///< "heightmap": the TIN heightmap and the inferred outline
  polylines,   ///< "polylines"
  walls,       ///< "walls": the vertical planes, and an outline that cannot be inferred
  hypothesis,  ///< "hypothesis": the candidate faces
  selection,   ///< "selection": the integer program
  model,       ///< "model": the assembled faces, a model not valid as written
  lod1,        ///< "lod1": the LoD1.2 block
  lod13,       ///< "lod1.3": the LoD1.3 blocks
  evaluation,  ///< "evaluation": a measure of the model
};

/// "planes", "lod1.3", ...
const char* stage_name(ReconstructionStage stage);

/// A building could not be reconstructed at the requested level: what() is "<stage>: <message>".
class ReconstructionError : public Error {
 public:
  ReconstructionError(ReconstructionStage stage, const std::string& message)
      : Error(std::string(stage_name(stage)) + ": " + message), stage_(stage) {}
  ReconstructionStage stage() const { return stage_; }

 private:
  ReconstructionStage stage_;
};

}  // namespace city3d
