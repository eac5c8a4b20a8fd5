// Point-cloud input entry points: pick the reader by the file's signature ("LASF" or "ply"), not
// its extension, and read whole files or headers.
#include "city3d/point_cloud_io.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <string>

#include "city3d/error.hpp"
#include "points/input_file.hpp"
#include "points/las_reader.hpp"
#include "points/ply_reader.hpp"

namespace city3d {
namespace {

constexpr std::size_t kReadChunk = 1u << 20;  // points per read() in read_point_cloud

enum class FileKind { las, ply };

/// The module named in messages before the signature is known: guessed from the extension.
std::string module_for(const std::string& path) {
  const auto dot = path.find_last_of('.');
  std::string ext = dot == std::string::npos ? "" : path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == "las" || ext == "laz") return "las";
  if (ext == "ply") return "ply";
  return "point cloud";
}

FileKind sniff(const std::string& path) {
  const std::string module = module_for(path);
  detail::InputFile file(path, module);
  if (file.size() == 0) throw IoError(module + ": " + path + " is empty (0 bytes)");
  char head[5] = {};
  const std::size_t got = file.read_some(head, 4);
  if (got == 4 && std::memcmp(head, "LASF", 4) == 0) return FileKind::las;
  if (got >= 4 && std::memcmp(head, "ply", 3) == 0 && (head[3] == '\n' || head[3] == '\r'))
    return FileKind::ply;
  std::string shown;
  for (std::size_t i = 0; i < got; ++i)
    shown += std::isprint(static_cast<unsigned char>(head[i])) ? head[i] : '?';
  throw IoError(module + ": " + path + " has an unknown signature '" + shown +
                "' (expected 'LASF' for LAS/LAZ or 'ply' for PLY)");
}

}  // namespace

std::unique_ptr<PointCloudReader> open_point_cloud(const std::string& path, PointFields fields) {
  return open_point_cloud(path, fields, 1);
}

std::unique_ptr<PointCloudReader> open_point_cloud(const std::string& path, PointFields fields,
                                                   unsigned decode_threads) {
  return sniff(path) == FileKind::las ? detail::open_las(path, fields, decode_threads)
                                      : detail::open_ply(path, fields);
}

std::unique_ptr<PointCloudReader> open_point_cloud(const std::string& path, PointFields fields,
                                                   unsigned decode_threads, ChunkExtents& extents,
                                                   const std::vector<Box2>& regions) {
  return sniff(path) == FileKind::las ? detail::open_las(path, fields, decode_threads, &extents, &regions)
                                      : detail::open_ply(path, fields);
}

PointCloud read_point_cloud(const std::string& path, PointFields fields) {
  return read_point_cloud(path, fields, 1);
}

PointCloud read_point_cloud(const std::string& path, PointFields fields, unsigned decode_threads) {
  auto reader = open_point_cloud(path, fields, decode_threads);
  PointCloud cloud;
  while (reader->read(cloud, kReadChunk) > 0) {
  }
  return cloud;
}

std::vector<std::string> point_cloud_files_in(const std::string& folder) {
  namespace fs = std::filesystem;
  std::vector<std::string> found;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    std::string ext = entry.path().extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (entry.is_regular_file() && (ext == ".las" || ext == ".laz" || ext == ".ply")) found.push_back(entry.path().string());
  }
  if (ec) throw IoError("input: cannot list folder " + folder + ": " + ec.message());
  std::sort(found.begin(), found.end());
  return found;
}

// ASPRS LAS 1.4 standard class names (R15); AHN uses 26 for civil structures ("kunstwerk").
const char* las_class_name(int c) {
  switch (c) {
    case 0: return "never classified";
    case 1: return "unclassified";
    case 2: return "ground";
    case 3: return "low vegetation";
    case 4: return "medium vegetation";
    case 5: return "high vegetation";
    case 6: return "building";
    case 7: return "low point (noise)";
    case 9: return "water";
    case 10: return "rail";
    case 11: return "road surface";
    case 13: return "wire guard";
    case 14: return "wire conductor";
    case 15: return "transmission tower";
    case 17: return "bridge deck";
    case 18: return "high noise";
    case 26: return "user defined (AHN: civil structure)";
    default: return c < 64 ? "reserved" : "user defined";
  }
}

PointCloudInfo read_point_cloud_info(const std::string& path) {
  return sniff(path) == FileKind::las ? detail::read_las_info(path) : detail::read_ply_info(path);
}

}  // namespace city3d
