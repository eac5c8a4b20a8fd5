// Tests of the point-cloud readers: LAS 1.0-1.4 (formats 0-3, 6-8), LAZ recognition, PLY (ascii,
// binary little/big endian), streaming, and deliberately broken files (tests/data/*/broken, written
// by tests/data/make_test_files.py).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/point_cloud_io.hpp"
#include "las_writer.hpp"

namespace city3d {
namespace {

const std::string kAhn3 = CITY3D_SHARED_DATA "/ahn3_delft/ahn3_cropped_1.las";
const std::string kAhn3Laz = CITY3D_SHARED_DATA "/ahn3_delft/ahn3_cropped_1.laz";
const std::string kCases = CITY3D_SHARED_DATA "/laz/cases/";
const std::string kTestLas = CITY3D_TEST_DATA "/las/";
const std::string kTestPly = CITY3D_TEST_DATA "/ply/";

/// Runs `f`, which must throw IoError, and returns its message (other exception types fail the test).
template <typename F>
std::string io_error_of(F f) {
  try {
    f();
  } catch (const IoError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no IoError thrown";
  return {};
}

void expect_contains(const std::string& message, std::initializer_list<const char*> parts) {
  for (const char* part : parts) EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
}

std::string read_error(const std::string& path) {
  return io_error_of([&] { read_point_cloud(path); });
}

/// The AHN3 tile, read once for all tests that need every point.
const PointCloud& ahn3() {
  static const PointCloud cloud = read_point_cloud(kAhn3);
  return cloud;
}

// ---------------------------------------------------------------------------------------------
// AHN3 tile (LAS 1.2, format 1)

TEST(LasReader, reads_ahn3_tile_point_count_and_class_histogram) {
  const PointCloud& c = ahn3();
  ASSERT_EQ(c.size(), 640510u);
  ASSERT_EQ(c.classification.size(), c.size());
  std::map<int, std::size_t> histogram;
  for (auto k : c.classification) ++histogram[k];
  const std::map<int, std::size_t> expected{{1, 196137}, {2, 195988}, {6, 246753}, {9, 267}, {26, 1365}};
  EXPECT_EQ(histogram, expected);
  std::map<int, std::size_t> returns;
  for (auto r : c.return_number) ++returns[r];
  const std::map<int, std::size_t> expected_returns{{1, 468011}, {2, 99134}, {3, 44555}, {4, 20800}, {5, 8010}};
  EXPECT_EQ(returns, expected_returns);
  EXPECT_EQ(c.gps_time.size(), c.size());
  EXPECT_TRUE(c.rgb.empty());    // format 1 has no colour
  EXPECT_TRUE(c.normals.empty());
}

TEST(LasReader, reports_ahn3_header_bounds_and_facts) {
  const PointCloudInfo info = read_point_cloud_info(kAhn3);
  EXPECT_EQ(info.format, "LAS");
  EXPECT_EQ(info.version, "1.2");
  EXPECT_EQ(info.point_format, 1);
  EXPECT_EQ(info.record_length, 28);
  EXPECT_EQ(info.point_count, 640510u);
  EXPECT_FALSE(info.compressed);
  EXPECT_DOUBLE_EQ(info.bounds.min.x, 84808.300);
  EXPECT_DOUBLE_EQ(info.bounds.max.x, 84999.999);
  EXPECT_DOUBLE_EQ(info.bounds.min.y, 447412.800);
  EXPECT_DOUBLE_EQ(info.bounds.max.y, 447641.299);
  EXPECT_DOUBLE_EQ(info.bounds.min.z, -0.568);  // ahn3_cropped_1.summary.json: "min" / "max"
  EXPECT_DOUBLE_EQ(info.bounds.max.z, 19.398);
  EXPECT_DOUBLE_EQ(info.scale[0], 0.001);
  EXPECT_TRUE(std::signbit(info.offset[0]));  // the file's offsets are IEEE -0.0
  EXPECT_EQ(info.generating_software, "las2las (version 160730)");
  EXPECT_TRUE(info.crs.empty());
  EXPECT_TRUE(info.vlrs.empty());
  EXPECT_EQ(info.fields, kFieldIntensity | kFieldReturns | kFieldClassification | kFieldGpsTime);
}

TEST(LasReader, ahn3_points_lie_inside_the_header_bounds) {
  Box3 box;
  for (const Point3& p : ahn3().points) box.add(p);
  const PointCloudInfo info = read_point_cloud_info(kAhn3);
  EXPECT_DOUBLE_EQ(box.min.x, info.bounds.min.x);
  EXPECT_DOUBLE_EQ(box.max.x, info.bounds.max.x);
  EXPECT_DOUBLE_EQ(box.min.y, info.bounds.min.y);
  EXPECT_DOUBLE_EQ(box.max.y, info.bounds.max.y);
  EXPECT_NEAR(box.min.z, info.bounds.min.z, 1e-9);
  EXPECT_NEAR(box.max.z, info.bounds.max.z, 1e-9);
}

TEST(LasReader, ahn3_records_match_sample_points_csv_exactly) {
  std::ifstream csv(CITY3D_SHARED_DATA "/ahn3_delft/sample_points.csv");
  ASSERT_TRUE(csv) << "sample_points.csv missing";
  std::string line;
  std::getline(csv, line);  // header
  const PointCloud& c = ahn3();
  int checked = 0;
  while (std::getline(csv, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) f.push_back(cell);
    if (f.at(0) != "ahn3_cropped_1.las") continue;
    const std::size_t i = std::stoul(f[1]);
    SCOPED_TRACE("point " + f[1]);
    ASSERT_LT(i, c.size());
    // world = int * 0.001 + (-0.0): the integer record survives exactly.
    EXPECT_EQ(std::llround(c.points[i].x * 1000.0), std::stoll(f[2]));
    EXPECT_EQ(std::llround(c.points[i].y * 1000.0), std::stoll(f[3]));
    EXPECT_EQ(std::llround(c.points[i].z * 1000.0), std::stoll(f[4]));
    EXPECT_EQ(c.points[i].x, std::stoll(f[2]) * 0.001);
    EXPECT_DOUBLE_EQ(c.points[i].x, std::stod(f[5]));
    EXPECT_DOUBLE_EQ(c.points[i].y, std::stod(f[6]));
    EXPECT_DOUBLE_EQ(c.points[i].z, std::stod(f[7]));
    EXPECT_EQ(c.intensity[i], std::stoi(f[8]));
    EXPECT_EQ(c.return_number[i], std::stoi(f[9]));
    EXPECT_EQ(c.number_of_returns[i], std::stoi(f[10]));
    EXPECT_EQ(c.classification[i], std::stoi(f[13]));
    EXPECT_EQ(c.gps_time[i], std::stod(f[20]));  // printed with 17 digits: exact
    ++checked;
  }
  EXPECT_GE(checked, 10);
}

TEST(LasReader, fills_only_the_requested_fields) {
  auto reader = open_point_cloud(kAhn3, kFieldClassification);
  PointCloud c;
  ASSERT_EQ(reader->read(c, 5), 5u);
  EXPECT_EQ(c.classification.size(), 5u);
  EXPECT_TRUE(c.intensity.empty());
  EXPECT_TRUE(c.return_number.empty());
  EXPECT_TRUE(c.gps_time.empty());
  EXPECT_EQ(c.classification[0], 6);  // sample_points.csv, index 0
}

// ---------------------------------------------------------------------------------------------
// The LAS twins of the LAZ cases: every version and format the project has

struct LasCase {
  const char* name;
  const char* version;
  int format;
  int record_length;
  std::uint64_t count;
};

const LasCase kLasCases[] = {
    {"las10_pf0_1pt", "1.0", 0, 20, 1},
    {"las10_pf1_mvk", "1.0", 1, 28, 6280},
    {"las11_pf0_1pt", "1.1", 0, 20, 1},
    {"las11_pf0_epsg4326_chunk1000", "1.1", 0, 20, 5380},
    {"las12_pf0_point10", "1.2", 0, 20, 1065},
    {"las12_pf1_1815", "1.2", 1, 28, 1247},
    {"las12_pf1_point-time", "1.2", 1, 28, 1065},
    {"las12_pf2_point-color", "1.2", 2, 26, 1065},
    {"las12_pf3_autzen_trim_3chunks", "1.2", 3, 34, 110000},
    {"las12_pf3_chunktable_minus1", "1.2", 3, 34, 110},
    {"las12_pf3_extrabytes27", "1.2", 3, 61, 1065},
    {"las12_pf3_point-color-time", "1.2", 3, 34, 1065},
    {"las12_pf3_simple", "1.2", 3, 34, 1065},
    {"las12_pf3_varchunk", "1.2", 3, 34, 2732},
    {"las13_pf0_nopoints", "1.3", 0, 20, 0},
    {"las13_pf3_interesting", "1.3", 3, 34, 1065},
    {"las14_pf1_point-time_compressor2", "1.4", 1, 28, 1065},
    {"las14_pf6_rand_20k_chunk5000", "1.4", 6, 30, 20000},  // legacy count 0: 64-bit count
    {"las14_pf6_test1_4", "1.4", 6, 30, 1000},
    {"las14_pf6_varchunk", "1.4", 6, 30, 1000},
    {"las14_pf7_autzen_60k_2chunks", "1.4", 7, 36, 60000},
    {"las14_pf7_copc_varchunk_real", "1.4", 7, 36, 1065},
    {"las14_pf7_zero_points", "1.4", 7, 36, 0},
    {"las14_pf8_autzen_nir_5k", "1.4", 8, 38, 5000},
    {"las14_pf8_eb3_real_1chunk", "1.4", 8, 41, 50000},  // legacy count 0, 3 extra bytes
};

TEST(LasReader, reads_every_las_case_with_the_right_count_and_plausible_fields) {
  for (const LasCase& k : kLasCases) {
    SCOPED_TRACE(k.name);
    const std::string path = kCases + k.name + ".las";
    const PointCloudInfo info = read_point_cloud_info(path);
    EXPECT_EQ(info.version, k.version);
    EXPECT_EQ(info.point_format, k.format);
    EXPECT_EQ(info.record_length, k.record_length);
    EXPECT_EQ(info.point_count, k.count);
    // Every record is a point or withheld (the random cases flag about half of theirs withheld).
    auto reader = open_point_cloud(path);
    PointCloud c;
    while (reader->read(c, 1u << 20) > 0) {
    }
    ASSERT_EQ(c.size() + reader->withheld_points(), k.count);
    const bool has_gps = k.format == 1 || k.format >= 3;
    const bool has_rgb = k.format == 2 || k.format == 3 || k.format >= 7;
    EXPECT_EQ(c.gps_time.size(), has_gps ? c.size() : 0u);
    EXPECT_EQ(c.rgb.size(), has_rgb ? c.size() : 0u);
    EXPECT_EQ(c.classification.size(), c.size());
    const int max_return = k.format >= 6 ? 15 : 7;
    const double tolerance = 0.5 * info.scale[0] + 1e-6;
    for (std::size_t i = 0; i < c.size(); ++i) {
      const Point3& p = c.points[i];
      ASSERT_TRUE(p.x >= info.bounds.min.x - tolerance && p.x <= info.bounds.max.x + tolerance &&
                  p.y >= info.bounds.min.y - tolerance && p.y <= info.bounds.max.y + tolerance)
          << "point " << i << " outside the header bounds";
      ASSERT_LE(c.return_number[i], max_return);
      ASSERT_LE(c.number_of_returns[i], max_return);
      if (k.format < 6) ASSERT_LE(c.classification[i], 31);
    }
  }
}

TEST(LasReader, reads_first_point_of_point_color_time_exactly) {
  // Values decoded independently with Python struct from the record at byte 1207 (format 3).
  const PointCloud c = read_point_cloud(kCases + "las12_pf3_point-color-time.las");
  ASSERT_EQ(c.size(), 1065u);
  EXPECT_DOUBLE_EQ(c.points[0].x, 494428.61);
  EXPECT_DOUBLE_EQ(c.points[0].y, 4877455.58);
  EXPECT_DOUBLE_EQ(c.points[0].z, 131.57);
  EXPECT_EQ(c.intensity[0], 143);
  EXPECT_EQ(c.return_number[0], 1);
  EXPECT_EQ(c.number_of_returns[0], 1);
  EXPECT_EQ(c.classification[0], 1);
  EXPECT_EQ(c.gps_time[0], 245380.78254962614);
  EXPECT_EQ(c.rgb[0], (std::array<std::uint16_t, 3>{68, 77, 88}));
}

TEST(LasReader, reads_first_point_of_format_8_with_extra_bytes_exactly) {
  // Python struct decode of the record at byte 2017 (format 8, 41-byte records).
  const PointCloud c = read_point_cloud(kCases + "las14_pf8_eb3_real_1chunk.las");
  ASSERT_EQ(c.size(), 50000u);
  EXPECT_DOUBLE_EQ(c.points[0].x, 484819.49);
  EXPECT_DOUBLE_EQ(c.points[0].y, 6632768.84);
  EXPECT_DOUBLE_EQ(c.points[0].z, 105.87);
  EXPECT_EQ(c.intensity[0], 945);
  EXPECT_EQ(c.return_number[0], 2);
  EXPECT_EQ(c.number_of_returns[0], 2);
  EXPECT_EQ(c.gps_time[0], 390583957.9501002);
  EXPECT_EQ(c.rgb[0], (std::array<std::uint16_t, 3>{18944, 22272, 18432}));
}

TEST(LasReader, reads_extended_returns_and_8_bit_class_past_extra_bytes) {
  // tests/data/las/las14_pf7_extrabytes_geokeys.las: values written by make_test_files.py.
  const std::string path = kTestLas + "las14_pf7_extrabytes_geokeys.las";
  const PointCloud c = read_point_cloud(path);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_DOUBLE_EQ(c.points[0].x, 84916.949);
  EXPECT_DOUBLE_EQ(c.points[0].y, 447413.300);
  EXPECT_DOUBLE_EQ(c.points[1].z, -5.101);
  EXPECT_EQ(c.return_number[0], 9);
  EXPECT_EQ(c.number_of_returns[0], 12);
  EXPECT_EQ(c.classification[0], 40);
  EXPECT_EQ(c.classification[1], 6);
  EXPECT_EQ(c.intensity[1], 70);
  EXPECT_EQ(c.gps_time[1], 228672.5);
  EXPECT_EQ(c.rgb[0], (std::array<std::uint16_t, 3>{1000, 2000, 65535}));
  const PointCloudInfo info = read_point_cloud_info(path);
  EXPECT_EQ(info.record_length, 40);
  EXPECT_EQ(info.crs, "EPSG:28992");
  ASSERT_EQ(info.vlrs.size(), 1u);
  EXPECT_EQ(info.vlrs[0], "LASF_Projection/34735 (24 bytes)");
  EXPECT_EQ(info.generating_software, "make_test_files.py");
}

TEST(LasReader, takes_crs_from_geotiff_keys_or_wkt) {
  EXPECT_EQ(read_point_cloud_info(kCases + "las12_pf3_point-color-time.las").crs, "EPSG:26910");
  EXPECT_EQ(read_point_cloud_info(kCases + "las11_pf0_epsg4326_chunk1000.las").crs, "EPSG:4326");
  // This one has both: the WKT wins.
  const std::string wkt = read_point_cloud_info(kCases + "las14_pf8_eb3_real_1chunk.las").crs;
  EXPECT_EQ(wkt.rfind("PROJCRS[\"RGF93 / Lambert-93\"", 0), 0u) << wkt.substr(0, 80);
}

TEST(LasReader, lists_vlrs_and_evlrs) {
  const PointCloudInfo info = read_point_cloud_info(kCases + "las14_pf7_copc_varchunk_real.las");
  ASSERT_FALSE(info.vlrs.empty());
  EXPECT_NE(info.vlrs.back().find("EVLR"), std::string::npos) << info.vlrs.back();
  const PointCloudInfo interesting = read_point_cloud_info(kCases + "las13_pf3_interesting.las");
  ASSERT_EQ(interesting.vlrs.size(), 5u);
  EXPECT_EQ(interesting.vlrs[0], "hobu/1234 (70 bytes)");
}

TEST(LasReader, streams_in_chunks_of_1000_with_the_same_points_as_a_whole_read) {
  const std::string path = kCases + "las12_pf3_autzen_trim_3chunks.las";
  const PointCloud whole = read_point_cloud(path);
  auto reader = open_point_cloud(path);
  PointCloud streamed;
  std::size_t calls = 0;
  for (std::size_t n; (n = reader->read(streamed, 1000)) > 0; ++calls) ASSERT_LE(n, 1000u);
  EXPECT_EQ(calls, 110u);
  ASSERT_EQ(streamed.size(), whole.size());
  for (std::size_t i = 0; i < whole.size(); ++i) {
    ASSERT_EQ(streamed.points[i].x, whole.points[i].x) << i;
    ASSERT_EQ(streamed.points[i].y, whole.points[i].y) << i;
    ASSERT_EQ(streamed.points[i].z, whole.points[i].z) << i;
  }
  EXPECT_EQ(streamed.classification, whole.classification);
  EXPECT_EQ(streamed.gps_time, whole.gps_time);
  EXPECT_EQ(streamed.rgb, whole.rgb);
  EXPECT_EQ(streamed.intensity, whole.intensity);
  EXPECT_EQ(reader->read(streamed, 1000), 0u);
}

// The LAS specification: points flagged withheld "should be considered a deleted point". They are
// left out of every read, whatever the chunking, and counted.
TEST(LasReader, leaves_out_points_flagged_withheld_and_counts_them) {
  const std::string path = ::testing::TempDir() + "/withheld.las";
  std::vector<test::LasPoint> points;
  for (int i = 0; i < 10; ++i) {
    // The first three and the seventh withheld (bit 7 of format 1's class byte), the others not.
    const bool withheld = i < 3 || i == 6;
    points.push_back(
        {1000.0 + i, 2000.0, 5.0 + i, static_cast<std::uint8_t>((i % 2 ? 6 : 2) | (withheld ? 0x80 : 0))});
  }
  test::write_las(path, points);
  for (std::size_t chunk : {1u, 2u, 1000u}) {
    auto reader = open_point_cloud(path);
    PointCloud c;
    std::size_t calls = 0;
    for (std::size_t n; (n = reader->read(c, chunk)) > 0; ++calls) ASSERT_LE(n, chunk);
    ASSERT_EQ(c.size(), 6u) << chunk;
    const double kept_x[] = {1003, 1004, 1005, 1007, 1008, 1009};
    for (std::size_t k = 0; k < 6; ++k) {
      EXPECT_EQ(c.points[k].x, kept_x[k]) << chunk;
      EXPECT_EQ(c.points[k].z, kept_x[k] - 995.0) << chunk;
      EXPECT_EQ(c.classification[k], static_cast<int>(kept_x[k]) % 2 ? 6 : 2) << chunk;
    }
    EXPECT_EQ(c.gps_time.size(), 6u);
    EXPECT_EQ(c.intensity.size(), 6u);
    EXPECT_EQ(reader->withheld_points(), 4u) << chunk;
    if (chunk == 1) EXPECT_EQ(calls, 6u);  // the withheld first three do not end the read early
  }
  std::remove(path.c_str());
}

TEST(LasReader, leaves_out_withheld_points_of_the_extended_formats_by_their_flag_bit) {
  // Formats 6-10 keep the flag in bit 2 of byte 15 (the classification flags); bit 7 there is the
  // edge of flight line, which must not drop a point.
  const std::string source = kCases + "las14_pf8_eb3_real_1chunk.las";
  const PointCloud whole = read_point_cloud(source);
  std::ifstream in(source, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t first = 2017,
                    length = 41;  // as in reads_first_point_of_format_8_with_extra_bytes_exactly
  bytes[first + 15] = static_cast<char>(bytes[first + 15] | 0x04);
  bytes[first + 2 * length + 15] = static_cast<char>(bytes[first + 2 * length + 15] | 0x04);
  bytes[first + length + 15] = static_cast<char>(bytes[first + length + 15] | 0x80);
  const std::string path = ::testing::TempDir() + "/withheld_pf8.las";
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  auto reader = open_point_cloud(path);
  PointCloud c;
  while (reader->read(c, 4096) > 0) {
  }
  ASSERT_EQ(c.size(), whole.size() - 2);
  EXPECT_EQ(reader->withheld_points(), 2u);
  EXPECT_EQ(c.points[0].x, whole.points[1].x);
  EXPECT_EQ(c.points[1].x, whole.points[3].x);
  EXPECT_EQ(c.rgb[0], whole.rgb[1]);
  EXPECT_EQ(c.gps_time[1], whole.gps_time[3]);
  std::remove(path.c_str());
}

TEST(LasReader, warns_but_reads_when_the_evlr_pointer_is_past_the_end) {
  const std::string path = kTestLas + "broken/evlr_pointer_past_eof.las";
  testing::internal::CaptureStderr();
  const PointCloud c = read_point_cloud(path);
  const std::string log = testing::internal::GetCapturedStderr();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_DOUBLE_EQ(c.points[0].z, 0.03);
  EXPECT_EQ(c.classification[0], 2);
  expect_contains(log, {"las: EVLR pointer 1000000000", "evlr_pointer_past_eof.las", "ignoring 2 EVLRs"});
}

// ---------------------------------------------------------------------------------------------
// LAZ: recognised, refused for reading, described by info

// Every field of every point of `a` equals the one of `b`.
void expect_same_points(const PointCloud& a, const PointCloud& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.points[i].x, b.points[i].x) << i;
    ASSERT_EQ(a.points[i].y, b.points[i].y) << i;
    ASSERT_EQ(a.points[i].z, b.points[i].z) << i;
  }
  EXPECT_EQ(a.intensity, b.intensity);
  EXPECT_EQ(a.return_number, b.return_number);
  EXPECT_EQ(a.number_of_returns, b.number_of_returns);
  EXPECT_EQ(a.classification, b.classification);
  // Bitwise: some test files hold random bytes as GPS times, NaNs among them.
  ASSERT_EQ(a.gps_time.size(), b.gps_time.size());
  if (!a.gps_time.empty())  // memcmp may not be given the null data() of an empty vector
    EXPECT_EQ(std::memcmp(a.gps_time.data(), b.gps_time.data(), a.gps_time.size() * sizeof(double)), 0);
  EXPECT_EQ(a.rgb, b.rgb);
}

// Every field of every point of a LAZ file equals its LAS twin's.
void expect_same_points(const std::string& laz, const std::string& las) {
  expect_same_points(read_point_cloud(laz), read_point_cloud(las));
}

/// Reads a file `batch` points per read() call, decoding LAZ on `threads` threads.
PointCloud read_in_batches(const std::string& path, unsigned threads, std::size_t batch) {
  auto reader = open_point_cloud(path, kFieldAll, threads);
  PointCloud cloud;
  while (reader->read(cloud, batch) > 0) {
  }
  return cloud;
}

TEST(LasReader, reads_ahn3_laz_to_exactly_the_points_of_its_las_twin) {
  const PointCloudInfo info = read_point_cloud_info(kAhn3Laz);
  EXPECT_TRUE(info.compressed);
  EXPECT_EQ(info.format, "LAZ");
  EXPECT_EQ(info.point_format, 1);
  EXPECT_EQ(info.record_length, 28);
  EXPECT_EQ(info.point_count, 640510u);
  ASSERT_EQ(info.vlrs.size(), 1u);
  EXPECT_EQ(info.vlrs[0], "laszip encoded/22204 (46 bytes)");
  expect_same_points(kAhn3Laz, CITY3D_SHARED_DATA "/ahn3_delft/ahn3_cropped_1.las");
}

TEST(LasReader, reads_every_laz_case_to_exactly_the_points_of_its_las_twin) {
  for (const LasCase& k : kLasCases) {
    SCOPED_TRACE(k.name);
    const std::string path = kCases + k.name + ".laz";
    const PointCloudInfo info = read_point_cloud_info(path);
    EXPECT_TRUE(info.compressed);
    EXPECT_EQ(info.point_count, k.count);
    EXPECT_EQ(info.point_format, k.format);
    EXPECT_EQ(info.record_length, k.record_length);
    expect_same_points(path, kCases + k.name + ".las");
  }
}

TEST(LasReader, reads_every_laz_case_and_both_ahn3_tiles_identically_on_1_2_and_4_decode_threads) {
  std::vector<std::pair<std::string, std::string>> pairs;
  for (const LasCase& k : kLasCases) pairs.emplace_back(kCases + k.name + ".laz", kCases + k.name + ".las");
  for (const char* tile : {"ahn3_cropped_1", "ahn3_cropped_2"}) {
    const std::string base = std::string(CITY3D_SHARED_DATA) + "/ahn3_delft/" + tile;
    pairs.emplace_back(base + ".laz", base + ".las");
  }
  for (const auto& [laz, las] : pairs) {
    const PointCloud expected = read_point_cloud(las);
    for (const unsigned threads : {1u, 2u, 4u}) {
      SCOPED_TRACE(laz + " on " + std::to_string(threads) + " threads");
      expect_same_points(read_point_cloud(laz, kFieldAll, threads), expected);
      // small reads: records of one decoded chunk are handed out over many calls
      expect_same_points(read_in_batches(laz, threads, 7777), expected);
    }
  }
}

/// Copies a LAZ case to a temporary file with 16 bytes flipped in the middle of its data.
std::string corrupt_laz_copy(const std::string& name, double where) {
  std::ifstream in(kCases + name + ".laz", std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), {});
  const auto at = static_cast<std::size_t>(static_cast<double>(bytes.size()) * where);
  for (std::size_t i = 0; i < 16; ++i) bytes[at + i] = static_cast<char>(bytes[at + i] ^ 0x5A);
  const std::string path = ::testing::TempDir() + "city3d_" + name + "_corrupt.laz";
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path;
}

/// Reads `path` 1000 points per call on `threads` threads; returns the error and how many records
/// were read before it (the points handed out and the withheld ones left out: the random cases flag
/// about half of their records withheld).
std::pair<std::string, std::size_t> error_and_points_before(const std::string& path, unsigned threads) {
  auto reader = open_point_cloud(path, kFieldAll, threads);
  PointCloud cloud;
  const std::string error = io_error_of([&] {
    while (reader->read(cloud, 1000) > 0) {
    }
  });
  // and every later call throws the same error
  EXPECT_EQ(io_error_of([&] { reader->read(cloud, 1000); }), error);
  return {error, cloud.size() + reader->withheld_points()};
}

TEST(LasReader, a_corrupt_laz_chunk_raises_the_same_error_on_4_threads_when_its_records_are_due) {
  // 20000 points in 4 chunks of 5000: the flipped bytes at 60% of the file lie in chunk 2
  const std::string path = corrupt_laz_copy("las14_pf6_rand_20k_chunk5000", 0.6);
  const auto [error1, before1] = error_and_points_before(path, 1);
  const auto [error4, before4] = error_and_points_before(path, 4);
  std::remove(path.c_str());
  expect_contains(error1, {"las14_pf6_rand_20k_chunk5000_corrupt.laz", "chunk 2 of 4"});
  EXPECT_EQ(error4, error1);
  // four threads hand out chunks 0 and 1 and stop exactly where chunk 2 starts; one thread decodes
  // 2 MB blocks of records (the whole file here) and reports none of a block that fails
  EXPECT_EQ(before4, 10000u);
  EXPECT_EQ(before1, 0u);
}

TEST(LasReader, destroying_a_laz_reader_mid_file_with_4_decode_threads_stops_its_workers) {
  for (const std::size_t read_first : {0u, 1u, 50000u, 300000u}) {
    auto reader = open_point_cloud(kAhn3Laz, kFieldXyz, 4);
    PointCloud cloud;
    if (read_first > 0) ASSERT_EQ(reader->read(cloud, read_first), read_first);
    EXPECT_EQ(cloud.size(), read_first);
    reader.reset();  // joins the workers (a hang here fails the test by timeout)
  }
  // a reader left after its error is destroyed cleanly too
  const std::string path = corrupt_laz_copy("las14_pf6_rand_20k_chunk5000", 0.35);
  {
    auto reader = open_point_cloud(path, kFieldAll, 4);
    PointCloud cloud;
    EXPECT_FALSE(io_error_of([&] {
                   while (reader->read(cloud, 1000) > 0) {
                   }
                 }).empty());
  }
  std::remove(path.c_str());
}

/// Reads `path` to the end through open_point_cloud(path, fields, threads, extents, regions).
PointCloud read_regions(const std::string& path, unsigned threads, ChunkExtents& extents,
                        const std::vector<Box2>& regions) {
  auto reader = open_point_cloud(path, kFieldAll, threads, extents, regions);
  PointCloud cloud;
  while (reader->read(cloud, 7000) > 0) {
  }
  return cloud;
}

/// The points of `whole` in the given chunks of 50,000 (AHN3's), in order.
std::vector<Point3> points_of_chunks(const PointCloud& whole, const std::vector<std::size_t>& chunks) {
  std::vector<Point3> out;
  for (std::size_t c : chunks)
    out.insert(out.end(), whole.points.begin() + static_cast<std::ptrdiff_t>(50000 * c),
               whole.points.begin() +
                   static_cast<std::ptrdiff_t>(std::min<std::size_t>(50000 * (c + 1), whole.size())));
  return out;
}

bool same_points(const std::vector<Point3>& a, const std::vector<Point3>& b) {
  return a.size() == b.size() &&
         std::equal(a.begin(), a.end(), b.begin(),
                    [](const Point3& p, const Point3& q) { return p.x == q.x && p.y == q.y && p.z == q.z; });
}

TEST(LasReader,
     a_whole_laz_read_learns_where_its_chunks_lie_and_a_later_one_decodes_only_those_a_region_meets) {
  const PointCloud whole = read_point_cloud(kAhn3Laz);
  ASSERT_EQ(whole.size(), 640510u);  // 13 chunks: 12 of 50,000 and one of 40,510
  for (const unsigned threads : {1u, 2u}) {
    SCOPED_TRACE(std::to_string(threads) + " decode threads");
    // A read while the extents are unknown hands out every point and learns the bounds of each chunk.
    ChunkExtents extents;
    const std::vector<Box2> nowhere;
    const PointCloud first = read_regions(kAhn3Laz, threads, extents, nowhere);
    EXPECT_TRUE(same_points(first.points, whole.points));
    ASSERT_EQ(extents.boxes.size(), 13u);
    for (std::size_t c = 0; c < 13; ++c) {
      Box2 box;
      for (const Point3& p : points_of_chunks(whole, {c})) box.add({p.x, p.y});
      EXPECT_TRUE(extents.boxes[c].min.x == box.min.x && extents.boxes[c].min.y == box.min.y &&
                  extents.boxes[c].max.x == box.max.x && extents.boxes[c].max.y == box.max.y)
          << "chunk " << c;
    }
    // A small region around the last point of chunk 9: only the chunks whose bounds it meets are read,
    // whole and in file order, with their attributes.
    const Point3 at = whole.points[50000 * 9 + 49999];
    const std::vector<Box2> region{{{at.x - 0.5, at.y - 0.5}, {at.x + 0.5, at.y + 0.5}}};
    std::vector<std::size_t> meeting;
    for (std::size_t c = 0; c < 13; ++c)
      if (extents.boxes[c].intersects(region[0])) meeting.push_back(c);
    ASSERT_FALSE(meeting.empty());
    ASSERT_LT(meeting.size(), 6u);  // the test must leave chunks out
    ChunkExtents known = extents;
    const PointCloud part = read_regions(kAhn3Laz, threads, known, region);
    EXPECT_TRUE(same_points(part.points, points_of_chunks(whole, meeting)));
    ASSERT_EQ(part.classification.size(), part.size());
    EXPECT_EQ(part.classification.front(), whole.classification[50000 * meeting.front()]);
    EXPECT_EQ(known.boxes.size(), 13u);  // kept as it was
    // No region: no point.
    EXPECT_EQ(read_regions(kAhn3Laz, threads, known, nowhere).size(), 0u);
  }
  // A read stopped before the end learns nothing.
  ChunkExtents unfinished;
  {
    auto reader = open_point_cloud(kAhn3Laz, kFieldXyz, 2, unfinished, {});
    PointCloud cloud;
    ASSERT_EQ(reader->read(cloud, 120000), 120000u);
  }
  EXPECT_TRUE(unfinished.boxes.empty());
  // A LAS file has no chunks: it is read whole, and nothing is learnt.
  ChunkExtents las;
  EXPECT_EQ(read_regions(kAhn3, 2, las, {}).size(), 640510u);
  EXPECT_TRUE(las.boxes.empty());
}

TEST(LasReader, rejects_compression_bit_without_laszip_vlr) {
  expect_contains(read_error(kTestLas + "broken/laz_bit_set.las"),
                  {"laz_bit_set.las", "compression bit set but there is no LASzip VLR"});
  expect_contains(read_error(CITY3D_SHARED_DATA "/laz/broken/broken_no_laszip_vlr.laz"),
                  {"broken_no_laszip_vlr.laz", "no LASzip VLR"});
}

// ---------------------------------------------------------------------------------------------
// Broken LAS files

TEST(LasReader, rejects_empty_file) {
  expect_contains(read_error(kTestLas + "broken/empty.las"), {"las: ", "empty.las", "is empty (0 bytes)"});
  expect_contains(io_error_of([&] { read_point_cloud_info(kTestLas + "broken/empty.las"); }), {"empty"});
}

TEST(LasReader, rejects_truncated_header_naming_the_byte) {
  expect_contains(read_error(kTestLas + "broken/truncated_header.las"),
                  {"las: header truncated at byte 180 in", "truncated_header.las", "227"});
}

TEST(LasReader, rejects_wrong_signature) {
  expect_contains(read_error(kTestLas + "broken/wrong_signature.las"),
                  {"wrong_signature.las", "signature", "LASX"});
}

TEST(LasReader, rejects_point_count_larger_than_the_file) {
  expect_contains(read_error(kTestLas + "broken/point_count_exceeds_file.las"),
                  {"las: invalid header in", "point_count_exceeds_file.las", "point count 5000",
                   "larger than the file", "only 20 bytes"});
}

TEST(LasReader, rejects_record_length_smaller_than_the_format_needs) {
  expect_contains(read_error(kTestLas + "broken/record_length_too_small.las"),
                  {"record_length_too_small.las", "point record length 24", "point data format 1", "(28)"});
}

TEST(LasReader, collects_all_header_problems_in_one_error) {
  expect_contains(read_error(kTestLas + "broken/many_header_problems.las"),
                  {"many_header_problems.las", "version 2.1", "point data format 12 is unknown",
                   "scale x is 0", "scale z is nan"});
}

TEST(LasReader, rejects_coordinates_that_overflow_after_scale_naming_the_point) {
  expect_contains(read_error(kTestLas + "broken/scale_overflow.las"),
                  {"las: point 1 in", "scale_overflow.las", "non-finite coordinate"});
}

TEST(PointCloudIo, rejects_missing_file_and_unknown_signature) {
  expect_contains(read_error(kTestLas + "no_such_file.las"), {"no_such_file.las", "cannot open"});
  expect_contains(read_error(CITY3D_TEST_DATA "/footprints/not_a_vector.txt"),
                  {"not_a_vector.txt", "unknown signature", "LASF", "ply"});
}

// ---------------------------------------------------------------------------------------------
// PLY

TEST(PlyReader, reads_smoke_buildings_with_the_manifest_counts) {
  std::ifstream manifest(CITY3D_SHARED_DATA "/city3d_smoke/manifest.csv");
  ASSERT_TRUE(manifest);
  std::string line;
  std::getline(manifest, line);
  int files = 0;
  while (std::getline(manifest, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) f.push_back(cell);
    SCOPED_TRACE(f.at(2));
    const std::string path = std::string(CITY3D_SHARED_DATA "/city3d_smoke/") + f.at(2);
    const PointCloud c = read_point_cloud(path);
    EXPECT_EQ(c.size(), std::stoul(f.at(4)));
    EXPECT_EQ(c.normals.size(), c.size());
    double zmin = 1e300;
    for (const Point3& p : c.points) zmin = std::min(zmin, p.z);
    EXPECT_NEAR(zmin, std::stod(f.at(11)), 1e-5);
    ++files;
  }
  EXPECT_EQ(files, 10);
}

TEST(PlyReader, reads_first_smoke_point_and_normal_exactly) {
  const std::string path = CITY3D_SHARED_DATA "/city3d_smoke/AHN3/00295.ply";
  const PointCloud c = read_point_cloud(path);
  ASSERT_EQ(c.size(), 475u);
  EXPECT_EQ(c.points[0].x, -2490.0703125);
  EXPECT_EQ(c.points[0].y, -2104.78125);
  EXPECT_EQ(c.points[0].z, static_cast<double>(8.552f));
  EXPECT_EQ(c.normals[0][0], 0.54261744f);
  EXPECT_EQ(c.normals[0][2], 0.80109513f);
  const PointCloudInfo info = read_point_cloud_info(path);
  EXPECT_EQ(info.format, "PLY");
  EXPECT_EQ(info.version, "binary_little_endian");
  EXPECT_EQ(info.point_count, 475u);
  EXPECT_EQ(info.fields, kFieldNormal);
  EXPECT_TRUE(c.classification.empty());
}

TEST(PlyReader, reads_ascii_with_faces_before_and_edges_after_the_vertices) {
  const std::string path = kTestPly + "ascii_faces_first.ply";
  const PointCloud c = read_point_cloud(path);
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c.points[0].x, static_cast<double>(1.5f));
  EXPECT_EQ(c.points[0].y, 2.5);
  EXPECT_EQ(c.points[0].z, 3.5);  // 'quality' between y and z is skipped
  EXPECT_EQ(c.points[1].z, -3.0);
  EXPECT_EQ(c.points[2].x, 1000.0);
  EXPECT_EQ(c.points[2].y, 2e-3);
  EXPECT_EQ(c.classification, (std::vector<std::uint8_t>{6, 2, 26}));
  EXPECT_EQ(c.rgb[0], (std::array<std::uint16_t, 3>{255, 128, 0}));
  EXPECT_EQ(c.intensity, (std::vector<std::uint16_t>{1000, 65535, 0}));
  EXPECT_TRUE(c.normals.empty());
  EXPECT_EQ(read_point_cloud_info(path).version, "ascii");
}

