// End-to-end tests of the `city3d` executable: options, help, exit codes and the info command on
// real data. Also pins the defaults of the option table so that a change is deliberate.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>
#include <string>

#include "city3d/error.hpp"
#include "city3d/options.hpp"
#include "city3d/point_cloud_io.hpp"
#include "cli/option_table.hpp"
#include "las_writer.hpp"
#include "batch/journal.hpp"

namespace fs = std::filesystem;

namespace {

struct Result {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// Runs a shell command, capturing stdout and stderr together.
Result run_shell(const std::string& command_line) {
  const std::string command = command_line + " 2>&1";
  Result r;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

Result run(const std::string& arguments) { return run_shell(std::string(CITY3D_EXE) + " " + arguments); }

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

const std::string kShared = CITY3D_SHARED_DATA;
const std::string kTile1 = kShared + "/ahn3_delft/ahn3_cropped_1.las";
const std::string kGpkg = kShared + "/ahn3_delft/footprints/bgt_pand_laz_area.gpkg";

void require_shared_data() {
  if (!fs::exists(kTile1)) GTEST_SKIP() << "../shared/data is not beside the repository";
}

}  // namespace

TEST(CommandLine, defaults_are_pinned) {
  const char* argv[] = {"city3d", "info", "x.las"};
  const city3d::RunOptions o = city3d::parse_command_line(3, argv);
  EXPECT_EQ(o.command, "info");
  ASSERT_EQ(o.inputs.size(), 1u);
  EXPECT_EQ(o.batch.output_dir, "city3d_out");
  EXPECT_EQ(o.format, "obj");
  EXPECT_EQ(o.batch.format, city3d::MeshFormat::obj);
  EXPECT_FALSE(o.batch.local_coordinates);
  EXPECT_TRUE(o.batch.footprint.id_field.empty());
  EXPECT_TRUE(o.batch.footprint.repair);
  EXPECT_EQ(o.batch.crop.building_classes, std::vector<std::uint8_t>{6});
  EXPECT_EQ(o.batch.crop.ground_class, 2);
  EXPECT_DOUBLE_EQ(o.batch.crop.ground_buffer, 3.0);
  EXPECT_DOUBLE_EQ(o.batch.crop.ground_percentile, 10.0);
  EXPECT_DOUBLE_EQ(o.batch.reconstruction.lod1.roof_percentile, 70.0);
  EXPECT_EQ(o.batch.threads, 1);
  EXPECT_TRUE(o.batch.per_building_files);
  EXPECT_TRUE(o.batch.cityjson);
  EXPECT_FALSE(o.batch.cityjson_seq);
  EXPECT_FALSE(o.strict);
  EXPECT_DOUBLE_EQ(o.batch.min_coverage, 0.95);  // issue 24: partial below 95% of a footprint's area in the tiles
  EXPECT_EQ(o.verbosity, 1);
  EXPECT_TRUE(o.batch.crs.empty());  // issue 25: the point clouds' CRS, else the footprints' (with a warning)
  EXPECT_FALSE(o.batch.gpkg);
  EXPECT_FALSE(o.batch.tiles3d);
}

// Issue 25: the parameters the outputs' metadata records are typed as --print-config types them, and
// leave out what does not change the outputs and the inputs (recorded apart).
TEST(CommandLine, run_parameters_are_typed_and_leave_out_what_does_not_change_the_outputs) {
  const char* argv[] = {"city3d", "reconstruct", "x.las", "-j", "4", "-o", "elsewhere", "--lambda-data", "0.5",
                        "--gpkg", "--crs", "EPSG:28992+5709", "--id-field", "gml_id", "--block-size", "100"};
  const city3d::RunOptions o = city3d::parse_command_line(16, argv);
  const nlohmann::json p = nlohmann::json::parse(city3d::run_parameters_json(o));
  EXPECT_EQ(p["lambda-data"], 0.5);
  EXPECT_EQ(p["min-points"], 20);
  EXPECT_EQ(p["gpkg"], true);
  EXPECT_EQ(p["3dtiles"], false);
  EXPECT_EQ(p["crs"], "EPSG:28992+5709");
  EXPECT_EQ(p["lod"], nlohmann::json({"1.2", "1.3", "2.2"}));
  EXPECT_EQ(p["building-classes"], nlohmann::json({6}));
  EXPECT_TRUE(p["where"].is_null());
  for (const char* left_out : {"jobs", "output", "block-size", "group-area", "shard", "id-field", "footprints", "layer",
                               "debug", "verbose", "quiet", "progress", "no-progress", "strict", "residuals", "config"})
    EXPECT_FALSE(p.contains(left_out)) << left_out;
  // The same parameters whatever -j, -o and the block size.
  const char* other[] = {"city3d", "reconstruct", "x.las", "--lambda-data", "0.5", "--gpkg", "--crs", "EPSG:28992+5709"};
  EXPECT_EQ(city3d::run_parameters_json(city3d::parse_command_line(8, other)), city3d::run_parameters_json(o));
}

TEST(CommandLine, collects_every_problem_in_one_error) {
  const char* argv[] = {"city3d", "info", "--frobnicate", "--bbox", "1,2,3", "--format", "stl"};
  try {
    city3d::parse_command_line(7, argv);
    FAIL() << "no exception";
  } catch (const city3d::ConfigError& e) {
    const std::string m = e.what();
    EXPECT_TRUE(contains(m, "unknown option '--frobnicate'")) << m;
    EXPECT_TRUE(contains(m, "--bbox")) << m;
    EXPECT_TRUE(contains(m, "'stl'")) << m;
  }
}

TEST(CommandLine, accepts_inline_values_and_parses_bbox) {
  const char* argv[] = {"city3d", "info", "--bbox=1,2,3,4", "--id-field", "gml_id", "f.gpkg", "-j3", "-oout"};
  const city3d::RunOptions o = city3d::parse_command_line(8, argv);
  EXPECT_EQ(o.batch.threads, 3);
  EXPECT_EQ(o.batch.output_dir, "out");
  ASSERT_TRUE(o.batch.footprint.bbox.has_value());
  EXPECT_DOUBLE_EQ(o.batch.footprint.bbox->min.x, 1.0);
  EXPECT_DOUBLE_EQ(o.batch.footprint.bbox->max.y, 4.0);
  EXPECT_EQ(o.batch.footprint.id_field, "gml_id");
}

TEST(Executable, help_lists_every_option_with_its_default_and_the_exit_codes) {
  const Result r = run("--help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* flag :
       {"--footprints", "--layer", "--id-field", "--where", "--bbox", "--no-repair", "--building-classes",
        "--ground-class", "--ignore-classes", "--ground-buffer", "--ground-percentile", "--ground-z",
        "--roof-percentile", "--output", "--format", "--no-model-files", "--merged", "--no-cityjson", "--cityjsonseq",
        "--timings", "--local-coordinates", "--jobs", "--strict", "--progress", "--no-progress", "--verbose",
        "--quiet", "--help", "--version", "--config", "--print-config", "--crs", "--gpkg", "--3dtiles"})
    EXPECT_TRUE(contains(r.output, flag)) << flag;
  EXPECT_TRUE(contains(r.output, "[default: city3d_out]"));
  EXPECT_TRUE(contains(r.output, "[default: obj]"));
  EXPECT_TRUE(contains(r.output, "[default: 6]"));
  EXPECT_TRUE(contains(r.output, "[default: 70]"));
  EXPECT_TRUE(contains(r.output, "exit codes:"));
}

TEST(Executable, prints_its_version) {
  const Result r = run("--version");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.output, std::string("city3d ") + CITY3D_VERSION + "\n");
}

TEST(Executable, rejects_unknown_option_with_usage_exit_code) {
  const Result r = run("info --no-such-option x.las");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(contains(r.output, "unknown option '--no-such-option'")) << r.output;
}

TEST(Executable, rejects_unknown_command) {
  const Result r = run("frobnicate");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(contains(r.output, "unknown command 'frobnicate'")) << r.output;
}

TEST(Executable, info_reports_ahn3_tile_count_bounds_and_classes) {
  require_shared_data();
  const Result r = run("info " + kTile1);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "format: LAS 1.2, point format 1, record length 28")) << r.output;
  EXPECT_TRUE(contains(r.output, "points: 640510\n")) << r.output;
  EXPECT_TRUE(contains(r.output, "bounds: x 84808.300 .. 84999.999, y 447412.800 .. 447641.299")) << r.output;
  EXPECT_TRUE(contains(r.output, "  1 unclassified: 196137\n")) << r.output;
  EXPECT_TRUE(contains(r.output, "  2 ground: 195988\n")) << r.output;
  EXPECT_TRUE(contains(r.output, "  6 building: 246753\n")) << r.output;
  EXPECT_TRUE(contains(r.output, "  9 water: 267\n")) << r.output;
  EXPECT_TRUE(contains(r.output, "  26 user defined (AHN: civil structure): 1365\n")) << r.output;
  EXPECT_TRUE(contains(r.output, "crs: none recorded")) << r.output;
}

