// Point-cloud input entry points: pick the reader by the file's signature ("LASF" or "ply"), not
// its extension, and read whole files or headers.
#include "city3d/point_cloud_io.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <string>

#include "city3d/error.hpp"
#include "io/input_file.hpp"
#include "io/las_reader.hpp"
#include "io/ply_reader.hpp"

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

PointCloudInfo read_point_cloud_info(const std::string& path) {
  return sniff(path) == FileKind::las ? detail::read_las_info(path) : detail::read_ply_info(path);
}

}  // namespace city3d