TEST(PlyReader, reads_big_endian_double_coordinates_exactly) {
  const PointCloud c = read_point_cloud(kTestPly + "big_endian_double.ply");
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.points[0].x, 84916.949);
  EXPECT_EQ(c.points[0].y, 447413.300);
  EXPECT_EQ(c.points[0].z, 5.977);
  EXPECT_EQ(c.points[1].x, 84808.3);
  EXPECT_EQ(c.points[1].z, -0.568);
  EXPECT_EQ(c.normals[1][0], 0.5f);
  EXPECT_EQ(c.normals[1][2], 0.70710677f);
  EXPECT_EQ(c.classification, (std::vector<std::uint8_t>{6, 2}));  // 'label'
  EXPECT_EQ(c.rgb[0], (std::array<std::uint16_t, 3>{65535, 0, 257}));
}

TEST(PlyReader, reads_type_aliases_and_scalar_field_names) {
  const PointCloud c = read_point_cloud(kTestPly + "little_endian_scalar_fields.ply");
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.points[0].z, 100.125);
  EXPECT_EQ(c.points[1].z, -3e-3);
  EXPECT_EQ(c.classification, (std::vector<std::uint8_t>{9, 1}));
  EXPECT_EQ(c.intensity, (std::vector<std::uint16_t>{17, 65535}));
}

