// End-to-end tests of the `city3d` executable: options, help, exit codes and the info command on
// real data. Also pins the defaults of the option table so that a change is deliberate.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>
#include <string>

#include "city3d/error.hpp"
#include "city3d/options.hpp"

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
  EXPECT_EQ(o.verbosity, 1);
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
        "--quiet", "--help", "--version"})
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
  EXPECT_TRUE(contains(r.output, "skipped: 0\n")) << r.output;
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
