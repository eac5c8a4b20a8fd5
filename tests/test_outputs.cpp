// End-to-end tests of the run-level outputs on the sample block: CityJSON with three levels of
// detail per building (ids, one transform in both files, attribute types and precision, metadata:
// CRS, extent, version, parameters), the GeoPackage (opened with ogrinfo: one feature per input
// footprint, each level's roof parts and MultiPolygonZ models), OBJ groups per semantic surface,
// run.json, and report.html (rendered by headless Chromium: a screenshot, no console errors, the
// map's hover and scale bar, inputs and parameters, the outlines inferred for single-building clouds);
// a row of report.json against its CSV row, and report.html's data against the records it is made of.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/run_outputs.hpp"
#include "reports/report.hpp"

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

// The issue's case: rounding two nearly collinear roof vertices to millimetres bends a polygon past
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

// --- issue 25: delivered as 3DBAG delivers ------------------------------------------------------

namespace {

using json = nlohmann::json;

json read_json(const fs::path& p) { return json::parse(read_file(p)); }

// A layer of a GeoPackage as GeoJSON (ogr2ogr), coordinates as stored.
json layer_geojson(const fs::path& gpkg, const std::string& layer, const fs::path& scratch) {
  const fs::path out = scratch / (layer + ".geojson");
  fs::remove(out);
  const Result r = run_shell("ogr2ogr -f GeoJSON " + out.string() + " " + gpkg.string() + " " + layer);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return fs::exists(out) ? read_json(out) : json::object();
}

// The faces (boundary rings) and semantic types of one building's Solid of a level in a CityJSON
// file, BuildingParts included, with the file's vertices in metres.
struct CityJsonLevel {
  std::vector<std::vector<std::array<double, 3>>> faces;
  std::vector<std::string> types;
};

CityJsonLevel cityjson_level(const json& city, const std::string& id, const std::string& lod) {
  CityJsonLevel level;
  const json& t = city["transform"];
  const auto add = [&](const json& object) {
    for (const json& g : object.value("geometry", json::array())) {
      if (g["lod"] != lod) continue;
      const json& surfaces = g["semantics"]["surfaces"];
      const json& values = g["semantics"]["values"][0];
      for (std::size_t f = 0; f < g["boundaries"][0].size(); ++f) {
        std::vector<std::array<double, 3>> ring;
        for (const json& v : g["boundaries"][0][f][0]) {
          const json& q = city["vertices"][v.get<std::size_t>()];
          ring.push_back({q[0].get<double>() * t["scale"][0].get<double>() + t["translate"][0].get<double>(),
                          q[1].get<double>() * t["scale"][1].get<double>() + t["translate"][1].get<double>(),
                          q[2].get<double>() * t["scale"][2].get<double>() + t["translate"][2].get<double>()});
        }
        level.faces.push_back(ring);
        level.types.push_back(surfaces[values[f].get<std::size_t>()]["type"]);
      }
    }
  };
  const json& building = city["CityObjects"][id];
  add(building);
  for (const json& child : building.value("children", json::array())) add(city["CityObjects"][child.get<std::string>()]);
  return level;
}

std::vector<std::string> building_ids(const json& city) {
  std::vector<std::string> ids;
  for (const auto& [id, object] : city["CityObjects"].items())
    if (object["type"] == "Building") ids.push_back(id);
  std::sort(ids.begin(), ids.end());
  return ids;
}

}  // namespace