TEST(Executable, info_reports_the_sample_tile_in_data) {
  const Result r = run(std::string("info ") + CITY3D_SAMPLE_DATA + "/delft_sample_1.las");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // scripts/make_sample.py printed "40957 of 640510 points" when it made the file.
  EXPECT_TRUE(contains(r.output, "points: 40957\n")) << r.output;
}

TEST(Executable, info_reports_footprint_source_layer_count_holes_and_srs) {
  require_shared_data();
  const Result r = run("info " + kGpkg);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "driver: GPKG\n")) << r.output;
  EXPECT_TRUE(contains(r.output, "layer: buildingpart\n")) << r.output;
  EXPECT_TRUE(contains(r.output, "footprints: 160\n")) << r.output;
  EXPECT_TRUE(contains(r.output, "id field: FID\n")) << r.output;
  EXPECT_TRUE(contains(r.output, "srs: EPSG:28992\n")) << r.output;
  EXPECT_TRUE(contains(r.output, "with holes: 1\n")) << r.output;
  EXPECT_TRUE(contains(r.output, "rings touching: 0 ")) << r.output;
  EXPECT_TRUE(contains(r.output, "vertices doubled or hairline spikes: 0 ")) << r.output;
  EXPECT_TRUE(contains(r.output, "skipped: 0\n")) << r.output;
}

// info counts the footprints a run will change before their stages: a courtyard touching its outer
// ring at a point, and a vertex 0.5 mm after another (each of another footprint).
TEST(Executable, info_counts_touching_rings_and_doubled_vertices) {
  const fs::path path = fs::temp_directory_path() / "city3d_cli_touching.geojson";
  {
    std::ofstream out(path);
    out << R"({"type":"FeatureCollection","features":[)"
        << R"({"type":"Feature","properties":{"id":"courtyard"},"geometry":{"type":"Polygon","coordinates":)"
        << R"([[[0,0],[12,0],[12,10],[0,10],[0,0]],[[6,0],[4,4],[8,4],[6,0]]]}},)"
        << R"({"type":"Feature","properties":{"id":"doubled"},"geometry":{"type":"Polygon","coordinates":)"
        << R"([[[20,0],[30,0],[30.0004,0.0003],[30,10],[20,10],[20,0]]]}},)"
        << R"({"type":"Feature","properties":{"id":"plain"},"geometry":{"type":"Polygon","coordinates":)"
        << R"([[[40,0],[50,0],[50,10],[40,10],[40,0]]]}}]})";
  }
  const Result r = run("info " + path.string());
  fs::remove(path);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "footprints: 3\n")) << r.output;
  EXPECT_TRUE(contains(r.output, "rings touching: 1 (opened by 0.01 m when reconstructed)\n")) << r.output;
  EXPECT_TRUE(contains(r.output, "vertices doubled or hairline spikes: 1 (dropped when reconstructed)\n"))
      << r.output;
}

TEST(Executable, info_on_missing_file_names_it_and_exits_with_input_error) {
  const Result r = run("info /nonexistent/tile_07.las");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(contains(r.output, "/nonexistent/tile_07.las")) << r.output;
}

TEST(Executable, info_on_truncated_las_names_the_file_and_exits_with_input_error) {
  const fs::path dir = fs::temp_directory_path() / "city3d_cli_truncated";
  fs::create_directories(dir);
  const fs::path bad = dir / "truncated.las";
  {
    FILE* f = std::fopen(bad.c_str(), "wb");
    std::fwrite("LASF\0\0\0\0\0\0", 1, 10, f);
    std::fclose(f);
  }
  const Result r = run("info " + bad.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(contains(r.output, "truncated.las")) << r.output;
  EXPECT_TRUE(contains(r.output, "truncated")) << r.output;
  fs::remove_all(dir);
}

TEST(Executable, evaluate_prints_rmse_and_validity_and_writes_every_points_residual) {
  const std::string smoke = kShared + "/city3d_smoke/AHN3/00295";
  if (!fs::exists(smoke + ".ply")) GTEST_SKIP() << "../shared/data is not beside the repository";
  const fs::path csv = fs::temp_directory_path() / "city3d_cli_residuals.csv";
  fs::remove(csv);
  const Result r = run("evaluate " + smoke + ".obj " + smoke + ".ply --residuals " + csv.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "faces: ")) << r.output;
  const std::size_t at = r.output.find("rmse: ");
  ASSERT_NE(at, std::string::npos) << r.output;
  const double printed = std::stod(r.output.substr(at + 6));
  const std::size_t pts = r.output.find("(", r.output.find("points: "));
  const std::size_t count = std::stoul(r.output.substr(pts + 1));
  // The CSV: a header, then x,y,z,distance per point, in the cloud's order; its RMSE is the printed one.
  std::ifstream in(csv);
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  EXPECT_EQ(line, "x,y,z,distance");
  std::size_t rows = 0;
  double sum = 0.0;
  while (std::getline(in, line)) {
    ++rows;
    const double d = std::stod(line.substr(line.rfind(',') + 1));
    EXPECT_GE(d, 0.0);
    sum += d * d;
  }
  EXPECT_EQ(rows, count);
  ASSERT_GT(rows, 0u);
  EXPECT_NEAR(std::sqrt(sum / static_cast<double>(rows)), printed, 1e-3);
  fs::remove(csv);
}

