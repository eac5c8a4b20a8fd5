// Point-cloud input: LAS 1.0-1.4 (point formats 0-10), PLY (ascii, binary little/big endian), LAZ
// recognised. Everything lands in one PointCloud type with double world coordinates. Files can be
// streamed chunk by chunk, reading only the attributes the caller asks for.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "city3d/point_cloud.hpp"
#include "city3d/types.hpp"

namespace city3d {

/// What a point-cloud file holds, from its header (no points read).
struct PointCloudInfo {
  std::string path;
  std::string format;            ///< "LAS", "LAZ" or "PLY"
  std::string version;           ///< LAS "1.2"; PLY "ascii", "binary_little_endian", "binary_big_endian"
  int point_format = -1;         ///< LAS point data format id (0-10) without the compression bits; -1 for PLY
  std::uint16_t record_length = 0;  ///< LAS point record length in bytes; 0 for PLY
  std::uint64_t point_count = 0;
  bool compressed = false;       ///< LAZ (compression bit or LASzip VLR)
  Box3 bounds;                   ///< header bounds for LAS; empty for PLY until the points are read
  std::array<double, 3> scale{1.0, 1.0, 1.0};
  std::array<double, 3> offset{0.0, 0.0, 0.0};
  std::string crs;               ///< WKT from the file (LAS WKT VLR), "EPSG:n" from GeoTIFF keys, or empty
  std::string generating_software;
  PointFields fields = kFieldXyz;  ///< attributes the file can provide
  std::vector<std::string> vlrs;   ///< "user_id/record_id (n bytes)" of each VLR and EVLR, for `info`
  std::uint64_t mesh_faces = 0;  ///< PLY: items of its 'face' element (a mesh, such as a model, not a cloud)
  /// PLY: x or y a 32-bit float, whose steps grow with the coordinates (0.5 m at 5.8e6: UTM northings).
  bool single_precision_xy = false;
  /// LAS: whole point records' worth of bytes after the counted points that neither waveform packets
  /// nor EVLRs claim (a header whose count was not rewritten when points were added); not read.
  std::uint64_t uncounted_records = 0;
};

/// A streaming reader over one file. Open with open_point_cloud(); call read() until it returns 0.
class PointCloudReader {
 public:
  virtual ~PointCloudReader() = default;
  /// Header facts, available right after opening.
  virtual const PointCloudInfo& info() const = 0;
  /// Appends at most `max_points` points (with the requested attributes) to `out` and returns how
  /// many it appended; 0 means the end of the file. Throws IoError on truncated or invalid data
  /// (message names the file and the point index).
  virtual std::size_t read(PointCloud& out, std::size_t max_points) = 0;
  /// LAS/LAZ records flagged withheld that read() has left out so far: the LAS specification has
  /// readers treat them as deleted. 0 for formats without the flag (PLY).
  virtual std::uint64_t withheld_points() const { return 0; }
};

/// Opens a LAS or PLY file (chosen by its signature, not its extension) and validates its header.
/// `fields` says which attributes read() fills. Throws IoError naming the file and the problem
/// (missing, empty, truncated, wrong signature, bad header fields, LAZ not supported yet, ...).
std::unique_ptr<PointCloudReader> open_point_cloud(const std::string& path,
                                                   PointFields fields = kFieldAll);

/// Reads a whole file into memory. Throws IoError as open_point_cloud() and read() do.
PointCloud read_point_cloud(const std::string& path, PointFields fields = kFieldAll);

/// As open_point_cloud(path, fields), with a LAZ file of several chunks decoded on `decode_threads`
/// threads (the chunks after the one being read are decoded ahead, at most `decode_threads` of them
/// held in memory). The points, their order and the errors are the same as with one thread (before
/// an error, the number of good points already handed out may differ); 0 and 1
/// both mean "decode in the calling thread". LAS and PLY files ignore it.
std::unique_ptr<PointCloudReader> open_point_cloud(const std::string& path, PointFields fields,
                                                   unsigned decode_threads);

/// Where the chunks of a LAZ file lie, learnt by one read of the whole file for later reads of parts
/// of it (a batch crops a large tile in several passes, each needing the points of a few regions).
struct ChunkExtents {
  std::vector<Box2> boxes;  ///< the xy bounds of each chunk's points, in file order; empty until learnt
};

/// As open_point_cloud(path, fields, decode_threads), for a reader that needs only the points within
/// `regions`. While `extents` is empty, every point is read and a read to the end of a LAZ file of
/// several chunks fills `extents`. Once it is filled (by a read of this same file: bounds of another
/// chunk count are ignored and the file is read whole), only the chunks whose bounds meet one of
/// `regions` are decoded: read() hands out their points, in file order, and none of the others'.
/// LAS, PLY and single-chunk LAZ files are read whole and leave `extents` empty, and so are LAZ files
/// whose chunks are too large to hold one decoded (over 256 MB) or whose coordinates may overflow.
std::unique_ptr<PointCloudReader> open_point_cloud(const std::string& path, PointFields fields,
                                                   unsigned decode_threads, ChunkExtents& extents,
                                                   const std::vector<Box2>& regions);

/// As read_point_cloud(path, fields), decoding LAZ on `decode_threads` threads (see above).
PointCloud read_point_cloud(const std::string& path, PointFields fields, unsigned decode_threads);

/// The LAS, LAZ and PLY files of a folder (by extension, any case), sorted by name; not those of
/// its subfolders. Throws IoError when the folder cannot be listed.
std::vector<std::string> point_cloud_files_in(const std::string& folder);

/// The name of a LAS class (ASPRS LAS 1.4 R15, with AHN's use of 26): "building", "ground", ...
const char* las_class_name(int c);

/// Reads only the header of a file. Throws IoError as open_point_cloud() does.
PointCloudInfo read_point_cloud_info(const std::string& path);

}  // namespace city3d