TEST_F(Outputs, geopackage_has_a_2d_and_a_3d_layer_per_level_as_3dbag_with_the_cityjson_faces_and_types) {
  ASSERT_EQ(run_.exit_code, 0) << run_.output;
  if (!have("ogrinfo") || !have("ogr2ogr")) GTEST_SKIP() << "ogrinfo / ogr2ogr (gdal-bin) not installed";
  const fs::path gpkg = dir_ / "out" / "buildings.gpkg";
  const Result layers = run_shell("ogrinfo -ro -q " + gpkg.string());
  for (const char* layer : {"buildings (Multi Polygon)", "lod12_2d (Polygon)", "lod12_3d (3D Multi Polygon)",
                            "lod13_2d (Polygon)", "lod13_3d (3D Multi Polygon)", "lod22_2d (Polygon)",
                            "lod22_3d (3D Multi Polygon)", "roof_parts (Polygon)"})
    EXPECT_NE(layers.output.find(layer), std::string::npos) << layer << "\n" << layers.output;
  const json city = read_json(dir_ / "out" / "buildings.city.json");
  const std::vector<std::string> ids = building_ids(city);
  ASSERT_EQ(ids.size(), 15u);
  for (const std::string lod : {"1.2", "1.3", "2.2"}) {
    SCOPED_TRACE("LoD" + lod);
    const std::string name = std::string("lod") + lod[0] + lod[2];
    // _3d: one MultiPolygonZ per building, its polygons the CityJSON Solid's faces, in the order
    // ground, walls, roofs, each named in `surfaces`.
    const json solids = layer_geojson(gpkg, name + "_3d", dir_);
    ASSERT_EQ(solids["features"].size(), 15u);
    std::vector<std::string> seen;
    std::size_t roof_faces = 0;
    for (const json& f : solids["features"]) {
      const std::string id = f["properties"]["id"];
      seen.push_back(id);
      const CityJsonLevel level = cityjson_level(city, id, lod);
      ASSERT_EQ(f["geometry"]["type"], "MultiPolygon") << id;
      const json& polygons = f["geometry"]["coordinates"];
      // A JSON field: ogr2ogr writes its value into GeoJSON as the JSON it holds.
      const json surfaces = f["properties"]["surfaces"];
      ASSERT_EQ(polygons.size(), level.faces.size()) << id;
      ASSERT_EQ(surfaces.size(), polygons.size()) << id;
      std::vector<std::string> sorted = level.types;
      const auto rank = [](const std::string& t) { return t == "GroundSurface" ? 0 : t == "WallSurface" ? 1 : 2; };
      std::stable_sort(sorted.begin(), sorted.end(), [&](const auto& a, const auto& b) { return rank(a) < rank(b); });
      EXPECT_EQ(surfaces.get<std::vector<std::string>>(), sorted) << id;
      const double ground = f["properties"]["b3_h_maaiveld"];
      double top = -1e9;
      for (std::size_t k = 0; k < polygons.size(); ++k) {
        for (const json& p : polygons[k][0]) {
          ASSERT_EQ(p.size(), 3u) << id;  // x, y, z
          top = std::max(top, p[2].get<double>());
          if (surfaces[k] == "GroundSurface") EXPECT_NEAR(p[2].get<double>(), ground, 0.0011) << id;
        }
        roof_faces += surfaces[k] == "RoofSurface";
      }
      EXPECT_NEAR(f["properties"]["h_max"].get<double>(), top, 0.0006) << id;
      EXPECT_EQ(f["properties"]["val3dity"], json::array()) << id;
      EXPECT_GT(f["properties"]["volume"].get<double>(), 0.0) << id;
    }
    std::sort(seen.begin(), seen.end());
    EXPECT_EQ(seen, ids);  // the CityJSON ids, each once
    // _2d: one feature per roof face, in plan, with its heights.
    const json parts = layer_geojson(gpkg, name + "_2d", dir_);
    EXPECT_EQ(parts["features"].size(), roof_faces);
    for (const json& f : parts["features"]) {
      const json& p = f["properties"];
      EXPECT_EQ(f["geometry"]["type"], "Polygon");
      EXPECT_EQ(f["geometry"]["coordinates"][0][0].size(), 2u);
      EXPECT_LE(p["h_min"].get<double>(), p["h_mean"].get<double>() + 1e-9);
      EXPECT_LE(p["h_mean"].get<double>(), p["h_max"].get<double>() + 1e-9);
      EXPECT_GT(p["h_min"].get<double>(), p["b3_h_maaiveld"].get<double>());
      if (lod != "2.2") {
        EXPECT_EQ(p["slope"].get<double>(), 0.0);  // a block's top is flat
        EXPECT_EQ(p["h_min"], p["h_max"]);
      }
    }
  }
}

TEST_F(Outputs, roof_parts_is_lod22_2d_under_its_earlier_name_with_its_earlier_columns) {
  ASSERT_EQ(run_.exit_code, 0) << run_.output;
  if (!have("ogrinfo") || !have("ogr2ogr")) GTEST_SKIP() << "ogrinfo / ogr2ogr (gdal-bin) not installed";
  const fs::path gpkg = dir_ / "out" / "buildings.gpkg";
  const json view = layer_geojson(gpkg, "roof_parts", dir_);
  const json table = layer_geojson(gpkg, "lod22_2d", dir_);
  ASSERT_EQ(view["features"].size(), table["features"].size());
  ASSERT_GE(view["features"].size(), 15u);
  for (std::size_t k = 0; k < view["features"].size(); ++k) {
    json expected = table["features"][k]["properties"];
    expected.erase("b3_h_maaiveld");
    EXPECT_EQ(view["features"][k]["properties"], expected);
    EXPECT_EQ(view["features"][k]["geometry"], table["features"][k]["geometry"]);
  }
}

TEST_F(Outputs, a_crs_taken_from_the_footprints_is_named_in_a_warning_and_stated_as_recorded) {
  ASSERT_EQ(run_.exit_code, 0) << run_.output;
  // The sample's LAS tiles record no CRS; its footprints are in RD New (2D).
  EXPECT_NE(run_.output.find("warning: input: the point clouds record no CRS: the run takes EPSG:28992 (Amersfoort / "
                             "RD New) from the footprints"),
            std::string::npos)
      << run_.output;
  EXPECT_NE(run_.output.find("give --crs EPSG:7415"), std::string::npos) << run_.output;
  const json city = read_json(dir_ / "out" / "buildings.city.json");
  EXPECT_EQ(city["metadata"]["referenceSystem"], "https://www.opengis.net/def/crs/EPSG/0/28992");
  EXPECT_EQ(city["metadata"]["city3d"]["crs_source"], "footprints");
  EXPECT_EQ(read_json(dir_ / "out" / "run.json")["crs_source"], "footprints");
}

TEST_F(Outputs, crs_option_states_the_heights_datum_in_every_output_without_a_warning) {
  const std::string d = CITY3D_SAMPLE_DATA;
  const fs::path out = dir_ / "crs";
  const Result r = run_shell(std::string(CITY3D_EXE) + " reconstruct " + d + "/delft_sample_1.las " + d +
                             "/delft_sample_2.las -f " + d + "/delft_sample_footprints.gpkg --id-field gml_id --gpkg "
                             "--cityjsonseq --no-html --no-progress --crs EPSG:28992+5709 -o " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("warning"), std::string::npos) << r.output;
  // EPSG:28992+5709 is known by a code of its own: EPSG:7415, RD New + NAP height (3DBAG's).
  const json city = read_json(out / "buildings.city.json");
  EXPECT_EQ(city["metadata"]["referenceSystem"], "https://www.opengis.net/def/crs/EPSG/0/7415");
  EXPECT_EQ(city["metadata"]["city3d"]["crs_source"], "--crs");
  EXPECT_EQ(json::parse(lines_of(read_file(out / "buildings.city.jsonl")).front())["metadata"]["referenceSystem"],
            "https://www.opengis.net/def/crs/EPSG/0/7415");
  EXPECT_EQ(read_json(out / "run.json")["crs"], "EPSG:7415");
  if (!have("ogrinfo")) return;
  for (const char* layer : {"buildings", "lod22_3d", "lod12_2d"}) {
    const Result info = run_shell("ogrinfo -ro -so " + (out / "buildings.gpkg").string() + " " + layer);
    EXPECT_NE(info.output.find("COMPOUNDCRS[\"Amersfoort / RD New + NAP height\""), std::string::npos)
        << layer << "\n" << info.output.substr(0, 600);
  }
}

