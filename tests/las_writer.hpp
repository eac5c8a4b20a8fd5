// Test helper: writes small LAS 1.2 files (point format 1) from points, with an optional EPSG code
// in a GeoTIFF GeoKeyDirectory VLR, and lets a test lie in the header (point count, VLR length) to
// make broken files. Used where a fixture must be made at test time (big or derived files).
#pragma once

#include <cstdint>
#include <cmath>
#include <cstring>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

namespace city3d::test {

struct LasPoint {
  double x = 0, y = 0, z = 0;
  std::uint8_t classification = 1;
};

struct LasWriteOptions {
  std::optional<int> epsg;                   ///< GeoKey: projected (or geographic when `geographic`)
  bool geographic = false;
  std::optional<std::uint32_t> claimed_count;  ///< header point count instead of the real one
  std::optional<std::uint16_t> claimed_vlr_length;  ///< the GeoKey VLR's length field instead of the real one
  std::optional<double> claimed_max_x;              ///< the header's max x instead of the real one
  double scale = 0.001;
  double offset_x = 0, offset_y = 0, offset_z = 0;
};

inline void put_bytes(std::vector<std::uint8_t>& out, const void* p, std::size_t n) {
  const auto* b = static_cast<const std::uint8_t*>(p);
  out.insert(out.end(), b, b + n);
}
template <typename T>
void put(std::vector<std::uint8_t>& out, T v) {
  put_bytes(out, &v, sizeof v);
}

/// The bytes of a LAS 1.2 file with point format 1 (28-byte records).
inline std::vector<std::uint8_t> las_bytes(const std::vector<LasPoint>& points, const LasWriteOptions& o = {}) {
  std::vector<std::uint8_t> vlr;
  if (o.epsg) {
    // GeoKeyDirectory: header (1, 1, 0, number of keys) and one key (id, location 0, count 1, value).
    const std::uint16_t keys[] = {1, 1, 0, 1, static_cast<std::uint16_t>(o.geographic ? 2048 : 3072), 0, 1,
                                  static_cast<std::uint16_t>(*o.epsg)};
    std::vector<std::uint8_t> payload;
    put_bytes(payload, keys, sizeof keys);
    put<std::uint16_t>(vlr, 0);
    char user_id[16] = {};
    std::memcpy(user_id, "LASF_Projection", 15);
    put_bytes(vlr, user_id, 16);
    put<std::uint16_t>(vlr, 34735);
    put<std::uint16_t>(vlr, o.claimed_vlr_length.value_or(static_cast<std::uint16_t>(payload.size())));
    char description[32] = {};
    put_bytes(vlr, description, 32);
    put_bytes(vlr, payload.data(), payload.size());
  }
  double min[3] = {0, 0, 0}, max[3] = {0, 0, 0};
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double v[3] = {points[i].x, points[i].y, points[i].z};
    for (int a = 0; a < 3; ++a) {
      if (i == 0 || v[a] < min[a]) min[a] = v[a];
      if (i == 0 || v[a] > max[a]) max[a] = v[a];
    }
  }
  std::vector<std::uint8_t> out;
  put_bytes(out, "LASF", 4);
  out.resize(24, 0);  // file source id, global encoding, GUID
  out.push_back(1);
  out.push_back(2);
  char text[32] = {};
  put_bytes(out, text, 32);  // system identifier
  std::memcpy(text, "city3d test", 11);
  put_bytes(out, text, 32);  // generating software
  put<std::uint16_t>(out, 1);
  put<std::uint16_t>(out, 2026);
  put<std::uint16_t>(out, 227);
  put<std::uint32_t>(out, static_cast<std::uint32_t>(227 + vlr.size()));
  put<std::uint32_t>(out, o.epsg ? 1 : 0);
  out.push_back(1);  // point format
  put<std::uint16_t>(out, 28);
  put<std::uint32_t>(out, o.claimed_count.value_or(static_cast<std::uint32_t>(points.size())));
  put<std::uint32_t>(out, static_cast<std::uint32_t>(points.size()));
  for (int i = 0; i < 4; ++i) put<std::uint32_t>(out, 0);
  for (int a = 0; a < 3; ++a) put<double>(out, o.scale);
  put<double>(out, o.offset_x);
  put<double>(out, o.offset_y);
  put<double>(out, o.offset_z);
  if (o.claimed_max_x) max[0] = *o.claimed_max_x;
  for (int a = 0; a < 3; ++a) {
    put<double>(out, max[a]);
    put<double>(out, min[a]);
  }
  put_bytes(out, vlr.data(), vlr.size());
  const double offset[3] = {o.offset_x, o.offset_y, o.offset_z};
  for (const LasPoint& p : points) {
    const double v[3] = {p.x, p.y, p.z};
    for (int a = 0; a < 3; ++a) put<std::int32_t>(out, static_cast<std::int32_t>(std::llround((v[a] - offset[a]) / o.scale)));
    put<std::uint16_t>(out, 0);     // intensity
    out.push_back(0x09);            // return 1 of 1
    out.push_back(p.classification);
    out.push_back(0);               // scan angle
    out.push_back(0);               // user data
    put<std::uint16_t>(out, 0);     // point source id
    put<double>(out, 0.0);          // GPS time
  }
  return out;
}

inline void write_las(const std::string& path, const std::vector<LasPoint>& points, const LasWriteOptions& o = {}) {
  const std::vector<std::uint8_t> bytes = las_bytes(points, o);
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()),
                                              static_cast<std::streamsize>(bytes.size()));
}

}  // namespace city3d::test
