// Model output: OBJ and PLY (ascii or binary) with polygonal faces, one file per building or one file
// for many. Files are written atomically (temporary file, then rename).
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <variant>
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

/// Reads a polygonal model from an OBJ file (`v` and `f` lines; `f` entries may carry `/vt/vn`
/// parts and negative indices; every other line is ignored), world coordinates as written, origin 0.
/// For evaluating models made by other tools. Throws IoError naming the file and line on malformed
/// vertices or faces, and when the file holds no face.
BuildingModel read_obj_model(const std::string& path);

/// One geometry of a city object: a level of detail and its model.
struct CityGeometry {
  std::string lod = "2.2";  ///< CityJSON LoD string ("1.2", "1.3", "2.2")
  BuildingModel model;
};

/// A building as a CityJSON `Building`: its id, its geometries (one per level of detail) and its
/// attributes.
struct CityObject {
  BuildingId id;
  std::vector<CityGeometry> geometries;
  std::vector<std::pair<std::string, AttributeValue>> attributes;
};

/// The transform and metadata of a CityJSON file. One run writes buildings.city.json and
/// buildings.city.jsonl with the same options, so both carry the same transform.
struct CityJsonOptions {
  std::string crs;             ///< "EPSG:28992" (written as an OGC CRS URL), or empty when unknown
  double scale = 0.0001;       ///< transform scale in metres: 0.0001 keeps 0.1 mm, 0.001 millimetres
  Point3 translate;            ///< transform translation, metres; a whole number keeps the grid exact
  std::string reference_date;  ///< metadata referenceDate (YYYY-MM-DD), or empty
};

/// Classifies the faces of a model (its `surfaces` when given, else by normal: down-facing ground,
/// near-vertical wall, otherwise roof).
std::vector<SurfaceType> surface_types(const BuildingModel& model);

/// Writes one CityJSON 2.0 file holding every object as a `Building` with one `Solid` per level of
/// detail, with semantic surfaces (RoofSurface, WallSurface, GroundSurface); a level whose model
/// has several edge-connected parts gives one child `BuildingPart` "<id>-<lod>-<k>" per part
/// (CityJSON's Building has no MultiSolid, and a Solid has one exterior shell). Vertices are quantised with the
/// given transform and shared per building. Atomic write; throws IoError naming the path.
void write_cityjson(const std::string& path, const std::vector<CityObject>& objects, const CityJsonOptions& options);

/// Streams CityJSONSeq (CityJSON Text Sequences): a first line with the CityJSON header and
/// transform, then one CityJSONFeature line per building, written in the order add() is called.
/// The file appears under its final name only after close() (atomic).
class CityJsonSeqWriter {
 public:
  /// The header carries options' transform, which every feature line uses.
  CityJsonSeqWriter(const std::string& path, const CityJsonOptions& options);
  ~CityJsonSeqWriter();
  CityJsonSeqWriter(const CityJsonSeqWriter&) = delete;
  CityJsonSeqWriter& operator=(const CityJsonSeqWriter&) = delete;
  void add(const CityObject& object);
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace city3d