// CloudCompare writes its scalar fields capitalised (scalar_Classification, scalar_Intensity), some
// writers X, Y, Z: the classes were ignored, and every point in a footprint taken for a building point.
TEST(PlyReader, reads_property_names_in_any_case) {
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "city3d_ply_capitalised.ply";
  std::ofstream(file)
      << "ply\nformat ascii 1.0\nelement vertex 2\nproperty double X\nproperty double Y\n"
         "property double Z\nproperty float scalar_Classification\nproperty float scalar_Intensity\n"
         "end_header\n1 2 3 6 40\n4 5 6 2 50\n";
  const PointCloud c = read_point_cloud(file.string());
  std::filesystem::remove(file);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.points[1].x, 4.0);
  EXPECT_EQ(c.points[1].z, 6.0);
  EXPECT_EQ(c.classification, (std::vector<std::uint8_t>{6, 2}));
  EXPECT_EQ(c.intensity, (std::vector<std::uint16_t>{40, 50}));
}

TEST(PlyReader, streams_one_vertex_at_a_time) {
  auto reader = open_point_cloud(kTestPly + "ascii_faces_first.ply", kFieldClassification);
  PointCloud c;
  EXPECT_EQ(reader->read(c, 1), 1u);
  EXPECT_EQ(reader->read(c, 1), 1u);
  EXPECT_EQ(reader->read(c, 5), 1u);
  EXPECT_EQ(reader->read(c, 5), 0u);
  EXPECT_EQ(c.classification, (std::vector<std::uint8_t>{6, 2, 26}));
  EXPECT_TRUE(c.rgb.empty());  // not requested
}

