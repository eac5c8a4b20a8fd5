// Model output: OBJ and PLY (ascii or binary) with polygonal faces, one file per building or one file
// for many. Files are written atomically (temporary file, then rename).
#pragma once

#include <string>
#include <vector>

#include "city3d/types.hpp"

namespace city3d {

enum class MeshFormat { obj, ply_ascii, ply_binary };

struct ModelWriteOptions {
  MeshFormat format = MeshFormat::obj;
  /// false: world coordinates (local + origin) written with millimetre-safe precision.
  /// true: local coordinates, with the origin recorded in the file's header comments.
  bool local_coordinates = false;
};

/// Parses "obj", "ply" (binary) or "ply-ascii"; throws ConfigError otherwise.
MeshFormat parse_mesh_format(const std::string& name);

/// The file extension for a format, with the dot (".obj", ".ply").
std::string mesh_extension(MeshFormat format);

/// A file name for a building id: characters outside [A-Za-z0-9._-] become '_'; never empty.
std::string model_file_name(const BuildingId& id, MeshFormat format);

/// Writes one building to `path`. Throws IoError naming the path when it cannot be written.
void write_model(const std::string& path, const BuildingModel& model, const ModelWriteOptions& options);

/// Writes many buildings into one file: OBJ with one `o <id>` group per building; PLY with a
/// per-face `building` index and one `comment building <index> <id>` line per building.
void write_models(const std::string& path, const std::vector<BuildingModel>& models,
                  const ModelWriteOptions& options);

}  // namespace city3d
