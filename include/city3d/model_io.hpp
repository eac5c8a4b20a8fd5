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

/// A file name for a building id: the id itself when it is made of [A-Za-z0-9._-] and does not
/// start with '.'; otherwise the id with every other character made '_' (and '_' put before a
/// leading '.' or an empty id), cut to 200 bytes when longer, then '-' and 8 hex digits of the id's
/// 32-bit FNV-1a hash, so that distinct ids never share a file name ("a b" and "a_b").
std::string model_file_name(const BuildingId& id, MeshFormat format);

/// The material library every OBJ model names (`mtllib`), in the folder of the OBJ files: one
/// material per semantic surface (GroundSurface, WallSurface, RoofSurface), which write_surface_materials() writes.
constexpr const char* kSurfaceMaterialFile = "city3d.mtl";

/// Writes the material library of the OBJ models (kSurfaceMaterialFile) to `path`: grey ground,
/// off-white walls, red roofs. Throws IoError naming the path.
void write_surface_materials(const std::string& path);

/// Writes one building to `path` (OBJ: its faces grouped by semantic surface, `g` and `usemtl`
/// GroundSurface, WallSurface, RoofSurface, with `mtllib city3d.mtl`). Throws IoError naming the path
/// when it cannot be written.
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

/// The scale and metadata of a CityJSON file (the translation is given with each call: one run
/// writes buildings.city.json and buildings.city.jsonl with the same transform).
struct CityJsonOptions {
  /// "EPSG:7415" or "EPSG:28992" (written as an OGC CRS URL; "EPSG:h+v", a compound without a code
  /// of its own, as OGC's crs-compound URL of its two parts), or empty when unknown
  std::string crs;
  double scale = 0.0001;       ///< transform scale in metres: 0.0001 keeps 0.1 mm, 0.001 millimetres
  std::string reference_date;  ///< metadata referenceDate (YYYY-MM-DD), or empty
  /// The metadata member "city3d", a JSON object as text ({"version": "0.1.0", "parameters": {...}}),
  /// written as given; empty: none.
  std::string city3d;
};

/// Classifies the faces of a model (its `surfaces` when given, else by normal: down-facing ground,
/// near-vertical wall, otherwise roof).
std::vector<SurfaceType> surface_types(const BuildingModel& model);

/// Writes one CityJSON 2.0 file holding every object as a `Building` with one `Solid` per level of
/// detail, with semantic surfaces (RoofSurface, WallSurface, GroundSurface); a level whose model
/// has several edge-connected parts gives one child `BuildingPart` "<id>-<lod>-<k>" per part
/// (CityJSON's Building has no MultiSolid, and a Solid has one exterior shell). The translation is
/// the minimum corner of all vertices, in whole metres. Vertices are quantised with the
/// given transform and shared per building. The metadata holds the CRS, the geographicalExtent of
/// the vertices as written (none without vertices) and `options.city3d`. Atomic write; throws
/// IoError naming the path.
void write_cityjson(const std::string& path, const std::vector<CityObject>& objects, const CityJsonOptions& options);

/// The same with the transform's translation given (a whole number of metres keeps the grid exact).
void write_cityjson(const std::string& path, const std::vector<CityObject>& objects, const CityJsonOptions& options,
                    const Point3& translate);

/// Streams CityJSONSeq (CityJSON Text Sequences): a first line with the CityJSON header and
/// transform (its metadata's geographicalExtent that of every feature's vertices), then one
/// CityJSONFeature line per building, written in the order add() is called. The features are
/// spooled to a temporary file until close() knows the extent. The file appears under its final name
/// only after close() (atomic).
class CityJsonSeqWriter {
 public:
  /// `translate` is the transform's translation for the whole file (e.g. the footprints' minimum corner).
  CityJsonSeqWriter(const std::string& path, const CityJsonOptions& options, const Point3& translate);
  ~CityJsonSeqWriter();
  CityJsonSeqWriter(const CityJsonSeqWriter&) = delete;
  CityJsonSeqWriter& operator=(const CityJsonSeqWriter&) = delete;
  void add(const CityObject& object);
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The CityJSONFeature text of one object (one line of CityJSONSeq, without its newline), its
/// vertices quantised with `options.scale` and `translate`. Throws IoError when the scale is invalid.
std::string cityjson_feature(const CityObject& object, const CityJsonOptions& options, const Point3& translate);

/// The first line of a CityJSONSeq file (without its newline): the CityJSON header with the
/// transform, and the geographicalExtent of `extent` (quantised vertices, as features hold them)
/// when given.
std::string cityjson_seq_header(const CityJsonOptions& options, const Point3& translate,
                                const Box3* extent = nullptr);

/// CityJSONSeq from CityJSONFeature texts (as cityjson_feature() makes them, with the same options
/// and translate), in the order add() is called: the header line, then each feature as given. The
/// features are spooled to a temporary file until close(), which writes the header with their
/// geographicalExtent. The file appears under its final name only after close() (atomic). Throws
/// IoError naming the feature's position when a text is not a CityJSONFeature.
class CityJsonSeqAssembler {
 public:
  CityJsonSeqAssembler(const std::string& path, const CityJsonOptions& options, const Point3& translate);
  ~CityJsonSeqAssembler();
  CityJsonSeqAssembler(const CityJsonSeqAssembler&) = delete;
  CityJsonSeqAssembler& operator=(const CityJsonSeqAssembler&) = delete;
  void add(const std::string& feature);
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Builds one CityJSON file from CityJSONFeature texts (as cityjson_feature() makes them, with the
/// same options and translate), in the order add() is called: every feature's CityObjects members
/// are copied byte for byte, its vertices appended to the file's vertex list and its vertex indices
/// moved accordingly. The result equals write_cityjson() of the same objects with that transform,
/// and holds whatever the features hold. Memory stays small (objects and vertices are spooled to
/// temporary files until close() writes the header with their geographicalExtent). The file appears under its final name only after close() (atomic). Throws IoError naming
/// the path, or the feature's position when a text is not a CityJSONFeature.
class CityJsonAssembler {
 public:
  CityJsonAssembler(const std::string& path, const CityJsonOptions& options, const Point3& translate);
  ~CityJsonAssembler();
  CityJsonAssembler(const CityJsonAssembler&) = delete;
  CityJsonAssembler& operator=(const CityJsonAssembler&) = delete;
  void add(const std::string& feature);
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace city3d
