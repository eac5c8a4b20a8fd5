// End-to-end tests of the `city3d` executable: options, help, exit codes and the info command on
// real data. Also pins the defaults of the option table so that a change is deliberate.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

#include "city3d/error.hpp"
#include "city3d/options.hpp"

namespace fs = std::filesystem;

namespace {

struct Result {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

Result run(const std::string& arguments) {
  const std::string command = std::string(CITY3D_EXE) + " " + arguments + " 2>&1";
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
  EXPECT_EQ(o.output_dir, "city3d_out");
  EXPECT_EQ(o.format, "obj");
  EXPECT_FALSE(o.local_coordinates);
  EXPECT_TRUE(o.footprint.id_field.empty());
  EXPECT_TRUE(o.footprint.repair);
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
  const char* argv[] = {"city3d", "info", "--bbox=1,2,3,4", "--id-field", "gml_id", "f.gpkg"};
  const city3d::RunOptions o = city3d::parse_command_line(6, argv);
  ASSERT_TRUE(o.footprint.bbox.has_value());
  EXPECT_DOUBLE_EQ(o.footprint.bbox->min.x, 1.0);
  EXPECT_DOUBLE_EQ(o.footprint.bbox->max.y, 4.0);
  EXPECT_EQ(o.footprint.id_field, "gml_id");
}

TEST(Executable, help_lists_every_option_with_its_default_and_the_exit_codes) {
  const Result r = run("--help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* flag : {"--footprints", "--layer", "--id-field", "--where", "--bbox", "--no-repair", "--output",
                           "--format", "--local-coordinates", "--verbose", "--quiet", "--help", "--version"})
    EXPECT_TRUE(contains(r.output, flag)) << flag;
  EXPECT_TRUE(contains(r.output, "[default: city3d_out]"));
  EXPECT_TRUE(contains(r.output, "[default: obj]"));
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