// Issue 23: a hand-made house whose points lie on a flat roof at 5 m, modelled with a blade (its east half
// a plane rising to 15 m): evaluate measures the surface no point supports, and none for the flat model.
TEST(Executable, evaluate_measures_a_blade_that_no_point_supports) {
  const fs::path dir = fs::temp_directory_path() / "city3d_cli_blade";
  fs::remove_all(dir);
  fs::create_directories(dir);
  {
    std::ofstream ply(dir / "points.ply");
    ply << "ply\nformat ascii 1.0\nelement vertex 441\nproperty double x\nproperty double y\nproperty double z\n"
           "end_header\n";
    for (int i = 0; i <= 20; ++i)
      for (int j = 0; j <= 20; ++j) ply << 0.5 * i + 85000 << ' ' << 0.5 * j + 447000 << " 5\n";
    const auto write_obj = [&](const fs::path& path, const std::string& vertices, const std::string& faces) {
      std::ofstream obj(path);
      std::istringstream v(vertices);
      double x, y, z;
      while (v >> x >> y >> z) obj << "v " << x + 85000 << ' ' << y + 447000 << ' ' << z << "\n";
      obj << faces;
    };
    write_obj(dir / "blade.obj", "0 0 0 10 0 0 10 10 0 0 10 0 0 0 5 5 0 5 10 0 15 10 10 15 5 10 5 0 10 5",
              "f 1 4 3 2\nf 5 6 9 10\nf 6 7 8 9\nf 1 2 7 6 5\nf 2 3 8 7\nf 3 4 10 9 8\nf 4 1 5 10\n");
    write_obj(dir / "flat.obj", "0 0 0 10 0 0 10 10 0 0 10 0 0 0 5 10 0 5 10 10 5 0 10 5",
              "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n");
  }
  const auto field = [](const std::string& output, const std::string& name) {
    const std::size_t at = output.find("\n" + name + ": ");
    return at == std::string::npos ? std::nan("") : std::stod(output.substr(at + name.size() + 3));
  };
  const Result blade = run("evaluate " + (dir / "blade.obj").string() + " " + (dir / "points.ply").string());
  ASSERT_EQ(blade.exit_code, 0) << blade.output;
  EXPECT_TRUE(contains(blade.output, "valid: yes")) << blade.output;
  // The blade above 6 m, the two side walls above 6 m and the east wall above 6 m (see test_evaluation).
  EXPECT_NEAR(field(blade.output, "unsupported_area"), 231.1, 7.0) << blade.output;
  EXPECT_GT(field(blade.output, "height_excess"), 9.5) << blade.output;
  EXPECT_NEAR(field(blade.output, "highest_vertex_above_points"), 10.0, 1e-9) << blade.output;
  const Result flat = run("evaluate " + (dir / "flat.obj").string() + " " + (dir / "points.ply").string());
  ASSERT_EQ(flat.exit_code, 0) << flat.output;
  EXPECT_EQ(field(flat.output, "unsupported_area"), 0.0) << flat.output;
  EXPECT_EQ(field(flat.output, "height_excess"), 0.0) << flat.output;
  EXPECT_EQ(field(flat.output, "unpointed_roof_area"), 0.0) << flat.output;
  fs::remove_all(dir);
}

TEST(Executable, residuals_option_belongs_to_evaluate) {
  const Result r = run("info x.las --residuals out.csv");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(contains(r.output, "--residuals")) << r.output;
}

namespace {

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream ss(text);
  for (std::string line; std::getline(ss, line);) lines.push_back(line);
  return lines;
}

// Validates a CityJSON (or, with `feature`, a CityJSONFeature) file against the official 2.0 schemas
// with ajv-cli, which scripts/setup.sh installs into build/tools.
Result validate_cityjson(const fs::path& file, bool feature) {
  const std::string s = CITY3D_SCHEMAS;
  std::string command = std::string(CITY3D_AJV) + " validate --spec=draft7 --strict=false -s " + s +
                        (feature ? "/cityjsonfeature.schema.json" : "/cityjson.schema.json");
  for (const char* r : {"appearance", "cityobjects", "geomprimitives", "geomtemplates", "metadata"})
    command += " -r " + s + "/" + r + ".schema.json";
  command += " -d " + file.string();
  return run_shell(command);
}

class Reconstruct : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("city3d_cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string sample_args() const {
    const std::string d = CITY3D_SAMPLE_DATA;
    return d + "/delft_sample_1.las " + d + "/delft_sample_2.las -f " + d +
           "/delft_sample_footprints.gpkg --id-field gml_id --cityjsonseq --no-progress";
  }
  fs::path dir_;
};

}  // namespace

TEST_F(Reconstruct, sample_block_gives_every_footprint_a_valid_model_and_a_report_row) {
  const Result r = run("reconstruct " + sample_args() + " -o " + (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "15 buildings")) << r.output;
  const auto rows = lines_of(read_file(dir_ / "out" / "report.csv"));
  ASSERT_EQ(rows.size(), 16u);  // header + the 15 footprints of data/delft_sample_footprints.gpkg
  for (std::size_t i = 1; i < rows.size(); ++i) {
    EXPECT_TRUE(contains(rows[i], ",ok,") || contains(rows[i], ",fallback,")) << rows[i];
    EXPECT_TRUE(contains(rows[i], ",1,")) << "model not valid: " << rows[i];
    const std::string id = rows[i].substr(0, rows[i].find(','));
    EXPECT_TRUE(fs::exists(dir_ / "out" / "models" / (id + ".obj"))) << id;
  }
}

