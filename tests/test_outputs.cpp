// End-to-end tests of the run-level outputs on the sample block: CityJSON with three levels of
// detail per building (ids, one transform in both files, attribute types and precision), the
// GeoPackage (opened with ogrinfo, one feature per input footprint), and report.html (rendered by
// headless Chromium: a screenshot, no console errors).
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace {

namespace fs = std::filesystem;

struct Result {
  int exit_code = -1;
  std::string output;
};

Result run_shell(const std::string& command) {
  Result r;
  std::FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

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

bool have(const char* program) { return run_shell(std::string("command -v ") + program + " > /dev/null").exit_code == 0; }

// One run of the sample block with every run-level output, shared by the tests (it takes seconds).
class Outputs : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // One folder per process: CTest runs each test of this suite as its own process, in parallel.
    dir_ = fs::temp_directory_path() / ("city3d_outputs_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    const std::string d = CITY3D_SAMPLE_DATA;
    // A copy of the footprints with a 64-bit id above 2^53 (a double cannot hold it) and a skipped
    // footprint (an empty geometry), to see both carried through.
    const fs::path footprints = dir_ / "footprints.geojson";
    Result conv = run_shell("ogr2ogr -f GeoJSON " + footprints.string() + " " + d + "/delft_sample_footprints.gpkg");
    ASSERT_EQ(conv.exit_code, 0) << conv.output;
    std::string text = read_file(footprints);
    const std::string first = "\"bag_pnd\": ";
    const auto at = text.find(first);
    ASSERT_NE(at, std::string::npos) << text.substr(0, 400);
    const auto end = text.find_first_of(",}", at + first.size());
    text.replace(at + first.size(), end - at - first.size(), "9007199254740993");
    const auto last = text.rfind("]");
    text.insert(last, ",\n{ \"type\": \"Feature\", \"properties\": { \"gml_id\": \"empty-one\", \"bag_pnd\": 1 }, \"geometry\": null }\n");
    std::ofstream(footprints) << text;
    run_ = run_shell(std::string(CITY3D_EXE) + " reconstruct " + d + "/delft_sample_1.las " + d +
                     "/delft_sample_2.las -f " + footprints.string() +
                     " --id-field gml_id --cityjsonseq --gpkg --no-progress -o " + (dir_ / "out").string());
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static fs::path dir_;
  static Result run_;
};
fs::path Outputs::dir_;
Result Outputs::run_;

// Ids of the report rows (first column), header excluded.
std::vector<std::string> report_ids(const fs::path& csv) {
  std::vector<std::string> ids;
  const auto rows = lines_of(read_file(csv));
  for (std::size_t i = 1; i < rows.size(); ++i) ids.push_back(rows[i].substr(0, rows[i].find(',')));
  return ids;
}

TEST_F(Outputs, run_succeeds_with_a_row_per_footprint) {
  ASSERT_EQ(run_.exit_code, 0) << run_.output;
  const auto ids = report_ids(dir_ / "out" / "report.csv");
  EXPECT_EQ(ids.size(), 16u);  // the sample's 15 footprints and the empty one
}

TEST_F(Outputs, cityjson_has_three_lods_per_building_under_the_footprint_id) {
  ASSERT_EQ(run_.exit_code, 0) << run_.output;
  const std::string text = read_file(dir_ / "out" / "buildings.city.json");
  std::size_t buildings = 0;
  for (const std::string& id : report_ids(dir_ / "out" / "report.csv")) {
    if (id == "empty-one") continue;
    const auto at = text.find("\"" + id + "\":{\"type\":\"Building\"");
    ASSERT_NE(at, std::string::npos) << id;
    ++buildings;
    const auto next = text.find("\"type\":\"Building\"", at + id.size() + 20);
    const std::string object = text.substr(at, next == std::string::npos ? std::string::npos : next - at);
    for (const char* lod : {"1.2", "1.3", "2.2"})
      EXPECT_NE(object.find(std::string("{\"type\":\"Solid\",\"lod\":\"") + lod + "\""), std::string::npos)
          << id << " has no LoD" << lod;
    EXPECT_NE(object.find("\"lods_reconstructed\":\"1.2,1.3,2.2\""), std::string::npos) << id;
    EXPECT_NE(object.find("{\"type\":\"RoofSurface\"}"), std::string::npos) << id;
  }
  EXPECT_EQ(buildings, 15u);
}

TEST_F(Outputs, cityjson_and_cityjsonseq_share_one_transform_at_a_tenth_of_a_millimetre) {
  ASSERT_EQ(run_.exit_code, 0) << run_.output;
  const std::regex transform("\"transform\":\\{[^}]*\\}");
  std::smatch whole, seq;
  const std::string a = read_file(dir_ / "out" / "buildings.city.json");
  const std::string b = lines_of(read_file(dir_ / "out" / "buildings.city.jsonl")).front();
  ASSERT_TRUE(std::regex_search(a, whole, transform));
  ASSERT_TRUE(std::regex_search(b, seq, transform));
  EXPECT_EQ(whole.str(), seq.str());
  EXPECT_NE(whole.str().find("\"scale\":[0.0001,0.0001,0.0001]"), std::string::npos) << whole.str();
}

TEST_F(Outputs, attributes_keep_64_bit_integers_and_are_written_at_a_sensible_precision) {
  ASSERT_EQ(run_.exit_code, 0) << run_.output;
  const std::string text = read_file(dir_ / "out" / "buildings.city.json");
  EXPECT_NE(text.find("\"bag_pnd\":9007199254740993"), std::string::npos);  // not ...992 (a double)
  EXPECT_NE(text.find("\"lokaalid\":\"G0503."), std::string::npos);         // text stays text
  // No attribute number carries binary noise such as 0.013000000000000001.
  std::size_t attributes = 0;
  for (auto at = text.find("\"attributes\":{"); at != std::string::npos; at = text.find("\"attributes\":{", at + 1)) {
    const std::string a = text.substr(at, text.find('}', at) - at);
    EXPECT_FALSE(std::regex_search(a, std::regex("[0-9]\\.[0-9]{6,}"))) << a;
    EXPECT_NE(a.find("\"b3_h_dak_70p\":"), std::string::npos) << a;
    EXPECT_NE(a.find("\"b3_volume_lod22\":"), std::string::npos) << a;
    ++attributes;
  }
  EXPECT_EQ(attributes, 15u);
}

TEST_F(Outputs, geopackage_opens_with_ogrinfo_and_has_one_feature_per_footprint) {
  ASSERT_EQ(run_.exit_code, 0) << run_.output;
  if (!have("ogrinfo")) GTEST_SKIP() << "ogrinfo (gdal-bin) not installed";
  const fs::path gpkg = dir_ / "out" / "buildings.gpkg";
  const Result info = run_shell("ogrinfo -ro -so " + gpkg.string() + " buildings");
  ASSERT_EQ(info.exit_code, 0) << info.output;
  EXPECT_NE(info.output.find("Feature Count: 16"), std::string::npos) << info.output;
  EXPECT_NE(info.output.find("bag_pnd: Integer64"), std::string::npos) << info.output;
  EXPECT_NE(info.output.find("b3_rmse_lod22: Real"), std::string::npos) << info.output;
  EXPECT_NE(info.output.find("unexplained_points: Integer64"), std::string::npos) << info.output;
  EXPECT_NE(info.output.find("unexplained_share: Real"), std::string::npos) << info.output;
  EXPECT_NE(info.output.find("unsupported_area: Real"), std::string::npos) << info.output;
  EXPECT_NE(info.output.find("height_excess: Real"), std::string::npos) << info.output;
  const Result empty = run_shell("ogrinfo -ro " + gpkg.string() + " buildings -where \"id = 'empty-one'\"");
  EXPECT_NE(empty.output.find("status (String) = skipped"), std::string::npos) << empty.output;
  const Result big = run_shell("ogrinfo -ro " + gpkg.string() + " buildings -where \"bag_pnd = 9007199254740993\"");
  EXPECT_NE(big.output.find("Feature Count: 1"), std::string::npos) << big.output;  // -so not given: count in summary
  const Result roofs = run_shell("ogrinfo -ro -so " + gpkg.string() + " roof_parts");
  ASSERT_EQ(roofs.exit_code, 0) << roofs.output;
  const std::smatch m = [&] {
    std::smatch s;
    std::regex_search(roofs.output, s, std::regex("Feature Count: ([0-9]+)"));
    return s;
  }();
  ASSERT_EQ(m.size(), 2u) << roofs.output;
  EXPECT_GE(std::stoi(m[1]), 15);  // at least one roof part per building
  for (const char* field : {"slope: Real", "azimuth: Real", "h_max: Real"})
    EXPECT_NE(roofs.output.find(field), std::string::npos) << roofs.output;
}

TEST_F(Outputs, report_html_renders_in_headless_chromium_without_console_errors) {
  ASSERT_EQ(run_.exit_code, 0) << run_.output;
  const fs::path html = dir_ / "out" / "report.html";
  const std::string page = read_file(html);
  // Self-contained: nothing is fetched (the SVG namespace URI is a name, not a request).
  for (const char* fetch : {"<script src", "<link ", "url(", "@import", "fetch("})
    EXPECT_EQ(page.find(fetch), std::string::npos) << fetch;
  std::string browser;
  for (const char* b : {"chromium", "chromium-browser"})
    if (have(b)) browser = b;
  if (browser.empty()) GTEST_SKIP() << "chromium not installed (scripts/setup.sh test installs it)";
  const fs::path shot = dir_ / "report.png";
  const fs::path profile = dir_ / "chromium-profile";
  // The page logs "city3d report ready" when its script has drawn everything. Chromium logs every
  // console message (and every uncaught exception) as "INFO:CONSOLE"; any other than that one fails.
  const Result r = run_shell("timeout 120 " + browser +
                             " --headless --no-sandbox --disable-gpu --disable-background-networking"
                             " --disable-component-update --disable-sync --no-first-run --user-data-dir=" +
                             profile.string() + " --enable-logging=stderr --v=0 --window-size=1400,1600"
                             " --virtual-time-budget=5000 --screenshot=" + shot.string() + " file://" + html.string());
  ASSERT_TRUE(fs::exists(shot)) << r.output;
  EXPECT_GT(fs::file_size(shot), 20000u);  // a drawn page, not a blank one
  EXPECT_NE(r.output.find("city3d report ready"), std::string::npos) << r.output;
  for (const std::string& line : lines_of(r.output)) {
    const bool console = line.find(":CONSOLE") != std::string::npos || line.find("Uncaught") != std::string::npos;
    if (console && line.find("city3d report ready") == std::string::npos) ADD_FAILURE() << "console: " << line;
  }
}

}  // namespace

namespace {

// The case: rounding two nearly collinear roof vertices to millimetres bends a polygon past
// val3dity's 20 degrees (204) on Delft buildings. At --scale 0.001 the check must see them on the
// coordinates as rounded and repair them (never write them as they are); at the default 0.1 mm grid
// there is nothing to repair. Which buildings have such a pair depends on the models: two with the
// models of issue 13, none with issue 10's defaults, one with planes grown at 20 degrees until issue
// 23, and since then one (b1105d28c) with the paper's 40 points per plane (used here).
TEST(OutputsDelft, millimetre_rounding_204_is_found_on_the_rounded_coordinates_and_repaired) {
  const std::string d = std::string(CITY3D_SHARED_DATA) + "/ahn3_delft";
  if (!fs::exists(d + "/ahn3_cropped_1.las")) GTEST_SKIP() << "../shared/data is not beside the repository";
  const fs::path dir = fs::temp_directory_path() / ("city3d_delft_mm_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const Result r = run_shell(std::string(CITY3D_EXE) + " reconstruct " + d + "/ahn3_cropped_1.las " + d +
                             "/ahn3_cropped_2.las -f " + d + "/footprints/bgt_pand_laz_area.gpkg --id-field gml_id" +
                             " -j 2 --no-progress -q --no-html --scale 0.001 --min-points 40 -o " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto rows = lines_of(read_file(dir / "report.csv"));
  ASSERT_EQ(rows.size(), 161u);
  std::size_t found = 0;
  for (const std::string& row : rows)
    if (row.find("LoD2.2: 204") != std::string::npos) {
      ++found;
      EXPECT_NE(row.find("into triangles"), std::string::npos) << row;  // repaired, not written as it was
      EXPECT_NE(row.find(",ok,"), std::string::npos) << row;
    }
  EXPECT_GE(found, 1u);
  fs::remove_all(dir);
}

}  // namespace