TEST(PlyReader, rejects_file_without_vertex_element) {
  expect_contains(read_error(kTestPly + "broken/no_vertex_element.ply"),
                  {"ply: ", "no_vertex_element.ply", "has no vertex element"});
}

TEST(PlyReader, rejects_list_property_on_vertices) {
  expect_contains(read_error(kTestPly + "broken/vertex_list_property.ply"),
                  {"vertex_list_property.ply", "vertex property 'weights' is a list"});
}

TEST(PlyReader, rejects_nan_coordinates_naming_the_vertex) {
  expect_contains(read_error(kTestPly + "broken/nan_coordinate.ply"),
                  {"nan_coordinate.ply", "vertex 2", "non-finite coordinate"});
}

TEST(PlyReader, rejects_truncated_body_naming_the_last_vertex) {
  expect_contains(read_error(kTestPly + "broken/truncated_body.ply"),
                  {"ply: ", "truncated_body.ply", "ends after vertex 2 of 5"});
}

TEST(PlyReader, rejects_missing_z_non_numeric_values_and_missing_format) {
  expect_contains(read_error(kTestPly + "broken/missing_z.ply"), {"missing_z.ply", "no 'z' property"});
  expect_contains(read_error(kTestPly + "broken/non_numeric.ply"),
                  {"non_numeric.ply", "vertex 1 property 'y'", "'abc' is not a number"});
  expect_contains(read_error(kTestPly + "broken/no_format_line.ply"), {"no_format_line.ply", "no format line"});
}

// ---------------------------------------------------------------------------------------------
// PointCloud

TEST(PointCloud, append_keeps_attributes_both_clouds_have_and_drops_the_others) {
  PointCloud a;
  a.points = {{1, 2, 3}};
  a.classification = {6};
  a.intensity = {10};
  PointCloud b;
  b.points = {{4, 5, 6}, {7, 8, 9}};
  b.classification = {2, 9};
  a.append(b);
  ASSERT_EQ(a.size(), 3u);
  EXPECT_EQ(a.points[2].z, 9.0);
  EXPECT_EQ(a.classification, (std::vector<std::uint8_t>{6, 2, 9}));
  EXPECT_TRUE(a.intensity.empty());
  PointCloud empty;
  empty.append(b);
  EXPECT_EQ(empty.classification, b.classification);
  empty.clear();
  EXPECT_TRUE(empty.empty());
  EXPECT_TRUE(empty.classification.empty());
}

}  // namespace
}  // namespace city3d
