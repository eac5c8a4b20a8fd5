// The bad-input corpus (issue 14): every case of tests/bad_inputs/manifest.toml is run through the
// `city3d` executable and checked for its exit code, its message, its wall time and (optionally) its
// report. Files too big or too derived for git are made here, at test time, into each case's own
// temporary folder (the generators below; the manifest names them as {gen:NAME}).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <toml++/toml.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "city3d/point_cloud_io.hpp"
#include "las_writer.hpp"

namespace fs = std::filesystem;
using city3d::test::LasPoint;
using city3d::test::LasWriteOptions;

namespace {

const std::string kCorpus = std::string(CITY3D_TEST_DATA) + "/../bad_inputs";
const std::string kShared = CITY3D_SHARED_DATA;

struct Case {
  std::string name, args, message, report, known;
  std::vector<std::string> absent;  ///< paths (with placeholders) that must not exist after the run
  int exit_code = 0;
  double seconds = 10;
};

std::vector<Case> load_manifest() {
  std::vector<Case> cases;
  const toml::table manifest = toml::parse_file(kCorpus + "/manifest.toml");
  const toml::array* rows = manifest["case"].as_array();
  if (rows == nullptr) throw std::runtime_error("bad_inputs/manifest.toml has no [[case]]");
  for (const toml::node& row : *rows) {
    const toml::table& t = *row.as_table();
    Case c;
    c.name = t["name"].value_or(std::string());
    c.args = t["args"].value_or(std::string());
    c.message = t["message"].value_or(std::string());
    c.report = t["report"].value_or(std::string());
    c.known = t["known"].value_or(std::string());
    if (const toml::array* absent = t["absent"].as_array())
      for (const toml::node& path : *absent) c.absent.push_back(path.value_or(std::string()));
    c.exit_code = static_cast<int>(t["exit"].value_or(std::int64_t{-1}));
    c.seconds = t["seconds"].value_or(10.0);
    if (c.name.empty() || c.args.empty() || c.message.empty() || c.exit_code < 0)
      throw std::runtime_error("bad_inputs/manifest.toml: case '" + c.name + "' needs name, args, exit and message");
    cases.push_back(c);
  }
  return cases;
}

std::vector<LasPoint> grid(int n, double z, std::uint8_t cls) {
  std::vector<LasPoint> points;
  for (int i = 0; i < n; ++i) points.push_back({85000.0 + (i % 10) * 0.5, 447550.0 + (i / 10) * 0.5, z, cls});
  return points;
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void write_text(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

void write_bytes(const fs::path& p, const std::vector<std::uint8_t>& bytes) {
  std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()),
                                          static_cast<std::streamsize>(bytes.size()));
}

std::string ply_ascii(const std::vector<std::array<double, 3>>& points, const std::string& count = "") {
  std::ostringstream out;
  out << "ply\nformat ascii 1.0\nelement vertex " << (count.empty() ? std::to_string(points.size()) : count)
      << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  for (const auto& p : points) out << p[0] << ' ' << p[1] << ' ' << p[2] << '\n';
  return out.str();
}

std::vector<LasPoint> sample_points(const std::string& path) {
  const city3d::PointCloud cloud = city3d::read_point_cloud(path, city3d::kFieldClassification);
  std::vector<LasPoint> points;
  for (std::size_t i = 0; i < cloud.size(); ++i)
    points.push_back({cloud.points[i].x, cloud.points[i].y, cloud.points[i].z, cloud.classification[i]});
  return points;
}

/// The sample block's reconstruction into `out` (what a finished earlier run leaves), with `extra`
/// options.
void sample_run(const fs::path& out, const std::string& extra = "") {
  const std::string d = CITY3D_SAMPLE_DATA;
  const std::string command = std::string(CITY3D_EXE) + " reconstruct " + d + "/delft_sample_1.las " + d +
                              "/delft_sample_2.las -f " + d + "/delft_sample_footprints.gpkg --id-field gml_id " +
                              extra + " -q --no-progress -o " + out.string() + " > /dev/null 2>&1";
  if (std::system(command.c_str()) != 0) throw std::runtime_error("test: the earlier run failed: " + command);
}

/// The generators: each makes its file (or folder) in `dir` and returns its path.
const std::map<std::string, std::function<fs::path(const fs::path&)>>& generators() {
  static const std::map<std::string, std::function<fs::path(const fs::path&)>> g = {
      {"las_giant_point_count",
       [](const fs::path& dir) {
         LasWriteOptions o;
         o.claimed_count = 0xFFFFFFFFu;  // 4.3 G points of 28 bytes: 120 GB claimed by a 1.6 KB file
         write_las((dir / "giant_point_count.las").string(), grid(50, 5, 6), o);
         return dir / "giant_point_count.las";
       }},
      {"las_giant_vlr_length",
       [](const fs::path& dir) {
         LasWriteOptions o;
         o.epsg = 28992;
         o.claimed_vlr_length = 65535;
         write_las((dir / "giant_vlr_length.las").string(), grid(50, 5, 6), o);
         return dir / "giant_vlr_length.las";
       }},
      {"las_truncated_points",
       [](const fs::path& dir) {
         std::vector<std::uint8_t> bytes = city3d::test::las_bytes(grid(100, 5, 6));
         bytes.resize(227 + 50 * 28 + 13);  // half the records and a piece of one
         write_bytes(dir / "truncated_points.las", bytes);
         return dir / "truncated_points.las";
       }},
      {"las_nan_scale",
       [](const fs::path& dir) {
         std::vector<std::uint8_t> bytes = city3d::test::las_bytes(grid(10, 5, 6));
         const double nan = std::numeric_limits<double>::quiet_NaN();
         std::memcpy(bytes.data() + 131, &nan, 8);  // scale x
         write_bytes(dir / "nan_scale.las", bytes);
         return dir / "nan_scale.las";
       }},
      {"las_inf_offset",
       [](const fs::path& dir) {
         std::vector<std::uint8_t> bytes = city3d::test::las_bytes(grid(10, 5, 6));
         const double inf = std::numeric_limits<double>::infinity();
         std::memcpy(bytes.data() + 163, &inf, 8);  // offset y
         write_bytes(dir / "inf_offset.las", bytes);
         return dir / "inf_offset.las";
       }},
      {"las_200k_equal_points",
       [](const fs::path& dir) {
         write_las((dir / "equal_points_200k.las").string(),
                   std::vector<LasPoint>(200000, LasPoint{85000.0, 447550.0, 7.0, 6}));
         return dir / "equal_points_200k.las";
       }},
      {"las_declaring_4326",
       [](const fs::path& dir) {
         LasWriteOptions o;
         o.epsg = 4326;
         o.geographic = true;
         write_las((dir / "declares_4326.las").string(), sample_points(std::string(CITY3D_SAMPLE_DATA) + "/delft_sample_1.las"), o);
         return dir / "declares_4326.las";
       }},
      {"ply_inf_coordinate",
       [](const fs::path& dir) {
         write_text(dir / "inf_coordinate.ply",
                    "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                    "end_header\n1 2 3\n1 2 inf\n");
         return dir / "inf_coordinate.ply";
       }},
      {"ply_giant_vertex_count",
       [](const fs::path& dir) {
         write_text(dir / "giant_vertex_count.ply", ply_ascii({{1, 2, 3}, {4, 5, 6}, {7, 8, 9}}, "1000000000000"));
         return dir / "giant_vertex_count.ply";
       }},
      {"ply_empty_element_of_1e11_items",
       [](const fs::path& dir) {
         write_text(dir / "empty_element.ply",
                    "ply\nformat ascii 1.0\nelement face 100000000000\nelement vertex 1\nproperty float x\n"
                    "property float y\nproperty float z\nend_header\n1 2 3\n");
         return dir / "empty_element.ply";
       }},
      {"cloud_zero_points",
       [](const fs::path& dir) {
         write_text(dir / "zero_points.ply", ply_ascii({}));
         return dir / "zero_points.ply";
       }},
      {"cloud_one_point",
       [](const fs::path& dir) {
         write_text(dir / "one_point.ply", ply_ascii({{10, 20, 5}}));
         return dir / "one_point.ply";
       }},
      {"cloud_collinear",
       [](const fs::path& dir) {
         std::vector<std::array<double, 3>> points;
         for (int i = 0; i < 500; ++i) points.push_back({i * 0.1, i * 0.2, i * 0.01});
         write_text(dir / "collinear.ply", ply_ascii(points));
         return dir / "collinear.ply";
       }},
      {"cloud_all_equal",
       [](const fs::path& dir) {
         write_text(dir / "all_equal.ply", ply_ascii(std::vector<std::array<double, 3>>(500, {5, 5, 5})));
         return dir / "all_equal.ply";
       }},
      {"cloud_flat_square",
       [](const fs::path& dir) {
         std::vector<std::array<double, 3>> points;
         for (int i = 0; i < 50; ++i)
           for (int k = 0; k < 50; ++k) points.push_back({i * 0.2, k * 0.2, 3.0});
         write_text(dir / "flat_square.ply", ply_ascii(points));
         return dir / "flat_square.ply";
       }},
      {"footprints_wgs84",
       [](const fs::path& dir) {
         const fs::path out = dir / "footprints_wgs84.geojson";
         const std::string command = "ogr2ogr -f GeoJSON -t_srs EPSG:4326 " + out.string() + " " +
                                     CITY3D_SAMPLE_DATA + "/delft_sample_footprints.gpkg 2>&1";
         if (std::system(command.c_str()) != 0) throw std::runtime_error("ogr2ogr failed: " + command);
         return out;
       }},
      {"footprint_circle_100000_vertices",
       [](const fs::path& dir) {
         // A circle of radius 9 m over a building of the sample block, as 100,000 vertices.
         std::ostringstream g;
         g.precision(12);
         g << "{\"type\":\"FeatureCollection\",\"features\":[{\"type\":\"Feature\",\"properties\":{\"id\":"
              "\"circle_100000\"},\"geometry\":{\"type\":\"Polygon\",\"coordinates\":[[";
         constexpr int n = 100000;
         for (int i = 0; i <= n; ++i) {
           const double a = 2.0 * M_PI * (i % n) / n;
           g << (i ? "," : "") << "[" << 84985.0 + 9.0 * std::cos(a) << "," << 447560.0 + 9.0 * std::sin(a) << "]";
         }
         g << "]]}}]}";
         write_text(dir / "circle_100000.geojson", g.str());
         return dir / "circle_100000.geojson";
       }},
      {"footprint_of_1e15_metres",
       [](const fs::path& dir) {
         write_text(dir / "huge.geojson",
                    "{\"type\":\"FeatureCollection\",\"features\":[{\"type\":\"Feature\",\"properties\":{\"id\":"
                    "\"huge\"},\"geometry\":{\"type\":\"Polygon\",\"coordinates\":[[[-1e15,-1e15],[1e15,-1e15],"
                    "[1e15,1e15],[-1e15,1e15],[-1e15,-1e15]]]}}]}");
         return dir / "huge.geojson";
       }},
      {"footprint_over_the_whole_delft_block",
       [](const fs::path& dir) {
         write_text(dir / "whole_block.geojson",
                    "{\"type\":\"FeatureCollection\",\"features\":[{\"type\":\"Feature\",\"properties\":{\"id\":"
                    "\"whole_block\"},\"geometry\":{\"type\":\"Polygon\",\"coordinates\":[[[84810,447415],"
                    "[85070,447415],[85070,447640],[84810,447640],[84810,447415]]]}}]}");
         return dir / "whole_block.geojson";
       }},
      {"output_with_damaged_journal",
       [](const fs::path& dir) {
         // One changed digit inside the third line's record (issue 14 item 4).
         sample_run(dir / "out");
         std::string journal = read_file(dir / "out" / "resume.journal");
         std::size_t line = journal.find('\n', journal.find('\n') + 1) + 1;
         const std::size_t at = journal.find_first_of("123456789", journal.find("\"csv\"", line));
         journal[at] = journal[at] == '9' ? '8' : static_cast<char>(journal[at] + 1);
         write_text(dir / "out" / "resume.journal", journal);
         return dir / "out";
       }},
      {"output_with_temporary_files_of_a_killed_run",
       [](const fs::path& dir) {
         sample_run(dir / "out");
         write_text(dir / "out" / "buildings.city.jsonl.tmp-99999-0", "{\"type\":\"CityJSON\"");
         write_text(dir / "out" / "models" / "b31be49eb-00ba-11e6-b420-2bdcc4ab5d7f.obj.tmp-99999-1", "v 0 0");
         return dir / "out";
       }},
      {"output_of_an_earlier_run_with_more_buildings",
       [](const fs::path& dir) {
         sample_run(dir / "out");
         return dir / "out";
       }},
      {"two_clouds_of_identical_bytes",
       [](const fs::path& dir) {
         // A gable roof of 10 x 8 m (eaves 5 m, ridge 8 m along x), points every 0.25 m, twice.
         std::vector<std::array<double, 3>> points;
         for (int i = 0; i <= 40; ++i)
           for (int k = 0; k <= 32; ++k) {
             const double y = k * 0.25;
             points.push_back({i * 0.25, y, 8.0 - 3.0 * std::abs(y - 4.0) / 4.0});
           }
         fs::create_directories(dir / "clouds");
         write_text(dir / "clouds" / "a.ply", ply_ascii(points));
         write_text(dir / "clouds" / "b.ply", ply_ascii(points));
         return dir / "clouds";
       }},
      {"sample_tile_without_building_class",
       [](const fs::path& dir) {
         // data/delft_sample_1.las with its building points (class 6) made unclassified (1).
         std::vector<LasPoint> points = sample_points(std::string(CITY3D_SAMPLE_DATA) + "/delft_sample_1.las");
         for (LasPoint& p : points)
           if (p.classification == 6) p.classification = 1;
         write_las((dir / "no_building_class.las").string(), points);
         return dir / "no_building_class.las";
       }},
      {"plain_file",
       [](const fs::path& dir) {
         write_text(dir / "plain_file", "not a folder\n");
         return dir / "plain_file";
       }},
      {"folder_with_models_file",
       [](const fs::path& dir) {
         fs::create_directories(dir / "with_models_file");
         write_text(dir / "with_models_file" / "models", "not a folder\n");
         return dir / "with_models_file";
       }},
  };
  return g;
}

void replace_all(std::string& s, const std::string& from, const std::string& to) {
  for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
    s.replace(at, from.size(), to);
}


// gtest prints a case by its name, not as bytes.
void PrintTo(const Case& c, std::ostream* out) { *out << c.name; }

class BadInput : public ::testing::TestWithParam<Case> {};

TEST_P(BadInput, exits_with_its_code_and_message_within_its_time) {
  const Case& c = GetParam();
  if (!c.known.empty()) GTEST_SKIP() << "known problem, not fixed yet: " << c.known;
  std::string args = c.args;
  if (args.find("{shared}") != std::string::npos && !fs::exists(kShared))
    GTEST_SKIP() << "../shared/data is not beside the repository";
  const fs::path tmp = fs::temp_directory_path() / ("city3d_bad_input_" + c.name);
  fs::remove_all(tmp);
  fs::create_directories(tmp);
  // {gen:NAME} -> a file made now.
  for (std::size_t at = args.find("{gen:"); at != std::string::npos; at = args.find("{gen:")) {
    const std::size_t end = args.find('}', at);
    const std::string name = args.substr(at + 5, end - at - 5);
    const auto g = generators().find(name);
    ASSERT_NE(g, generators().end()) << "no generator '" << name << "' (tests/test_bad_inputs.cpp)";
    args.replace(at, end - at + 1, g->second(tmp).string());
  }
  replace_all(args, "{data}", CITY3D_SAMPLE_DATA);
  replace_all(args, "{test_data}", CITY3D_TEST_DATA);
  replace_all(args, "{corpus}", kCorpus);
  replace_all(args, "{shared}", kShared);
  replace_all(args, "{tmp}", tmp.string());

  // A runaway is killed at three times its bound, so the suite itself never hangs.
  const int kill_after = static_cast<int>(std::ceil(c.seconds * 3 + 10));
  const std::string command = "cd " + tmp.string() + " && timeout -k 5 " + std::to_string(kill_after) + " " +
                              CITY3D_EXE + " " + args + " --no-progress 2>&1";
  const auto start = std::chrono::steady_clock::now();
  std::string output;
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) output.append(buf.data(), n);
  const int status = pclose(pipe);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const int exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;

  EXPECT_NE(exit_code, 3) << "internal error on a bad input: " << args << "\n" << output;
  EXPECT_NE(exit_code, 124) << "killed after " << kill_after << " s: " << args;
  EXPECT_EQ(exit_code, c.exit_code) << args << "\n" << output;
  EXPECT_TRUE(std::regex_search(output, std::regex(c.message))) << "message /" << c.message << "/ not in:\n" << output;
  EXPECT_LE(seconds, c.seconds) << args;
  if (!c.report.empty()) {
    const std::string report = read_file(tmp / "out" / "report.csv");
    EXPECT_TRUE(std::regex_search(report, std::regex(c.report))) << "report /" << c.report << "/ not in:\n" << report;
  }
  for (std::string path : c.absent) {
    replace_all(path, "{tmp}", tmp.string());
    EXPECT_FALSE(fs::exists(path)) << path << " should not exist after the run";
  }
  if (!HasFailure()) fs::remove_all(tmp);
}

INSTANTIATE_TEST_SUITE_P(Corpus, BadInput, ::testing::ValuesIn(load_manifest()),
                         [](const ::testing::TestParamInfo<Case>& info) { return info.param.name; });

TEST(BadInputManifest, no_case_expects_an_internal_error_and_names_are_unique) {
  std::set<std::string> names;
  for (const Case& c : load_manifest()) {
    EXPECT_NE(c.exit_code, 3) << c.name;
    EXPECT_TRUE(names.insert(c.name).second) << "duplicate case " << c.name;
    EXPECT_NO_THROW(std::regex(c.message)) << c.name;
  }
  EXPECT_GE(names.size(), 50u);
}

}  // namespace