TEST(OutputsCrs, crs_option_that_disagrees_with_the_tiles_record_is_an_error_naming_both) {
  const fs::path dir = fs::temp_directory_path() / ("city3d_crs_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const std::string las = std::string(CITY3D_TEST_DATA) + "/las/las14_pf7_extrabytes_geokeys.las";  // EPSG:28992
  const Result r = run_shell(std::string(CITY3D_EXE) + " reconstruct " + las + " --crs EPSG:32631 --no-progress -o " +
                             (dir / "out").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--crs EPSG:32631 is EPSG:32631 (WGS 84 / UTM zone 31N) but the point clouds record EPSG:28992"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
  const Result degrees = run_shell(std::string(CITY3D_EXE) + " reconstruct " + las + " --crs EPSG:4326 -o " + (dir / "out").string());
  EXPECT_EQ(degrees.exit_code, 2) << degrees.output;
  EXPECT_NE(degrees.output.find("option --crs: 'EPSG:4326' is geographic (degrees)"), std::string::npos) << degrees.output;
  const Result nonsense = run_shell(std::string(CITY3D_EXE) + " reconstruct " + las + " --crs EPSG:123456789 -o " + (dir / "out").string());
  EXPECT_EQ(nonsense.exit_code, 2) << nonsense.output;
  EXPECT_NE(nonsense.output.find("option --crs: 'EPSG:123456789' is no CRS"), std::string::npos) << nonsense.output;
  // A tileset needs a place on the globe: single-building clouds in a frame of their own have none.
  const Result tiles = run_shell(std::string(CITY3D_EXE) + " reconstruct " + std::string(CITY3D_TEST_DATA) +
                                 "/ply/little_endian_scalar_fields.ply --3dtiles -o " + (dir / "out").string());
  EXPECT_EQ(tiles.exit_code, 1) << tiles.output;
  EXPECT_NE(tiles.output.find("3dtiles: the run has no CRS (the point clouds record none)"), std::string::npos) << tiles.output;
  fs::remove_all(dir);
}

TEST_F(Outputs, cityjson_metadata_has_the_extent_of_its_vertices_the_version_and_the_run_parameters) {
  ASSERT_EQ(run_.exit_code, 0) << run_.output;
  const json city = read_json(dir_ / "out" / "buildings.city.json");
  const json& t = city["transform"];
  double lo[3] = {1e18, 1e18, 1e18}, hi[3] = {-1e18, -1e18, -1e18};
  for (const json& v : city["vertices"])
    for (int k = 0; k < 3; ++k) {
      const double w = v[k].get<double>() * t["scale"][k].get<double>() + t["translate"][k].get<double>();
      lo[k] = std::min(lo[k], w), hi[k] = std::max(hi[k], w);
    }
  const json& extent = city["metadata"]["geographicalExtent"];
  ASSERT_EQ(extent.size(), 6u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(extent[k].get<double>(), lo[k], 1e-9);
    EXPECT_NEAR(extent[k + 3].get<double>(), hi[k], 1e-9);
  }
  // CityJSONSeq's header has the same metadata, the extent of its features' vertices.
  const json seq = json::parse(lines_of(read_file(dir_ / "out" / "buildings.city.jsonl")).front());
  EXPECT_EQ(seq["metadata"], city["metadata"]);
  const json& meta = city["metadata"]["city3d"];
  EXPECT_EQ(meta["version"], CITY3D_VERSION);
  const json& p = meta["parameters"];
  EXPECT_EQ(p["lambda-data"], 0.34);
  EXPECT_EQ(p["min-points"], 20);
  EXPECT_EQ(p["lod"], json({"1.2", "1.3", "2.2"}));
  EXPECT_EQ(p["building-classes"], json({6}));
  EXPECT_EQ(p["gpkg"], true);
  EXPECT_TRUE(p["where"].is_null());
  // What does not change the outputs is not a parameter of them.
  for (const char* left_out : {"jobs", "output", "shard", "block-size", "group-area", "footprints", "id-field", "progress"})
    EXPECT_FALSE(p.contains(left_out)) << left_out;
}

TEST_F(Outputs, val3dity_codes_are_lists_in_cityjson_and_json_text_in_the_geopackage) {
  ASSERT_EQ(run_.exit_code, 0) << run_.output;
  const json city = read_json(dir_ / "out" / "buildings.city.json");
  std::size_t buildings = 0;
  for (const auto& [id, object] : city["CityObjects"].items()) {
    if (object["type"] != "Building") continue;
    ++buildings;
    for (const char* lod : {"b3_val3dity_lod12", "b3_val3dity_lod13", "b3_val3dity_lod22"}) {
      EXPECT_TRUE(object["attributes"][lod].is_array()) << id << " " << lod;  // not the string "[]"
      EXPECT_TRUE(object["attributes"][lod].empty()) << id << " " << lod;
    }
  }
  EXPECT_EQ(buildings, 15u);
  if (!have("ogrinfo")) return;
  const Result info = run_shell("ogrinfo -ro -so " + (dir_ / "out" / "buildings.gpkg").string() + " buildings");
  EXPECT_NE(info.output.find("b3_val3dity_lod22: String(JSON)"), std::string::npos) << info.output;
}

TEST_F(Outputs, obj_models_group_their_faces_by_semantic_surface_with_a_material_library) {
  ASSERT_EQ(run_.exit_code, 0) << run_.output;
  const json city = read_json(dir_ / "out" / "buildings.city.json");
  const std::string materials = read_file(dir_ / "out" / "models" / "city3d.mtl");
  for (const char* m : {"newmtl GroundSurface\nKd ", "newmtl WallSurface\nKd ", "newmtl RoofSurface\nKd "})
    EXPECT_NE(materials.find(m), std::string::npos) << materials;
  std::size_t models = 0;
  for (const std::string& id : building_ids(city)) {
    const std::vector<std::string> lines = lines_of(read_file(dir_ / "out" / "models" / (id + ".obj")));
    ASSERT_FALSE(lines.empty()) << id;
    ++models;
    EXPECT_NE(std::find(lines.begin(), lines.end(), "mtllib city3d.mtl"), lines.end()) << id;
    // The faces under each group: the CityJSON LoD2.2 faces of that type, grounds, walls, roofs.
    std::map<std::string, std::size_t> faces;
    std::vector<std::string> groups;
    std::string group;
    for (const std::string& line : lines) {
      if (line.rfind("g ", 0) == 0) groups.push_back(group = line.substr(2));
      if (line.rfind("usemtl ", 0) == 0) EXPECT_EQ(line.substr(7), group) << id;
      if (line.rfind("f ", 0) == 0) ++faces[group];
    }
    EXPECT_EQ(groups, std::vector<std::string>({"GroundSurface", "WallSurface", "RoofSurface"})) << id;
    std::map<std::string, std::size_t> expected;
    for (const std::string& type : cityjson_level(city, id, "2.2").types) ++expected[type];
    EXPECT_EQ(faces, expected) << id;
  }
  EXPECT_EQ(models, 15u);
}

TEST_F(Outputs, run_json_records_the_version_crs_inputs_and_parameters) {
  ASSERT_EQ(run_.exit_code, 0) << run_.output;
  const json run = read_json(dir_ / "out" / "run.json");
  EXPECT_EQ(run["city3d"], CITY3D_VERSION);
  EXPECT_EQ(run["crs"], "EPSG:28992");
  ASSERT_EQ(run["inputs"]["point_clouds"].size(), 2u);
  EXPECT_EQ(fs::path(run["inputs"]["point_clouds"][0].get<std::string>()).filename(), "delft_sample_1.las");
  EXPECT_TRUE(fs::path(run["inputs"]["point_clouds"][0].get<std::string>()).is_absolute());
  EXPECT_EQ(fs::path(run["inputs"]["footprints"].get<std::string>()).filename(), "footprints.geojson");
  EXPECT_EQ(run["inputs"]["id_field"], "gml_id");
  EXPECT_EQ(run["parameters"], read_json(dir_ / "out" / "buildings.city.json")["metadata"]["city3d"]["parameters"]);
}

namespace {

// report.html opened in headless Chromium with "#check" (the page then points at its first outline
// and logs what the hover shows and its scale bar); the console lines it logged.
std::vector<std::string> checked_page(const fs::path& html, const fs::path& scratch) {
  std::string browser;
  for (const char* b : {"chromium", "chromium-browser"})
    if (have(b)) browser = b;
  if (browser.empty()) return {};
  const Result r = run_shell("timeout 120 " + browser +
                             " --headless --no-sandbox --disable-gpu --disable-background-networking"
                             " --disable-component-update --disable-sync --no-first-run --user-data-dir=" +
                             (scratch / "chromium-check").string() + " --enable-logging=stderr --v=0 --window-size=1400,1600"
                             " --virtual-time-budget=5000 --screenshot=" + (scratch / "check.png").string() + " 'file://" +
                             html.string() + "#check'");
  std::vector<std::string> console;
  for (const std::string& line : lines_of(r.output)) {
    const auto at = line.find("\"city3d report");
    if (line.find(":CONSOLE") != std::string::npos && at != std::string::npos)
      console.push_back(line.substr(at + 1, line.find('"', at + 1) - at - 1));
    else if (line.find(":CONSOLE") != std::string::npos || line.find("Uncaught") != std::string::npos)
      console.push_back("unexpected: " + line);
  }
  return console;
}

// The logged map line: outlines, scale bar metres and pixels, map pixels and viewBox metres.
struct MapCheck {
  int outlines = 0;
  double metres = 0, pixels = 0, width = 0, height = 0, box_width = 0, box_height = 0;
};

MapCheck map_check(const std::vector<std::string>& console) {
  MapCheck m;
  for (const std::string& line : console) {
    std::smatch s;
    if (std::regex_search(line, s, std::regex("city3d report map: ([0-9]+) outlines; scale bar ([0-9.]+) m = ([0-9]+) px; "
                                              "map ([0-9.]+) x ([0-9.]+) px, ([0-9.]+) x ([0-9.]+) m")))
      m = {std::stoi(s[1]), std::stod(s[2]), std::stod(s[3]), std::stod(s[4]), std::stod(s[5]), std::stod(s[6]), std::stod(s[7])};
  }
  return m;
}

void expect_true_scale_bar(const MapCheck& m) {
  // A round length: 1, 2 or 5 times a power of ten metres ...
  const double power = std::pow(10.0, std::floor(std::log10(m.metres)));
  const double f = m.metres / power;
  EXPECT_TRUE(std::fabs(f - 1) < 1e-9 || std::fabs(f - 2) < 1e-9 || std::fabs(f - 5) < 1e-9) << m.metres;
  // ... drawn at the map's scale (the viewBox fitted into the map, aspect kept) ...
  const double per_metre = std::min(m.width / m.box_width, m.height / m.box_height);
  EXPECT_NEAR(m.pixels, m.metres * per_metre, 1.0);
  // ... of about a fifth of its width.
  EXPECT_GT(m.pixels, m.width / 12);
  EXPECT_LE(m.pixels, m.width / 5 + 1);
}

}  // namespace

TEST_F(Outputs, report_html_map_has_hover_a_true_scale_bar_and_the_inputs_and_parameters) {
  ASSERT_EQ(run_.exit_code, 0) << run_.output;
  const std::string page = read_file(dir_ / "out" / "report.html");
  EXPECT_NE(page.find("Inputs and parameters"), std::string::npos);
  // The page's data: the inputs and the parameters of the run, as run.json has them.
  const auto at = page.find("\"inputs\":");
  ASSERT_NE(at, std::string::npos);
  const json run = read_json(dir_ / "out" / "run.json");
  EXPECT_NE(page.find("\"inputs\":" + run["inputs"].dump()), std::string::npos);
  EXPECT_NE(page.find("\"parameters\":" + run["parameters"].dump()), std::string::npos);
  EXPECT_NE(page.find("\"crs_source\":\"footprints\""), std::string::npos);
  const std::vector<std::string> console = checked_page(dir_ / "out" / "report.html", dir_);
  if (console.empty()) GTEST_SKIP() << "chromium not installed (scripts/setup.sh test installs it)";
  for (const std::string& line : console) EXPECT_EQ(line.rfind("unexpected", 0), std::string::npos) << line;
  // Pointing at the first footprint shows its building's id, status, level and figures.
  const auto hover = std::find_if(console.begin(), console.end(), [](const std::string& l) { return l.rfind("city3d report hover: ", 0) == 0; });
  ASSERT_NE(hover, console.end());
  EXPECT_TRUE(std::regex_search(*hover, std::regex("hover: b[0-9a-f-]+ · ok · LoD2\\.2 · roof [0-9.]+ m · RMSE 0\\.[0-9]{3} m · [0-9]+ faces"))) << *hover;
  const MapCheck m = map_check(console);
  EXPECT_EQ(m.outlines, 15);  // the empty footprint has no outline
  expect_true_scale_bar(m);
  // The viewBox is the footprints' extent with 3% of its larger side around it (ogrinfo's extent).
  if (!have("ogrinfo")) return;
  const Result info = run_shell("ogrinfo -ro -so " + (dir_ / "out" / "buildings.gpkg").string() + " buildings");
  std::smatch e;
  ASSERT_TRUE(std::regex_search(info.output, e, std::regex("Extent: \\(([0-9.]+), ([0-9.]+)\\) - \\(([0-9.]+), ([0-9.]+)\\)"))) << info.output;
  const double w = std::stod(e[3]) - std::stod(e[1]), h = std::stod(e[4]) - std::stod(e[2]);
  EXPECT_NEAR(m.box_width, w + 0.06 * std::max(w, h), 0.02);
  EXPECT_NEAR(m.box_height, h + 0.06 * std::max(w, h), 0.02);
}

namespace {

// A single-building cloud as ASCII PLY: a flat roof of w x d metres at height h on a 0.3 m grid, and
// its walls down to z = 0 on a 0.5 m grid (so that its floor is at 0), turned by `angle` degrees, at
// (x0, y0) in a frame of its own.
void write_box_cloud(const fs::path& path, double w, double d, double h, double angle, double x0, double y0) {
  std::vector<std::array<double, 3>> points;
  for (double x = 0; x <= w + 1e-9; x += 0.3)
    for (double y = 0; y <= d + 1e-9; y += 0.3) points.push_back({x, y, h + 0.01 * std::sin(7 * x + 3 * y)});
  for (double z = 0; z < h; z += 0.5) {
    for (double x = 0; x <= w + 1e-9; x += 0.5) points.push_back({x, 0, z}), points.push_back({x, d, z});
    for (double y = 0; y <= d + 1e-9; y += 0.5) points.push_back({0, y, z}), points.push_back({w, y, z});
  }
  const double a = angle * 3.14159265358979 / 180, c = std::cos(a), s = std::sin(a);
  std::ofstream out(path);
  out << "ply\nformat ascii 1.0\nelement vertex " << points.size() << "\nproperty float x\nproperty float y\n"
      << "property float z\nend_header\n";
  for (const auto& p : points) out << x0 + c * p[0] - s * p[1] << " " << y0 + s * p[0] + c * p[1] << " " << p[2] << "\n";
}

}  // namespace

TEST(OutputsClouds, report_html_of_single_building_clouds_draws_the_outlines_inferred_from_their_points) {
  const fs::path dir = fs::temp_directory_path() / ("city3d_clouds_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  // Three buildings, each in a frame of its own (all near the origin: drawn where they are, they would
  // lie on one another): 12 x 8, 6 x 6 turned by 30 degrees, 20 x 5.
  write_box_cloud(dir / "a.ply", 12, 8, 6, 0, 0, 0);
  write_box_cloud(dir / "b.ply", 6, 6, 4, 30, 1, 1);
  write_box_cloud(dir / "c.ply", 20, 5, 9, 0, -2, 0);
  const Result r = run_shell(std::string(CITY3D_EXE) + " reconstruct " + (dir / "a.ply").string() + " " +
                             (dir / "b.ply").string() + " " + (dir / "c.ply").string() + " --no-progress -o " +
                             (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string page = read_file(dir / "out" / "report.html");
  EXPECT_NE(page.find("\"inferred\":true"), std::string::npos);
  // Each building's outline, laid out in a cell of its own: no two outlines' boxes meet, and each is
  // the size of its building's ground (12 x 8, 6 x 6 turned, 20 x 5 m, to within 0.5 m).
  std::vector<std::array<double, 4>> boxes;
  const std::regex row("\\{\"id\":\"([abc])\"[^\\n]*\"fp\":\\[(.*)\\]\\}");
  for (const std::string& line : lines_of(page)) {
    std::smatch m;
    if (!std::regex_search(line, m, row)) continue;
    std::array<double, 4> box{1e9, 1e9, -1e9, -1e9};
    const std::string rings = m[2];
    const std::regex point("\\[(-?[0-9.]+),(-?[0-9.]+)\\]");
    for (auto it = std::sregex_iterator(rings.begin(), rings.end(), point); it != std::sregex_iterator(); ++it) {
      const double x = std::stod((*it)[1]), y = std::stod((*it)[2]);
      box = {std::min(box[0], x), std::min(box[1], y), std::max(box[2], x), std::max(box[3], y)};
    }
    ASSERT_LT(box[0], box[2]) << "no outline for " << m[1];
    const double bw = box[2] - box[0], bh = box[3] - box[1];
    const std::string id = m[1];
    const double turned = 6 * (std::cos(0.5236) + std::sin(0.5236));
    const double want_w = id == "a" ? 12 : id == "b" ? turned : 20, want_h = id == "a" ? 8 : id == "b" ? turned : 5;
    EXPECT_NEAR(bw, want_w, 0.5) << id;
    EXPECT_NEAR(bh, want_h, 0.5) << id;
    boxes.push_back(box);
  }
  ASSERT_EQ(boxes.size(), 3u);
  for (std::size_t i = 0; i < boxes.size(); ++i)
    for (std::size_t j = i + 1; j < boxes.size(); ++j)
      EXPECT_TRUE(boxes[i][2] < boxes[j][0] || boxes[j][2] < boxes[i][0] || boxes[i][3] < boxes[j][1] || boxes[j][3] < boxes[i][1])
          << i << " and " << j << " overlap";
  const std::vector<std::string> console = checked_page(dir / "out" / "report.html", dir);
  if (console.empty()) GTEST_SKIP() << "chromium not installed (scripts/setup.sh test installs it)";
  for (const std::string& line : console) EXPECT_EQ(line.rfind("unexpected", 0), std::string::npos) << line;
  const MapCheck m = map_check(console);
  EXPECT_EQ(m.outlines, 3);
  expect_true_scale_bar(m);
  EXPECT_NE(page.find("Outlines inferred from the points"), std::string::npos);
  fs::remove_all(dir);
}

namespace {

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> fields;
  std::stringstream ss(text);
  for (std::string field; std::getline(ss, field, separator);) fields.push_back(field);
  if (!text.empty() && text.back() == separator) fields.emplace_back();
  return fields;
}

}  // namespace

// report.json's row is made with nlohmann (issue 26): the CSV's columns as keys, in the CSV's order,
// and every number the value CSV prints (rounded half away from zero, 6.5215 -> 6.522 as CityJSON
// rounds it; -0 as 0), counts as integers, null where the CSV cell is empty.
TEST(ReportRows, a_json_row_has_the_csv_columns_in_order_and_the_values_csv_prints) {
  city3d::BuildingReport r;
  r.id = "b1<&>";
  r.status = city3d::BuildingStatus::ok;
  r.level = city3d::ModelLevel::lod22;
  r.note = "a note";
  r.points = 72;
  r.ground_z = -0.0004;  // -0 once rounded
  r.roof_z = 2.39;
  r.rmse = -1.0;  // no model: null
  r.valid = true;
  r.lods = "2.2";  // one level: no comma, so that the CSV row splits at every comma
  r.footprint_area = 68.845;
  r.h_roof_50p = 6.5215;  // printf alone writes 6.521
  r.h_roof_70p = 1e16;    // beyond 1e15: as it is
  r.unexplained_points = 12;
  r.coverage = std::nan("");
  r.cpu_seconds = 0.01234;
  r.seconds = 0.5;
  const std::string text = city3d::detail::report_json_row(r);
  EXPECT_EQ(text.find('\n'), std::string::npos) << text;
  EXPECT_EQ(text.find("-0"), std::string::npos) << text;
  const nlohmann::ordered_json row = nlohmann::ordered_json::parse(text);
  const std::vector<std::string> columns = split(city3d::detail::report_csv_header(), ',');
  const std::vector<std::string> cells = split(city3d::detail::report_csv_row(r), ',');
  ASSERT_EQ(cells.size(), columns.size());
  std::vector<std::string> keys;
  for (const auto& item : row.items()) keys.push_back(item.key());
  EXPECT_EQ(keys, columns);
  for (std::size_t k = 0; k < columns.size() && k < keys.size(); ++k) {
    const auto& v = row[columns[k]];
    if (v.is_string()) EXPECT_EQ(v.get<std::string>(), cells[k]) << columns[k];
    else if (v.is_boolean()) EXPECT_EQ(v.get<bool>() ? "1" : "0", cells[k]) << columns[k];
    else if (v.is_null()) EXPECT_EQ(cells[k], "") << columns[k];
    else EXPECT_EQ(v.get<double>(), std::stod(cells[k])) << columns[k] << ": " << cells[k];
  }
  EXPECT_EQ(row["h_roof_50p"].get<double>(), 6.522);
  EXPECT_EQ(row["footprint_area"].get<double>(), 68.85);
  EXPECT_EQ(row["h_roof_70p"].get<double>(), 1e16);
  EXPECT_TRUE(row["ground_z"].is_number_float());
  EXPECT_EQ(row["ground_z"].get<double>(), 0.0);
  EXPECT_TRUE(row["points"].is_number_unsigned());
  EXPECT_TRUE(row["unexplained_points"].is_number_integer());
  EXPECT_EQ(row["unexplained_points"].get<int>(), 12);
  EXPECT_TRUE(row["rmse"].is_null());
  EXPECT_TRUE(row["coverage"].is_null());
  EXPECT_EQ(row["valid"], true);
  EXPECT_EQ(row["cpu_seconds"].get<double>(), 0.0123);
}

// The GeoPackage and the 3D Tiles take a building's attributes from its overview record, read back from
// the report.json row the journal keeps: every attribute a building has in the CityJSON must come back
// from that row with its value (building_coverage once came back null in both).
TEST(ReportRows, the_overview_record_read_from_a_json_row_has_every_output_attribute_of_the_report) {
  city3d::BuildingReport r;
  r.id = "b7";
  r.status = city3d::BuildingStatus::fallback;
  r.level = city3d::ModelLevel::lod22_footprint_walls;
  r.reason = "a reason";
  r.note = "a note";
  r.lods = "1.2,1.3,2.2";
  r.lods_reconstructed = "1.3,2.2";
  r.ground_z = 1.25;
  r.ground_method = "footprint ring";
  r.h_roof_50p = 6.5, r.h_roof_70p = 7.25, r.h_roof_min = 2.5, r.h_roof_max = 9.75, r.h_ridge = 9.5;
  r.roof_type = "slanted";
  r.volume_lod12 = 101.5, r.volume_lod13 = 102.5, r.volume_lod22 = 103.5;
  r.rmse_lod12 = 0.5, r.rmse_lod13 = 0.25, r.rmse_lod22 = 0.125;
  r.unexplained_points = 17;
  r.unexplained_share = 0.0625;
  r.unsupported_area = 1.5;
  r.height_excess = 0.75;
  r.validity_found = "lod22: 203 NON_PLANAR_POLYGON_DISTANCE_PLANE";
  r.repairs = "snapped";
  r.footprint_area = 68.5;
  r.point_density = 9.5;
  r.coverage = 0.875, r.point_coverage = 0.625, r.building_coverage = 0.75;
  r.points = 650, r.planes = 3, r.faces = 21;
  const city3d::Attributes written = city3d::detail::output_attributes(r, {}, false);
  const city3d::OverviewRecord read =
      city3d::overview_record(city3d::detail::report_json_row(r), "", {}, 0.001, {0, 0, 0}, 0, false);
  const city3d::Attributes back = city3d::detail::output_attributes(read.report, {}, false);
  ASSERT_EQ(back.size(), written.size());
  for (std::size_t k = 0; k < written.size(); ++k) {
    EXPECT_EQ(back[k].first, written[k].first);
    EXPECT_TRUE(back[k].second == written[k].second) << written[k].first << " did not come back";
  }
  for (const auto& [name, value] : written)  // the row above gives every attribute a value
    EXPECT_FALSE(std::holds_alternative<std::monostate>(value)) << name;
}

// A footprint field whose name the GeoPackage's buildings layer has already, in any case (id, STATUS, a
// footprint_status of its own), made the GeoPackage fail after the whole run: it is renamed, the same in
// every output, and nothing is lost.
TEST(OutputsNames, footprint_fields_named_as_city3ds_own_in_any_case_are_renamed_and_kept) {
  if (!have("ogrinfo") || !have("ogr2ogr")) GTEST_SKIP() << "ogrinfo / ogr2ogr (gdal-bin) not installed";
  const fs::path dir = fs::temp_directory_path() / ("city3d_names_test_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string d = CITY3D_SAMPLE_DATA;
  const fs::path footprints = dir / "names.gpkg";
  const Result conv =
      run_shell("ogr2ogr " + footprints.string() + " " + d + "/delft_sample_footprints.gpkg -nln fp " +
                "-sql \"SELECT gml_id, gml_id AS id, bgt_status AS STATUS, 'own' AS footprint_status, " +
                "GEOMETRY FROM buildingpart\"");
  ASSERT_EQ(conv.exit_code, 0) << conv.output;
  const Result run = run_shell(
      std::string(CITY3D_EXE) + " reconstruct " + d + "/delft_sample_1.las " + d + "/delft_sample_2.las -f " +
      footprints.string() + " --id-field gml_id --gpkg --no-html --no-progress -o " + (dir / "out").string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const Result fields =
      run_shell("ogrinfo -ro -so " + (dir / "out" / "buildings.gpkg").string() + " buildings");
  for (const char* field : {"id: String", "footprint_id: String", "footprint_STATUS_2: String",
                            "footprint_status: String", "status: String"})
    EXPECT_NE(fields.output.find(field), std::string::npos) << field << "\n" << fields.output;
  const json city = read_json(dir / "out" / "buildings.city.json");
  const json& attributes = city["CityObjects"][building_ids(city).front()]["attributes"];
  EXPECT_EQ(attributes["footprint_status"], "own");
  EXPECT_TRUE(attributes.contains("footprint_STATUS_2")) << attributes.dump();
  EXPECT_EQ(attributes["footprint_id"], building_ids(city).front());
  EXPECT_EQ(attributes["status"], "ok");
  fs::remove_all(dir);
}

namespace {

// The records of a run held in memory.
class HeldRecords : public city3d::OverviewSource {
 public:
  explicit HeldRecords(std::vector<city3d::OverviewRecord> records) : records_(std::move(records)) {}
  std::size_t size() const override { return records_.size(); }
  city3d::OverviewRecord at(std::size_t k, bool) const override { return records_.at(k); }

 private:
  std::vector<city3d::OverviewRecord> records_;
};

}  // namespace

// report.html's data is made with nlohmann (issue 26), then '<', '>' and '&' escaped: texts of the
// records and of the run that hold "</script>" cannot end the data's <script> element, and the data
// parses back to what they hold; numbers as the page rounds them (8, not 8.0).
TEST(ReportPage, its_data_cannot_close_its_script_element_and_parses_back_to_the_records) {
  const fs::path dir = fs::temp_directory_path() / ("city3d_page_data_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  city3d::OverviewRecord record;
  record.report.id = "x</script><!--&\"\n";
  record.report.status = city3d::BuildingStatus::failed;
  record.report.reason = "a < b & c > d";
  record.report.seconds = 1.23456;
  record.report.footprint_area = 24.75;
  record.footprint = {{{{10.25, 20.5}, {15.75, 20.5}, {15.75, 25}, {10.25, 25}}, {}}};
  const city3d::RunDescription run{"EPSG:28992", "--crs", R"({"footprints":"a</script>&b.gpkg"})", R"({"lod":["2.2"]})"};
  const fs::path html = dir / "report.html";
  city3d::write_report_html(html.string(), HeldRecords({record}), run);
  const std::string page = read_file(html);
  const std::string open = "<script id=\"data\" type=\"application/json\">";
  const auto begin = page.find(open);
  ASSERT_NE(begin, std::string::npos);
  const auto end = page.find("</script>", begin);
  ASSERT_NE(end, std::string::npos);
  const std::string data = page.substr(begin + open.size(), end - begin - open.size());
  EXPECT_EQ(data.find_first_of("<>&"), std::string::npos) << data;
  const json d = json::parse(data);
  ASSERT_EQ(d["buildings"].size(), 1u);
  const json& b = d["buildings"][0];
  EXPECT_EQ(b["id"], record.report.id);
  EXPECT_EQ(b["s"], "failed");
  EXPECT_EQ(b["r"], record.report.reason);
  EXPECT_EQ(b["t"], 1.235);
  EXPECT_EQ(b["fa"], 24.75);
  EXPECT_TRUE(b["rmse"].is_null());
  EXPECT_EQ(b["m"], -1);  // no model shown
  // The footprint relative to the extent's corner rounded down (10, 20), in metres to the centimetre.
  EXPECT_EQ(b["fp"].dump(), "[[[0.25,0.5],[5.75,0.5],[5.75,5],[0.25,5]]]");
  EXPECT_EQ(d["inputs"]["footprints"], "a</script>&b.gpkg");
  EXPECT_EQ(d["parameters"]["lod"][0], "2.2");
  EXPECT_EQ(d["crs"], "EPSG:28992");
  EXPECT_EQ(d["inferred"], false);
  EXPECT_TRUE(d["models"].empty());
  fs::remove_all(dir);
}

// A run's records, a box model each (of 8 to 400 vertices: the first ones are kept between the page's
// passes, the later ones read again), with statuses and RMSEs that order the models shown.
std::vector<city3d::OverviewRecord> box_records(std::size_t n) {
  std::vector<city3d::OverviewRecord> records(n);
  for (std::size_t k = 0; k < n; ++k) {
    city3d::OverviewRecord& r = records[k];
    r.report.id = "b" + std::to_string(k);
    r.report.status = k % 7 == 0 ? city3d::BuildingStatus::fallback : city3d::BuildingStatus::ok;
    r.report.rmse = 0.01 * static_cast<double>((k * 37) % 101);
    r.report.seconds = 0.001 * static_cast<double>(k);
    r.report.footprint_area = 100;
    const double x = 20.0 * static_cast<double>(k % 20), y = 20.0 * static_cast<double>(k / 20);
    r.footprint = {{{{x, y}, {x + 10, y}, {x + 10, y + 10}, {x, y + 10}}, {}}};
    city3d::CityGeometry level;
    city3d::PolygonMesh& mesh = level.model.mesh;
    for (int z = 0; z < 2; ++z)
      for (const auto& [px, py] : std::vector<std::pair<double, double>>{{0, 0}, {10, 0}, {10, 10}, {0, 10}})
        mesh.vertices.push_back({x + px, y + py, 5.0 * z});
    mesh.faces = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
    // Unused vertices make the large models that the page's vertex budgets weigh.
    for (std::size_t extra = 0; extra < (k * 13) % 392; ++extra) mesh.vertices.push_back({x, y, 0});
    r.lods.push_back(level);
  }
  return records;
}

// The same records from several threads give the same page as from one; a record that cannot be
// read is reported as the first such record in output order, whichever thread read it first.
TEST(ReportPage, is_the_same_page_whatever_the_threads_and_names_the_first_bad_record) {
  const fs::path dir = fs::temp_directory_path() / ("city3d_page_threads_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const HeldRecords records(box_records(700));
  const city3d::RunDescription run{"EPSG:28992", "--crs", "{}", "{}"};
  city3d::write_report_html((dir / "one.html").string(), records, run, 1);
  city3d::write_report_html((dir / "four.html").string(), records, run, 4);
  const std::string one = read_file(dir / "one.html");
  EXPECT_EQ(one, read_file(dir / "four.html"));
  EXPECT_NE(one.find("\"id\":\"b699\""), std::string::npos);

  class Failing : public city3d::OverviewSource {
   public:
    explicit Failing(const HeldRecords& held) : held_(held) {}
    std::size_t size() const override { return held_.size(); }
    city3d::OverviewRecord at(std::size_t k, bool levels) const override {
      if (k == 150 || k == 151 || k == 190)
        throw city3d::IoError("record " + std::to_string(k) + " is damaged");
      return held_.at(k, levels);
    }

   private:
    const HeldRecords& held_;
  };
  for (int round = 0; round < 20; ++round) {
    try {
      city3d::write_report_html((dir / "bad.html").string(), Failing(records), run, 4);
      ADD_FAILURE() << "no error";
    } catch (const city3d::IoError& e) {
      EXPECT_STREQ(e.what(), "record 150 is damaged");
    }
  }
  EXPECT_FALSE(fs::exists(dir / "bad.html"));
  fs::remove_all(dir);
}
