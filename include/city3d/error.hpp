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

/// A building could not be reconstructed at the requested level.
class ReconstructionError : public Error {
 public:
  using Error::Error;
};

}  // namespace city3d