// Issue 27: --profile gives each stage's CPU over the run, and the stages add up to the buildings' CPU
// the report gives (the same clocks, a building's time in no stage counted as "other").
TEST_F(Reconstruct, profile_gives_the_cpu_of_each_stage_adding_up_to_the_buildings_cpu) {
  const Result r = run("reconstruct " + sample_args() + " -j 2 --profile -q -o " + (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  double all = -1.0;
  std::size_t stages = 0;
  for (const std::string& line : lines_of(r.output)) {
    std::istringstream in(line);
    std::string tag, name;
    double first = 0.0, rebuilds = 0.0, total = 0.0;
    if (!(in >> tag >> name >> first >> rebuilds >> total) || tag != "profile:") continue;
    EXPECT_NEAR(first + rebuilds, total, 0.002) << line;
    if (name == "all") all = total;
    else ++stages;
  }
  EXPECT_EQ(stages, 16u) << r.output;  // every stage, even those that took no time
  double report = 0.0;
  const auto rows = lines_of(read_file(dir_ / "out" / "report.csv"));
  ASSERT_EQ(rows.size(), 16u);
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const std::string before_seconds = rows[i].substr(0, rows[i].rfind(','));
    report += std::stod(before_seconds.substr(before_seconds.rfind(',') + 1));
  }
  ASSERT_GT(report, 0.0);
  EXPECT_NEAR(all, report, 0.02 * report + 0.01) << r.output;
}

TEST_F(Reconstruct, cityjson_and_cityjsonseq_validate_against_the_official_schemas) {
  if (!fs::exists(CITY3D_SCHEMAS)) GTEST_SKIP() << "../shared/spec is not beside the repository";
  ASSERT_TRUE(fs::exists(CITY3D_AJV)) << "ajv-cli missing: run scripts/setup.sh test";
  const Result r = run("reconstruct " + sample_args() + " -o " + (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Result whole = validate_cityjson(dir_ / "out" / "buildings.city.json", false);
  EXPECT_EQ(whole.exit_code, 0) << whole.output;
  const auto lines = lines_of(read_file(dir_ / "out" / "buildings.city.jsonl"));
  ASSERT_EQ(lines.size(), 16u);  // header line + 15 features
  for (std::size_t i = 1; i < lines.size(); i += 7) {
    const fs::path feature = dir_ / ("feature" + std::to_string(i) + ".json");
    std::ofstream(feature) << lines[i] << "\n";
    const Result v = validate_cityjson(feature, true);
    EXPECT_EQ(v.exit_code, 0) << v.output;
  }
  // The validator must reject a broken file, or this test proves nothing.
  const fs::path broken = dir_ / "broken.city.json";
  std::string text = read_file(dir_ / "out" / "buildings.city.json");
  text.replace(text.find("\"Building\""), 10, "\"Buildin\"");
  std::ofstream(broken) << text;
  EXPECT_NE(validate_cityjson(broken, false).exit_code, 0);
}

TEST_F(Reconstruct, output_is_byte_identical_for_one_and_two_jobs_and_any_block_size) {
  ASSERT_EQ(run("reconstruct " + sample_args() + " -j 1 -o " + (dir_ / "j1").string()).exit_code, 0);
  ASSERT_EQ(run("reconstruct " + sample_args() + " -j 2 -o " + (dir_ / "j2").string()).exit_code, 0);
  // Blocks of 20 m split the sample's 15 footprints into many blocks, each cropped on its own.
  ASSERT_EQ(run("reconstruct " + sample_args() + " -j 2 --block-size 20 -o " + (dir_ / "b20").string()).exit_code, 0);
  for (const char* f : {"buildings.city.json", "buildings.city.jsonl"}) {
    EXPECT_EQ(read_file(dir_ / "j1" / f), read_file(dir_ / "j2" / f)) << f;
    EXPECT_EQ(read_file(dir_ / "j1" / f), read_file(dir_ / "b20" / f)) << f;
  }
  for (const auto& entry : fs::directory_iterator(dir_ / "j1" / "models"))
    EXPECT_EQ(read_file(entry.path()), read_file(dir_ / "j2" / "models" / entry.path().filename())) << entry.path();
}

namespace {

// Faces of an OBJ model that are neither horizontal nor vertical (a slanted roof), by Newell normals.
std::size_t slanted_faces(const fs::path& obj) {
  std::vector<std::array<double, 3>> v;
  std::size_t slanted = 0;
  for (const std::string& line : lines_of(read_file(obj))) {
    std::stringstream ss(line);
    std::string tag;
    ss >> tag;
    if (tag == "v") {
      std::array<double, 3> p{};
      ss >> p[0] >> p[1] >> p[2];
      v.push_back(p);
    } else if (tag == "f") {
      std::vector<std::size_t> face;
      for (std::string index; ss >> index;) face.push_back(std::stoul(index.substr(0, index.find('/'))) - 1);
      double n[3] = {0, 0, 0};
      for (std::size_t k = 0; k < face.size(); ++k) {
        const auto& a = v.at(face[k]);
        const auto& b = v.at(face[(k + 1) % face.size()]);
        n[0] += (a[1] - b[1]) * (a[2] + b[2]);
        n[1] += (a[2] - b[2]) * (a[0] + b[0]);
        n[2] += (a[0] - b[0]) * (a[1] + b[1]);
      }
      const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      if (len > 0 && std::fabs(n[2]) / len > 0.01 && std::fabs(n[2]) / len < 0.99) ++slanted;
    }
  }
  return slanted;
}

}  // namespace

// Issue 13 item 3: --lod chooses the levels CityJSON holds; OBJ/PLY hold one, the highest asked for;
// 1.2 alone makes blocks without trying LoD2.
TEST_F(Reconstruct, lod_option_chooses_the_levels_of_cityjson_and_obj_holds_the_highest) {
  struct Case {
    std::string lods;
    std::vector<std::string> in, out;
    bool slanted_obj;  // the OBJ models are LoD2.2 (slanted roofs), not blocks
    std::string report;
  };
  const std::vector<Case> cases = {
      {"1.2,1.3,2.2", {"1.2", "1.3", "2.2"}, {}, true, ",LoD2.2,"},
      {"1.2,1.3", {"1.2", "1.3"}, {"2.2"}, false, "\"1.2,1.3\",\"1.2,1.3\""},
      {"2.2", {"2.2"}, {"1.2", "1.3"}, true, ",2.2,2.2,"},
      {"1.2", {"1.2"}, {"1.3", "2.2"}, false, ",LoD1.2,"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE("--lod " + c.lods);
    const fs::path out = dir_ / ("lod" + c.lods);
    const Result r = run("reconstruct " + sample_args() + " --no-html --lod " + c.lods + " -o " + out.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::string cityjson = read_file(out / "buildings.city.json");
    for (const std::string& lod : c.in)
      EXPECT_TRUE(contains(cityjson, "{\"type\":\"Solid\",\"lod\":\"" + lod + "\"")) << lod;
    for (const std::string& lod : c.out)
      EXPECT_FALSE(contains(cityjson, "\"lod\":\"" + lod + "\"")) << lod;
    std::size_t slanted = 0;
    for (const auto& entry : fs::directory_iterator(out / "models")) slanted += slanted_faces(entry.path());
    if (c.slanted_obj)
      EXPECT_GT(slanted, 15u);  // the sample's roofs are pitched
    else
      EXPECT_EQ(slanted, 0u);
    const auto rows = lines_of(read_file(out / "report.csv"));
    ASSERT_EQ(rows.size(), 16u);
    for (std::size_t i = 1; i < rows.size(); ++i) EXPECT_TRUE(contains(rows[i], c.report)) << rows[i];
  }
}

TEST_F(Reconstruct, single_building_cloud_without_footprint_gives_one_model) {
  const std::string ply = kShared + "/city3d_smoke/AHN3";
  if (!fs::exists(ply)) GTEST_SKIP() << "../shared/data is not beside the repository";
  std::string first;
  for (const auto& e : fs::directory_iterator(ply))
    if (e.path().extension() == ".ply" && (first.empty() || e.path().string() < first)) first = e.path().string();
  const Result r = run("reconstruct " + first + " --no-progress -o " + (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto rows = lines_of(read_file(dir_ / "out" / "report.csv"));
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[1].substr(0, rows[1].find(',')), fs::path(first).stem().string());
  EXPECT_TRUE(fs::exists(dir_ / "out" / "models" / (fs::path(first).stem().string() + ".obj")));
}

// Clouds without footprints are one pass that the threads share, so a thread takes the largest file
// first (it used to be one pass per cloud: -j 2 ran one cloud at a time). The outputs keep input order.
TEST_F(Reconstruct, single_building_clouds_are_taken_largest_first_and_written_in_input_order) {
  const std::string smoke = kShared + "/city3d_smoke/AHN3/";
  if (!fs::exists(smoke)) GTEST_SKIP() << "../shared/data is not beside the repository";
  const std::vector<std::string> ids = {"00295", "08541", "04160"};  // 12 kB, 4 kB, 25 kB
  ASSERT_GT(fs::file_size(smoke + ids[2] + ".ply"), fs::file_size(smoke + ids[0] + ".ply"));
  ASSERT_GT(fs::file_size(smoke + ids[0] + ".ply"), fs::file_size(smoke + ids[1] + ".ply"));
  std::string clouds;
  for (const std::string& id : ids) clouds += smoke + id + ".ply ";
  const Result r = run("reconstruct " + clouds + "-j 1 --no-progress -o " + (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto rows = lines_of(read_file(dir_ / "out" / "report.csv"));
  ASSERT_EQ(rows.size(), 4u);
  for (std::size_t i = 0; i < ids.size(); ++i)
    EXPECT_EQ(rows[i + 1].substr(0, 6), ids[i] + ",") << rows[i + 1];
  // The journal holds the records in the order they were finished: the largest cloud first.
  const auto journal = lines_of(read_file(dir_ / "out" / "resume.journal"));
  ASSERT_EQ(journal.size(), 4u);  // header + 3 buildings
  for (const auto& [line, id] : {std::pair{1, ids[2]}, std::pair{2, ids[0]}, std::pair{3, ids[1]}})
    EXPECT_TRUE(contains(journal[line], "\"csv\":\"" + id + ","))
        << line << ": " << journal[line].substr(0, 60);
}

TEST_F(Reconstruct, missing_footprint_source_is_an_input_error_naming_it) {
  const std::string d = CITY3D_SAMPLE_DATA;
  const Result r = run("reconstruct " + d + "/delft_sample_1.las -f /nonexistent/bgt.gpkg -o " + dir_.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(contains(r.output, "/nonexistent/bgt.gpkg")) << r.output;
}

TEST_F(Reconstruct, without_inputs_is_a_usage_error) {
  const Result r = run("reconstruct -o " + dir_.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(contains(r.output, "no point-cloud file")) << r.output;
}

TEST_F(Reconstruct, broken_footprints_are_reported_and_never_stop_the_others) {
  const std::string d = CITY3D_SAMPLE_DATA;
  const Result r = run("reconstruct " + d + "/delft_sample_1.las " + d + "/delft_sample_2.las -f " +
                       CITY3D_TEST_DATA + "/footprints/sample_broken.geojson --id-field gml_id --no-progress -o " +
                       (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto rows = lines_of(read_file(dir_ / "out" / "report.csv"));
  ASSERT_EQ(rows.size(), 11u);  // header + 10 features: 5 good ones and 5 broken ones
  auto row_of = [&](const std::string& id) {
    for (const std::string& row : rows)
      if (row.rfind(id + ",", 0) == 0) return row;
    return std::string();
  };
  // The bow-tie's two small triangles get a model (LoD2, or LoD1 when too few points for a plane).
  EXPECT_TRUE(contains(row_of("bowtie"), ",ok,") || contains(row_of("bowtie"), ",fallback,")) << row_of("bowtie");
  EXPECT_TRUE(contains(row_of("bowtie"), "repaired with MakeValid")) << row_of("bowtie");
  EXPECT_TRUE(contains(row_of("empty"), ",skipped,none,footprints,no geometry")) << row_of("empty");
  EXPECT_TRUE(contains(row_of("null_geometry"), ",skipped,none,footprints,no geometry")) << row_of("null_geometry");
  EXPECT_TRUE(contains(row_of("no_points"), ",skipped,none,crop,no building points")) << row_of("no_points");
  std::size_t ok = 0, duplicated = 0;
  for (const std::string& row : rows) {
    ok += contains(row, ",ok,") || contains(row, ",fallback,");
    duplicated += contains(row, "duplicated id");
  }
  EXPECT_EQ(ok, 6u);  // models for the 5 good footprints and the repaired bow-tie
  EXPECT_EQ(duplicated, 1u);
  // A strict run fails on... nothing here: skipped is not failed.
  EXPECT_EQ(run("reconstruct " + d + "/delft_sample_1.las -f " + CITY3D_TEST_DATA +
                "/footprints/sample_broken.geojson --strict --no-progress -o " + (dir_ / "strict").string())
                .exit_code,
            0);
}

TEST_F(Reconstruct, run_killed_halfway_resumes_to_the_same_output) {
  const fs::path whole = dir_ / "whole", resumed = dir_ / "resumed";
  ASSERT_EQ(run("reconstruct " + sample_args() + " -o " + whole.string()).exit_code, 0);
  // A kill in the middle of writing: the journal holds the header, some finished buildings and half
  // a line, the models folder the models of those buildings; no other output exists yet.
  const std::string journal = read_file(whole / "resume.journal");
  const auto lines = lines_of(journal);
  ASSERT_EQ(lines.size(), 16u);  // header + 15 buildings
  std::size_t cut = 0;
  for (int i = 0; i < 7; ++i) cut = journal.find('\n', cut) + 1;  // header + 6 buildings
  fs::create_directories(resumed);
  fs::copy(whole / "models", resumed / "models");
  std::ofstream(resumed / "resume.journal", std::ios::binary) << journal.substr(0, cut + 40);
  const Result r = run("reconstruct " + sample_args() + " -v -o " + resumed.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "resume: 6 finished buildings")) << r.output;
  for (const char* f : {"buildings.city.json", "buildings.city.jsonl"})
    EXPECT_EQ(read_file(whole / f), read_file(resumed / f)) << f;
  for (const auto& entry : fs::directory_iterator(whole / "models"))
    EXPECT_EQ(read_file(entry.path()), read_file(resumed / "models" / entry.path().filename())) << entry.path();
  EXPECT_EQ(lines_of(read_file(resumed / "resume.journal")).size(), 16u);
  // Other parameters: nothing is reused.
  const Result other = run("reconstruct " + sample_args() + " -v --roof-percentile 50 -o " + resumed.string());
  ASSERT_EQ(other.exit_code, 0) << other.output;
  EXPECT_TRUE(contains(other.output, "from another run")) << other.output;
  EXPECT_NE(read_file(whole / "buildings.city.json"), read_file(resumed / "buildings.city.json"));
}

TEST_F(Reconstruct, footprint_attribute_overrides_the_ground_height) {
  // BGT's rel_hoogte (relative height level) is 0 for every footprint of the sample: as a ground
  // field it puts every floor at z = 0 instead of the ground points' 10th percentile (0.13-0.35 m).
  const Result r = run("reconstruct " + sample_args() + " --ground-field rel_hoogte -o " + (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto rows = lines_of(read_file(dir_ / "out" / "report.csv"));
  ASSERT_EQ(rows.size(), 16u);
  for (std::size_t i = 1; i < rows.size(); ++i) EXPECT_TRUE(contains(rows[i], ",0.000,footprint attribute,")) << rows[i];
  const Result bad = run("reconstruct " + sample_args() + " --ground-field no_such_field -o " + (dir_ / "bad").string());
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_TRUE(contains(bad.output, "no field 'no_such_field'")) << bad.output;
}

TEST_F(Reconstruct, debug_option_writes_every_intermediate_result_of_a_building) {
  const std::string ply = kShared + "/city3d_smoke/AHN3/04160.ply";
  if (!fs::exists(ply)) GTEST_SKIP() << "../shared/data is not beside the repository";
  const Result r = run("reconstruct " + ply + " --no-progress --debug " + (dir_ / "debug").string() + " -o " +
                       (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"planes.ply", "heightmap.png", "edges.png", "polylines.obj", "regularised.obj", "walls.obj",
                        "candidates.obj"}) {
    const fs::path file = dir_ / "debug" / "04160" / f;
    ASSERT_TRUE(fs::exists(file)) << file;
    EXPECT_GT(fs::file_size(file), 50u) << file;
  }
  EXPECT_EQ(read_file(dir_ / "debug" / "04160" / "edges.png").substr(1, 3), "PNG");
}

// Issue 14 item 3: an output or debug path the file system refuses is an ordinary user mistake: exit
// 1 with the path and the problem, never exit 3 ("internal error") from a std::filesystem exception.
TEST_F(Reconstruct, unusable_output_or_debug_folder_is_an_input_error_naming_the_path) {
  const std::string d = CITY3D_SAMPLE_DATA;
  const std::string args = "reconstruct " + d + "/delft_sample_1.las -f " + d + "/delft_sample_footprints.gpkg --no-progress";
  fs::create_directories(dir_ / "out_with_models_file");
  std::ofstream(dir_ / "a_file") << "x";
  std::ofstream(dir_ / "out_with_models_file" / "models") << "x";
  struct Case {
    std::string options, message;
  };
  const std::vector<Case> cases = {
      {"-o " + (dir_ / "a_file").string(), "cannot create folder " + (dir_ / "a_file").string() + ": " +
                                               (dir_ / "a_file").string() + " exists and is a file, not a folder"},
      {"-o " + (dir_ / "a_file" / "sub").string(), (dir_ / "a_file").string() + " is a file, not a folder"},
      {"-o " + (dir_ / "out_with_models_file").string(),
       "output: cannot create folder " + (dir_ / "out_with_models_file" / "models").string()},
      {"-o " + (dir_ / "out").string() + " --debug " + (dir_ / "a_file" / "debug").string(),
       "debug: cannot create folder " + (dir_ / "a_file" / "debug").string()},
  };
  for (const Case& c : cases) {
    const Result r = run(args + " " + c.options);
    EXPECT_EQ(r.exit_code, 1) << c.options << "\n" << r.output;
    EXPECT_TRUE(contains(r.output, c.message)) << c.options << "\n" << r.output;
    EXPECT_FALSE(contains(r.output, "internal error")) << r.output;
  }
  // Without write permission, for the output and the --debug folder. Root writes anywhere, so as root
  // (CI) the run is made as the user nobody (setpriv, util-linux) in a folder only root may write.
  std::string as_user;
  if (::geteuid() == 0) {
    if (run_shell("command -v setpriv > /dev/null").exit_code != 0) GTEST_SKIP() << "root without setpriv";
    as_user = "setpriv --reuid=65534 --regid=65534 --clear-groups ";
  }
  fs::create_directories(dir_ / "locked");
  fs::permissions(dir_ / "locked", ::geteuid() == 0 ? fs::perms::owner_all | fs::perms::others_read | fs::perms::others_exec
                                                    : fs::perms::owner_read | fs::perms::owner_exec);
  // nobody must reach the inputs and the executable (copied here: the checkout may sit in a folder
  // only root can enter, as a fresh clone in a mktemp -d folder does), and write the other folder.
  fs::permissions(dir_, fs::perms::others_read | fs::perms::others_exec, fs::perm_options::add);
  fs::create_directories(dir_ / "inputs");
  for (const char* f : {"delft_sample_1.las", "delft_sample_footprints.gpkg"})
    fs::copy_file(d + "/" + f, dir_ / "inputs" / f, fs::copy_options::overwrite_existing);
  fs::copy_file(CITY3D_EXE, dir_ / "inputs" / "city3d", fs::copy_options::overwrite_existing);
  for (const auto& e : fs::directory_iterator(dir_ / "inputs"))
    fs::permissions(e.path(), fs::perms::others_read | fs::perms::others_exec, fs::perm_options::add);
  fs::permissions(dir_ / "inputs", fs::perms::others_read | fs::perms::others_exec, fs::perm_options::add);
  const std::string exe = (dir_ / "inputs" / "city3d").string();
  const std::string local_args = "reconstruct " + (dir_ / "inputs" / "delft_sample_1.las").string() + " -f " +
                                 (dir_ / "inputs" / "delft_sample_footprints.gpkg").string() + " --no-progress";
  fs::create_directories(dir_ / "open");
  fs::permissions(dir_ / "open", fs::perms::all);
  const Result out = run_shell(as_user + exe + " " + local_args + " -o " + (dir_ / "locked" / "out").string());
  const Result debug = run_shell(as_user + exe + " " + local_args + " -o " + (dir_ / "open" / "out").string() +
                                 " --debug " + (dir_ / "locked" / "debug").string());
  fs::permissions(dir_ / "locked", fs::perms::owner_all);
  EXPECT_EQ(out.exit_code, 1) << out.output;
  EXPECT_TRUE(contains(out.output, "output: cannot create folder " + (dir_ / "locked" / "out").string() +
                                       ": Permission denied")) << out.output;
  EXPECT_EQ(debug.exit_code, 1) << debug.output;
  EXPECT_TRUE(contains(debug.output, "debug: cannot create folder " + (dir_ / "locked" / "debug").string() +
                                         ": Permission denied")) << debug.output;
  EXPECT_FALSE(fs::exists(dir_ / "open" / "out"));  // a run that fails on its outputs leaves no folder
}

namespace {

// A copy of a sample tile that records `epsg` (as a projected or geographic GeoKey).
void copy_tile_with_crs(const std::string& from, const fs::path& to, int epsg, bool geographic) {
  const city3d::PointCloud cloud = city3d::read_point_cloud(from, city3d::kFieldClassification);
  std::vector<city3d::test::LasPoint> points;
  for (std::size_t i = 0; i < cloud.size(); ++i)
    points.push_back({cloud.points[i].x, cloud.points[i].y, cloud.points[i].z, cloud.classification[i]});
  city3d::test::LasWriteOptions o;
  o.epsg = epsg;
  o.geographic = geographic;
  city3d::test::write_las(to.string(), points, o);
}

// id -> status,level of every report row.
std::map<std::string, std::string> statuses(const fs::path& report) {
  std::map<std::string, std::string> out;
  const auto rows = lines_of(read_file(report));
  for (std::size_t i = 1; i < rows.size(); ++i) {
    std::stringstream ss(rows[i]);
    std::string id, status, level;
    std::getline(ss, id, ',');
    std::getline(ss, status, ',');
    std::getline(ss, level, ',');
    out[id] = status + "," + level;
  }
  return out;
}

}  // namespace

// Issue 14 item 8: the same tile given twice (twice by name, through a folder and by name, or
// through a symbolic link) doubled every building's points and changed 13 of 15 models.
TEST_F(Reconstruct, same_tile_given_twice_is_read_once_with_a_warning) {
  const std::string d = CITY3D_SAMPLE_DATA;
  const std::string tail = " -f " + d + "/delft_sample_footprints.gpkg --id-field gml_id --no-progress -o ";
  ASSERT_EQ(run("reconstruct " + d + "/delft_sample_1.las " + d + "/delft_sample_2.las" + tail + (dir_ / "once").string())
                .exit_code,
            0);
  fs::create_directories(dir_ / "tiles");
  fs::create_symlink(d + "/delft_sample_1.las", dir_ / "tiles" / "link_to_1.las");
  fs::copy_file(d + "/delft_sample_2.las", dir_ / "copy_of_2.las");
  const std::vector<std::string> twice = {
      d + "/delft_sample_1.las " + d + "/delft_sample_2.las " + d + "/delft_sample_1.las",
      (dir_ / "tiles").string() + " " + d + "/delft_sample_1.las " + d + "/delft_sample_2.las",
      d + "/delft_sample_1.las " + d + "/delft_sample_2.las " + (dir_ / "copy_of_2.las").string()};
  for (std::size_t k = 0; k < twice.size(); ++k) {
    const fs::path out = dir_ / ("twice" + std::to_string(k));
    const Result r = run("reconstruct " + twice[k] + tail + out.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "read once")) << r.output;
    EXPECT_EQ(read_file(out / "buildings.city.json"), read_file(dir_ / "once" / "buildings.city.json")) << twice[k];
    for (const auto& entry : fs::directory_iterator(dir_ / "once" / "models"))
      EXPECT_EQ(read_file(entry.path()), read_file(out / "models" / entry.path().filename())) << entry.path();
  }
}

// Issue 14 item 6: footprints and points in different CRSs ended with exit 0 and every building
// skipped, even with --strict.
TEST_F(Reconstruct, footprints_in_another_crs_are_reprojected_or_refused_with_both_extents) {
  const std::string d = CITY3D_SAMPLE_DATA;
  fs::create_directories(dir_);
  const fs::path wgs84 = dir_ / "footprints_wgs84.geojson";
  const Result converted = run_shell("ogr2ogr -f GeoJSON -t_srs EPSG:4326 -lco COORDINATE_PRECISION=10 " + wgs84.string() +
                                     " " + d + "/delft_sample_footprints.gpkg");
  ASSERT_EQ(converted.exit_code, 0) << converted.output;
  copy_tile_with_crs(d + "/delft_sample_1.las", dir_ / "rd_1.las", 28992, false);
  copy_tile_with_crs(d + "/delft_sample_2.las", dir_ / "rd_2.las", 28992, false);
  const std::string rd_tiles = (dir_ / "rd_1.las").string() + " " + (dir_ / "rd_2.las").string();
  const std::string opts = " --id-field gml_id --no-progress -o ";

  // Tiles that record no CRS (AHN3 as delivered) under WGS84 footprints: nothing can meet.
  Result r = run("reconstruct " + d + "/delft_sample_1.las " + d + "/delft_sample_2.las -f " + wgs84.string() + opts +
                 (dir_ / "a").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(contains(r.output, "no footprint meets any point cloud")) << r.output;
  EXPECT_TRUE(contains(r.output, "EPSG:4326")) << r.output;
  EXPECT_TRUE(contains(r.output, "the point clouds' headers (no CRS recorded) give their points as spanning x 84945.000 .. 85026.997")) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "a")) << "a failed run leaves no output folder";

  // Tiles that record EPSG:28992: the WGS84 footprints are reprojected, and give the buildings
  // the RD New footprints give.
  r = run("reconstruct " + rd_tiles + " -f " + wgs84.string() + opts + (dir_ / "b").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "footprints reprojected")) << r.output;
  ASSERT_EQ(run("reconstruct " + rd_tiles + " -f " + d + "/delft_sample_footprints.gpkg" + opts + (dir_ / "c").string())
                .exit_code,
            0);
  const auto reprojected = statuses(dir_ / "b" / "report.csv"), direct = statuses(dir_ / "c" / "report.csv");
  EXPECT_EQ(reprojected.size(), 15u);
  EXPECT_EQ(reprojected, direct);
  EXPECT_TRUE(contains(read_file(dir_ / "b" / "buildings.city.json"), "EPSG/0/28992"));

  // A tile that declares EPSG:4326 (degrees) against RD New footprints.
  copy_tile_with_crs(d + "/delft_sample_1.las", dir_ / "says_4326.las", 4326, true);
  r = run("reconstruct " + (dir_ / "says_4326.las").string() + " -f " + d + "/delft_sample_footprints.gpkg" + opts +
          (dir_ / "d").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(contains(r.output, "says_4326.las declares a geographic CRS (EPSG:4326")) << r.output;
  EXPECT_TRUE(contains(r.output, "are not degrees either")) << r.output;

  // Tiles of two CRSs.
  copy_tile_with_crs(d + "/delft_sample_2.las", dir_ / "utm_2.las", 32631, false);
  r = run("reconstruct " + (dir_ / "rd_1.las").string() + " " + (dir_ / "utm_2.las").string() + " -f " + d +
          "/delft_sample_footprints.gpkg" + opts + (dir_ / "e").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(contains(r.output, "utm_2.las is in EPSG:32631 but")) << r.output;
}

// Issue 14 item 6: --strict counted a run where nothing was reconstructed as a failure; since issue 24
// item 6 such a run exits 1, --strict or not (its report is written).
TEST_F(Reconstruct, run_where_nothing_was_reconstructed_exits_with_1_strict_or_not) {
  const std::string d = CITY3D_SAMPLE_DATA;
  const std::string args = "reconstruct " + d + "/delft_sample_1.las -f " + d +
                           "/delft_sample_footprints.gpkg --building-classes 99 --no-progress -o ";
  Result r = run(args + (dir_ / "a").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(contains(r.output, "no building was reconstructed")) << r.output;
  EXPECT_TRUE(fs::exists(dir_ / "a" / "report.csv"));
  r = run(args + (dir_ / "b").string() + " --strict");
  EXPECT_EQ(r.exit_code, 1) << r.output;
}

// Issue 14 item 9: `info` on a missing or empty LAS said "footprints: cannot open" or "not a vector
// source"; a point cloud without points was skipped as "footprint has no usable polygon"; a run that
// failed on bad input left an output folder with only a journal in it.
TEST_F(Reconstruct, info_on_a_missing_or_empty_las_names_the_point_cloud_problem) {
  fs::create_directories(dir_);
  std::ofstream(dir_ / "empty.las").close();
  Result r = run("info " + (dir_ / "missing.las").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(contains(r.output, "las: cannot open " + (dir_ / "missing.las").string() + ": No such file")) << r.output;
  EXPECT_FALSE(contains(r.output, "footprints")) << r.output;
  r = run("info " + (dir_ / "empty.las").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(contains(r.output, "las: " + (dir_ / "empty.las").string() + " is empty (0 bytes)")) << r.output;
  EXPECT_FALSE(contains(r.output, "vector source")) << r.output;
}

TEST_F(Reconstruct, single_building_cloud_without_points_is_skipped_for_want_of_points) {
  fs::create_directories(dir_);
  std::ofstream(dir_ / "nothing.ply") << "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                                         "property float z\nend_header\n";
  const Result r = run("reconstruct " + (dir_ / "nothing.ply").string() + " --no-progress -o " + (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 1) << r.output;  // nothing built (issue 24 item 6)
  const auto rows = lines_of(read_file(dir_ / "out" / "report.csv"));
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_TRUE(contains(rows[1], "nothing,skipped,none,input,the point cloud has no points")) << rows[1];
}

TEST_F(Reconstruct, run_that_fails_on_bad_input_leaves_no_output_folder) {
  const std::string broken = kShared + "/laz/broken/broken_corrupt_v2_bytes.laz";
  if (!fs::exists(broken)) GTEST_SKIP() << "../shared/data is not beside the repository";
  // The header is fine (so the run starts), the points are not: the failure comes mid-run.
  Result r = run("reconstruct " + broken + " --no-progress -o " + (dir_ / "out").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(contains(r.output, "broken_corrupt_v2_bytes.laz")) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "out")) << "left behind: an output folder without results";
  // A folder that was there before is left as it was.
  fs::create_directories(dir_ / "kept");
  r = run("reconstruct " + broken + " --no-progress -o " + (dir_ / "kept").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(fs::exists(dir_ / "kept"));
}

// Issue 13 item 7: --config FILE.toml with every option, --print-config to start one.
namespace {

city3d::RunOptions parse(std::vector<std::string> args) {
  args.insert(args.begin(), "city3d");
  std::vector<const char*> argv;
  for (const std::string& a : args) argv.push_back(a.c_str());
  return city3d::parse_command_line(static_cast<int>(argv.size()), argv.data());
}

std::string config_error(std::vector<std::string> args) {
  try {
    parse(std::move(args));
  } catch (const city3d::ConfigError& e) {
    return e.what();
  }
  return "no error";
}

// What decides a run's output, as the resume journal sees it, plus every option as --print-config
// prints it.
std::string effective(const city3d::RunOptions& o) {
  return city3d::detail::batch_fingerprint(o.batch, {}) + "\n" + city3d::parameters_text(o.batch.reconstruction) +
         "\n" + city3d::config_text(o);
}

class Config : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("city3d_config_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name) << text;
    return (dir_ / name).string();
  }
  fs::path dir_;
};

}  // namespace

TEST_F(Config, every_option_of_the_table_is_a_key_of_print_config_with_its_value) {
  const std::string text = city3d::config_text(city3d::RunOptions{});
  for (const city3d::detail::OptionSpec& spec : city3d::detail::option_table()) {
    // Every row shows its value, so that --print-config prints what --config read.
    EXPECT_TRUE(static_cast<bool>(spec.show)) << spec.flag << " has no show function";
    if (!city3d::detail::in_config_file(spec)) {
      EXPECT_FALSE(contains(text, std::string("\n") + (spec.flag + 2) + " =")) << spec.flag;
      continue;
    }
    const std::string key = spec.flag + 2;
    EXPECT_TRUE(contains(text, "\n" + key + " = ") || contains(text, "\n# " + key + " = ")) << key;
  }
  EXPECT_TRUE(contains(text, "\nlambda-data = 0.34\n")) << text;
  EXPECT_TRUE(contains(text, "\nbuilding-classes = [6]\n")) << text;
  EXPECT_TRUE(contains(text, "\noutput = \"city3d_out\"\n")) << text;
  EXPECT_TRUE(contains(text, "\nstrict = false\n")) << text;
  EXPECT_TRUE(contains(text, "\n# footprints = \"PATH\"\n")) << text;
}

TEST_F(Config, print_config_read_back_gives_identical_effective_parameters) {
  // The defaults.
  const std::string defaults = write("defaults.toml", city3d::config_text(parse({"--print-config"})));
  EXPECT_EQ(effective(parse({"reconstruct", "x.las", "--config", defaults})), effective(parse({"reconstruct", "x.las"})));
  // Every kind of value changed from its default.
  const std::vector<std::string> flags = {
      "--footprints", "fp \"quoted\".gpkg", "--layer", "pand", "--id-field", "gml_id", "--where", "bouwjaar > 1900",
      "--bbox", "84970.5,447530,85030,447580.25", "--ground-field", "h", "--no-repair", "--building-classes",
      "6,26", "--ground-class", "9", "--ignore-classes", "--ground-buffer", "2.5", "--ground-percentile", "12.5",
      "--ground-z", "-1.75", "--roof-percentile", "60", "--lod", "1.2", "--min-points", "33", "--plane-distance",
      "0.123456789012", "--plane-angle", "15", "--resolution", "0.3", "--eps-d", "0.2", "--eps-c", "1.5",
      "--snap-angle", "10", "--walls", "footprint", "--lambda-data", "0.3", "--lambda-complexity", "0.65",
      "--lambda-roof", "0.05", "--solver", "glpk", "--time-limit", "7.5", "--debug", "dbg", "-o", "out dir",
      "--format", "ply", "--no-model-files", "--merged", "--no-cityjson", "--cityjsonseq", "--timings",
      "--local-coordinates", "-j", "3", "--no-resume", "--block-size", "250", "--strict", "--no-progress", "-q"};
  std::vector<std::string> args = {"reconstruct", "x.las"};
  args.insert(args.end(), flags.begin(), flags.end());
  const city3d::RunOptions direct = parse(args);
  const std::string file = write("changed.toml", city3d::config_text(direct));
  const city3d::RunOptions from_file = parse({"reconstruct", "x.las", "--config", file});
  EXPECT_EQ(effective(from_file), effective(direct));
  EXPECT_EQ(from_file.batch.footprints, "fp \"quoted\".gpkg");
  EXPECT_EQ(from_file.batch.crop.building_classes, (std::vector<std::uint8_t>{6, 26}));
  EXPECT_DOUBLE_EQ(from_file.batch.reconstruction.planes.max_distance, 0.123456789012);
  EXPECT_EQ(from_file.batch.threads, 3);
  EXPECT_EQ(from_file.batch.output_dir, "out dir");
  EXPECT_EQ(from_file.batch.format, city3d::MeshFormat::ply_binary);
  EXPECT_TRUE(from_file.strict);
  EXPECT_EQ(from_file.verbosity, 0);
  EXPECT_EQ(from_file.progress, 0);
  ASSERT_TRUE(from_file.batch.ground_z.has_value());
  EXPECT_DOUBLE_EQ(*from_file.batch.ground_z, -1.75);
  ASSERT_TRUE(from_file.batch.footprint.bbox.has_value());
  EXPECT_DOUBLE_EQ(from_file.batch.footprint.bbox->max.y, 447580.25);
  EXPECT_NE(effective(from_file), effective(parse({"reconstruct", "x.las"})));
}

// Found by the config fuzzer (fuzz/regressions/config/): a path that strtod reads as a number ("\t333...",
// 30 digits, "1.50", "0x1F") was written as a bare TOML number, which --config refuses or rewrites.
TEST_F(Config, number_like_paths_are_written_as_strings_and_read_back_unchanged) {
  for (const std::string path : {std::string("\t\t3333333333333333333333333333333"), std::string("1.50"),
                                 std::string("0x1F"), std::string(" 12"), std::string("1e5")}) {
    const city3d::RunOptions direct = parse({"reconstruct", "x.las", "--footprints", path});
    const std::string text = city3d::config_text(direct);
    const std::string file = write("number_like.toml", text);
    city3d::RunOptions from_file;
    ASSERT_NO_THROW(from_file = parse({"reconstruct", "x.las", "--config", file})) << path;
    EXPECT_EQ(from_file.batch.footprints, path);
    EXPECT_EQ(city3d::config_text(from_file), text);
  }
  // And a negative zero, which TOML reads as the integer 0: written as 0.
  const std::string file = write("negative_zero.toml", "lambda-data = -0.0\n");
  const std::string text = city3d::config_text(parse({"reconstruct", "x.las", "--config", file}));
  EXPECT_NE(text.find("\nlambda-data = 0\n"), std::string::npos);
  const std::string again = write("negative_zero_again.toml", text);
  EXPECT_EQ(city3d::config_text(parse({"reconstruct", "x.las", "--config", again})), text);
}

TEST_F(Config, executable_reads_back_what_it_prints) {
  const Result printed = run("--print-config");
  ASSERT_EQ(printed.exit_code, 0) << printed.output;
  const std::string file = write("printed.toml", printed.output);
  const Result again = run("--config " + file + " --print-config");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(again.output, printed.output);
}

TEST_F(Config, options_on_the_command_line_override_the_file) {
  const std::string file = write("c.toml", "jobs = 3\nlambda-data = 0.5\nstrict = true\noutput = \"from_file\"\n"
                                           "building-classes = [6, 26]\n");
  const city3d::RunOptions o = parse({"reconstruct", "x.las", "--config", file, "-j", "2", "--strict=false"});
  EXPECT_EQ(o.batch.threads, 2);
  EXPECT_FALSE(o.strict);
  EXPECT_DOUBLE_EQ(o.batch.reconstruction.selection.lambda_data, 0.5);
  EXPECT_EQ(o.batch.output_dir, "from_file");
  EXPECT_EQ(o.batch.crop.building_classes, (std::vector<std::uint8_t>{6, 26}));
  // Wherever --config stands among the options.
  EXPECT_EQ(parse({"reconstruct", "--lambda-data", "0.4", "x.las", "--config", file}).batch.reconstruction.selection.lambda_data,
            0.4);
  // And through the executable: --print-config shows the merged result.
  const Result r = run("--config " + file + " --lambda-data 0.25 --print-config");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "\nlambda-data = 0.25\n")) << r.output;
  EXPECT_TRUE(contains(r.output, "\njobs = 3\n")) << r.output;
}

TEST_F(Config, every_problem_names_the_file_the_key_and_the_line_and_exits_with_2) {
  struct Case {
    std::string text, message;
  };
  const std::vector<Case> cases = {
      {"jobs = 2\nlambda-data = \n", "line 2 column 15: "},                                // TOML syntax
      {"jobs = 2\nid_field = \"x\"\n", "line 2: unknown key 'id_field' (did you mean 'id-field'?)"},
      {"frobnicate = 1\n", "line 1: unknown key 'frobnicate'"},
      {"[reconstruction]\njobs = 2\n", "line 1: unknown key 'reconstruction' (a table"},
      {"\n\njobs = \"2\"\n", "line 3: jobs must be a number, not a string"},
      {"strict = 1\n", "line 1: strict must be true or false, not an integer"},
      {"output = 3\n", "line 1: output must be a string, not an integer"},
      {"building-classes = [6, [2]]\n", "line 1: building-classes must be an array of numbers or strings"},
      {"solver = \"simplex\"\n", "line 1: solver: 'simplex' is not auto, glpk or cbc"},
      {"min-points = 2\n", "line 1: min-points: '2' is not an integer >= 3"},
      {"bbox = [1, 2, 3]\n", "line 1: bbox: expected XMIN,YMIN,XMAX,YMAX"},
      {"\neps-d = 0.0\n", "max_hausdorff must be > 0 (got 0)"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const std::string file = write("bad" + std::to_string(i) + ".toml", cases[i].text);
    const std::string message = config_error({"reconstruct", "x.las", "--config", file});
    EXPECT_TRUE(contains(message, file)) << cases[i].text << "\n" << message;
    EXPECT_TRUE(contains(message, cases[i].message)) << cases[i].text << "\n" << message;
  }
  EXPECT_TRUE(contains(config_error({"reconstruct", "x.las", "--config", (dir_ / "missing.toml").string()}),
                       "config: cannot open " + (dir_ / "missing.toml").string()));
  // The last case: a range error found by a stage, traced to its line and key.
  EXPECT_TRUE(contains(config_error({"reconstruct", "x.las", "--config", (dir_ / "bad11.toml").string()}),
                       "line 2: eps-d"));
  // Every problem of a file at once, in file order.
  const std::string several = write("several.toml", "jobs = \"x\"\nfoo = 1\nstrict = 3\n");
  const std::string message = config_error({"reconstruct", "x.las", "--config", several});
  EXPECT_LT(message.find("line 1"), message.find("line 2")) << message;
  EXPECT_LT(message.find("line 2"), message.find("line 3")) << message;
  const Result r = run("reconstruct x.las --config " + several);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_TRUE(contains(r.output, "several.toml line 3: strict must be true or false")) << r.output;
}

namespace {

// Issue 10: --step-height sets the step lines' least height step; 0 turns them off; negative is an error.
TEST(CommandLine, step_height_sets_the_step_lines_and_zero_turns_them_off) {
  const auto step_lines = [](std::vector<std::string> extra) {
    extra.insert(extra.begin(), {"reconstruct", "x.las"});
    return parse(extra).batch.reconstruction.step_lines;
  };
  EXPECT_TRUE(step_lines({}).enabled);
  EXPECT_EQ(step_lines({}).min_step, 0.5);
  EXPECT_EQ(step_lines({"--step-height", "1.2"}).min_step, 1.2);
  EXPECT_TRUE(step_lines({"--step-height", "1.2"}).enabled);
  EXPECT_FALSE(step_lines({"--step-height", "0"}).enabled);
  EXPECT_NE(config_error({"reconstruct", "x.las", "--step-height", "-1"}).find("--step-height"), std::string::npos);
}

}  // namespace
