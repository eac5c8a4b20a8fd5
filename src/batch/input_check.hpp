// Checks of a run's inputs taken together, before anything is read in full or written: the same
// tile given twice, point clouds in different or unusable CRSs, footprints that meet no tile.
#pragma once

#include <string>
#include <vector>

#include "city3d/crop.hpp"
#include "city3d/footprint_io.hpp"
#include "city3d/point_cloud_io.hpp"

namespace city3d::detail {

/// What distinct_inputs() drops.
enum class Repeats {
  /// Tiles (with footprints): the same file under another name, a copy of its bytes, and a twin
  /// holding the same points in another encoding (a LAS file and its LAZ): reading a tile twice
  /// would double the points of every building on it.
  tiles,
  /// Single-building clouds: only the same file under another name. Each file is a building, so a
  /// copy is a building of its own (with a warning: it is seldom meant).
  clouds,
};

/// A coordinate as messages give it: millimetres for metres, about 0.1 m for degrees.
std::string fixed(double v);

/// `files` without repeats, first occurrence kept, in order. The same file is one under another
/// name (a second mention, a folder holding a file also given alone, a symbolic or hard link); a
/// copy has the same size and the same first and last 64 KiB; a twin is a LAS or LAZ file with the
/// same header facts (point count, format, record length, scale, offset; bounds within half a scale
/// step) and the same first and last kTwinRecords point records, decompressed. Each dropped file gets a warning naming both.
std::vector<std::string> distinct_inputs(const std::vector<std::string>& files, Repeats repeats = Repeats::tiles);

/// Point records compared at each end of two LAS/LAZ files with the same header facts.
constexpr std::size_t kTwinRecords = 64;

/// The CRS the point clouds share ("EPSG:n" or WKT as the files record it), or empty when none of
/// them records one. Throws IoError when two files record different CRSs, or when the CRS is
/// geographic (degrees, where city3d needs metres).
std::string common_point_cloud_crs(const std::vector<std::string>& files, const std::vector<PointCloudInfo>& infos);

/// What city3d needs to know of a coordinate reference system.
struct CrsFacts {
  /// "EPSG:7415" when PROJ's database knows it by a code (a compound given as "EPSG:28992+5709" is
  /// EPSG:7415); "EPSG:28992+5709" for a compound of two codes with none of its own; empty when no
  /// EPSG code identifies it.
  std::string name;
  std::string title;       ///< "Amersfoort / RD New + NAP height"
  std::string horizontal;  ///< the horizontal part: "EPSG:28992", or WKT
  bool vertical = false;   ///< it states the heights' vertical datum (a compound CRS)
  bool geographic = false; ///< its horizontal part is in degrees
  /// Metres per unit of its (projected) plan coordinates, and the unit's name: 0.3048006 "US survey
  /// foot" for EPSG:2263; 1 "metre" for most.
  double unit_metres = 1.0;
  std::string unit;
};

/// The facts of a CRS given as "EPSG:n", "EPSG:h+v", WKT or PROJ text. Throws ConfigError naming
/// `text` when OGR/PROJ cannot understand it.
CrsFacts crs_facts(const std::string& text);

/// The run's CRS and where it came from.
struct RunCrs {
  std::string name;    ///< as CrsFacts::name ("EPSG:7415"), else the CRS as recorded (WKT); empty without one
  std::string source;  ///< "--crs", "point clouds", "footprints", or empty
};

/// The run's CRS: `given` (--crs) when set, else the point clouds' (`points_crs`), else the
/// footprints' (`footprints_srs`, of the source `footprints_path`), with a warning naming it, as the
/// heights then have no stated reference. Says at -v which it is and whether its heights have a
/// vertical datum. Throws IoError when `given` disagrees in plan with what the point clouds record,
/// ConfigError when it is geographic.
RunCrs resolve_run_crs(const std::string& given, const std::string& points_crs, const std::string& footprints_srs,
                       const std::string& footprints_path);

/// Throws IoError when none of the footprints' bounding boxes `boxes` (those `footprints` kept, in
/// the points' CRS) meets any point cloud's header bounds (the usual sign of footprints and points
/// in different CRSs), naming both extents and CRSs. Does nothing when there are no footprints or
/// some cloud's bounds are unknown (PLY).
void check_footprints_meet_points(const std::vector<Box2>& boxes, const FootprintSet& footprints,
                                  const std::vector<PointCloudInfo>& infos, const std::string& points_crs);

/// Throws ConfigError when a folder of point clouds (`point_clouds`) is the output folder (a later
/// run would read the models written there as points), or when an input file (a point cloud, the
/// `footprints`) stands where the run writes: named as a run-level output in the output folder
/// (buildings.gpkg, ...) or in its models/. Throws IoError when `output_dir` holds files
/// of the names a run writes (report.csv, run.json, models/, ...) but no resume.journal: no run is
/// resumed there, and a run would replace them unasked (a user's own files, or a run's whose
/// journal was deleted).
void check_output_folder(const std::vector<std::string>& point_clouds, const std::string& footprints,
                         const std::string& output_dir);

/// A warning for each input that is a mesh (a PLY with faces, such as a model) rather than a cloud.
void warn_of_meshes(const std::vector<PointCloudInfo>& infos);

/// A single-building cloud's points, and a note when more than a tenth of them are classified
/// ground (LAS class 2): a tile given without its footprints, whose ground would be modelled as a roof;
/// or when its x and y look like degrees (a span under 0.01 within -180..180 and -90..90).
struct CloudPoints {
  std::vector<Point3> points;
  std::string note;
};
CloudPoints read_building_cloud(const std::string& path, double max_extent);

/// One warning per LAS file with whole records after its counted points that nothing else in the file
/// claims (PointCloudInfo::uncounted_records): they are not read. One per LAS file whose x or y scale
/// is coarser than 5 cm (a scale of 1: a roof cannot be read from whole metres).
void warn_of_uncounted_records(const std::vector<PointCloudInfo>& infos);

/// Each input's ground from its footprint's ground field (Footprint::ground_z, read with
/// --ground-field `field`), unless that stands above half of the building's points, or more than
/// `max_below` metres below the ground measured from the points around it (another field than a
/// height, or heights in another datum): then the ground measured from the points stays, a note says
/// why, and one warning counts them. A value taken more than `note_distance` metres above or below the
/// ground measured around the footprint gets a note saying by how much, and one warning counts those.
void take_ground_fields(std::vector<BuildingInput>& inputs, const std::string& field, double max_below,
                        double note_distance);

}  // namespace city3d::detail
