// End-to-end tests of the 3D Tiles output (--3dtiles) on the sample block, and on the Delft block when
// ../shared/data is there: the tileset's structure as 3D Tiles 1.1 asks it (regions that hold their
// children, geometric errors that shrink to 0), every glTF valid by the Khronos validator, each
// building once in the coarse (LoD1.2) and once in the fine (LoD2.2) tiles with its id and attributes
// as EXT_mesh_features / EXT_structural_metadata, vertices where PROJ (through gdaltransform) puts
// the CityJSON's, and CesiumJS (local, no network) drawing and picking the buildings in headless
// Chromium, checked on its screenshot.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "city3d/footprint_io.hpp"
#include "read_png.hpp"

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

struct Result {
  int exit_code = -1;
  std::string output;
};

Result run_shell(const std::string& command) {
  Result r;
  std::FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  char buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, pipe)) > 0) r.output.append(buf, n);
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

bool have(const char* program) { return run_shell(std::string("command -v ") + program + " > /dev/null").exit_code == 0; }

// --- reading what was written --------------------------------------------------------------------

// A binary glTF: its JSON and its BIN chunk, checked against the GLB layout (and the 8-byte
// alignment EXT_structural_metadata asks for).
struct Glb {
  json gltf;
  std::string bin;
};

Glb read_glb(const fs::path& path) {
  const std::string bytes = read_file(path);
  Glb glb;
  const auto u32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
  };
  EXPECT_GE(bytes.size(), 28u) << path;
  if (bytes.size() < 28) return glb;
  EXPECT_EQ(bytes.substr(0, 4), "glTF") << path;
  EXPECT_EQ(u32(4), 2u) << path;
  EXPECT_EQ(u32(8), bytes.size()) << path;
  const std::uint32_t json_length = u32(12);
  EXPECT_EQ(bytes.substr(16, 4), "JSON") << path;
  EXPECT_EQ(json_length % 8, 0u) << path;
  glb.gltf = json::parse(bytes.substr(20, json_length));
  const std::size_t bin_at = 20 + json_length;
  const std::uint32_t bin_length = u32(bin_at);
  EXPECT_EQ(bytes.substr(bin_at + 4, 4), std::string("BIN\0", 4)) << path;
  EXPECT_EQ(bin_length % 8, 0u) << path;
  glb.bin = bytes.substr(bin_at + 8, bin_length);
  return glb;
}

template <typename T>
std::vector<T> view_values(const Glb& g, int view_index) {
  const json& view = g.gltf["bufferViews"][view_index];
  const std::size_t offset = view.value("byteOffset", 0), length = view["byteLength"];
  EXPECT_EQ(offset % 8, 0u);
  std::vector<T> values(length / sizeof(T));
  std::memcpy(values.data(), g.bin.data() + offset, values.size() * sizeof(T));
  return values;
}

template <typename T>
std::vector<T> accessor_values(const Glb& g, int accessor_index) {
  const json& a = g.gltf["accessors"][accessor_index];
  std::vector<T> values = view_values<T>(g, a["bufferView"]);
  return values;
}

// One column of a glTF's property table: every row's value as text ("" for a left-out column).
std::vector<std::string> property_column(const Glb& g, const std::string& name) {
  const json& ext = g.gltf["extensions"]["EXT_structural_metadata"];
  const json& table = ext["propertyTables"][0];
  const std::size_t count = table["count"];
  const json& cls = ext["schema"]["classes"][table["class"].get<std::string>()]["properties"][name];
  std::vector<std::string> column(count);
  if (!table["properties"].contains(name)) return column;
  const json& p = table["properties"][name];
  if (cls["type"] == "STRING") {
    const std::vector<std::uint32_t> offsets = view_values<std::uint32_t>(g, p["stringOffsets"]);
    const json& view = g.gltf["bufferViews"][p["values"].get<int>()];
    const std::string text = g.bin.substr(view.value("byteOffset", 0), view["byteLength"].get<std::size_t>());
    EXPECT_EQ(offsets.size(), count + 1);
    for (std::size_t k = 0; k < count; ++k) column[k] = text.substr(offsets[k], offsets[k + 1] - offsets[k]);
  } else if (cls["componentType"] == "FLOAT64") {
    const std::vector<double> v = view_values<double>(g, p["values"]);
    EXPECT_EQ(v.size(), count);
    for (std::size_t k = 0; k < count; ++k) column[k] = v[k] == cls["noData"].get<double>() ? "" : json(v[k]).dump();
  } else {
    const std::vector<std::int64_t> v = view_values<std::int64_t>(g, p["values"]);
    EXPECT_EQ(v.size(), count);
    for (std::size_t k = 0; k < count; ++k) column[k] = v[k] == cls["noData"].get<std::int64_t>() ? "" : std::to_string(v[k]);
  }
  return column;
}

// The tiles of a tileset: each tile object with its accumulated transform.
struct TileRef {
  const json* tile;
  std::array<double, 16> transform;  // column-major
};

std::array<double, 16> multiply(const std::array<double, 16>& a, const std::array<double, 16>& b) {
  std::array<double, 16> c{};
  for (int col = 0; col < 4; ++col)
    for (int row = 0; row < 4; ++row)
      for (int k = 0; k < 4; ++k) c[col * 4 + row] += a[k * 4 + row] * b[col * 4 + k];
  return c;
}

void collect_tiles(const json& tile, const std::array<double, 16>& parent, std::vector<TileRef>& out) {
  std::array<double, 16> t = parent;
  if (tile.contains("transform")) t = multiply(parent, tile["transform"].get<std::array<double, 16>>());
  out.push_back({&tile, t});
  if (tile.contains("children"))  // not value(): the children must be the tileset's own, not a copy's
    for (const json& child : tile["children"]) collect_tiles(child, t, out);
}

constexpr std::array<double, 16> kIdentity = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

// ECEF (WGS 84) to longitude, latitude (degrees) and ellipsoidal height (Bowring, then refined).
std::array<double, 3> geodetic(double x, double y, double z) {
  const double a = 6378137.0, f = 1 / 298.257223563, e2 = f * (2 - f);
  const double p = std::hypot(x, y), lon = std::atan2(y, x);
  double lat = std::atan2(z, p * (1 - e2)), h = 0;
  for (int k = 0; k < 10; ++k) {
    const double n = a / std::sqrt(1 - e2 * std::sin(lat) * std::sin(lat));
    h = p / std::cos(lat) - n;
    lat = std::atan2(z, p * (1 - e2 * n / (n + h)));
  }
  return {lon * 180 / M_PI, lat * 180 / M_PI, h};
}

// Every vertex of a tile's glTF on the globe (lon, lat, h), with the building (feature ID) it belongs to.
struct GlobeVertex {
  double lon, lat, h;
  int feature;
};

std::vector<GlobeVertex> globe_vertices(const Glb& g, const std::array<double, 16>& m) {
  std::vector<GlobeVertex> out;
  for (const json& primitive : g.gltf["meshes"][0]["primitives"]) {
    const std::vector<float> p = accessor_values<float>(g, primitive["attributes"]["POSITION"]);
    const std::vector<float> f = accessor_values<float>(g, primitive["attributes"]["_FEATURE_ID_0"]);
    for (std::size_t k = 0; k < f.size(); ++k) {
      // glTF's y-up to the tile's z-up: (x, y, z) -> (x, -z, y); then the tile transform.
      const double v[4] = {p[3 * k], -double(p[3 * k + 2]), p[3 * k + 1], 1.0};
      double w[3] = {0, 0, 0};
      for (int row = 0; row < 3; ++row)
        for (int col = 0; col < 4; ++col) w[row] += m[col * 4 + row] * v[col];
      const auto g3 = geodetic(w[0], w[1], w[2]);
      out.push_back({g3[0], g3[1], g3[2], static_cast<int>(f[k])});
    }
  }
  return out;
}

// CityJSON vertices of a building's level, in metres.
std::vector<std::array<double, 3>> cityjson_vertices(const json& city, const std::string& id, const std::string& lod) {
  std::vector<std::array<double, 3>> vertices;
  const json& t = city["transform"];
  std::set<std::size_t> seen;
  const auto add = [&](const json& object) {
    for (const json& g : object.value("geometry", json::array())) {
      if (g["lod"] != lod) continue;
      for (const json& face : g["boundaries"][0])
        for (const json& v : face[0])
          if (seen.insert(v.get<std::size_t>()).second) {
            const json& q = city["vertices"][v.get<std::size_t>()];
            vertices.push_back({q[0].get<double>() * t["scale"][0].get<double>() + t["translate"][0].get<double>(),
                                q[1].get<double>() * t["scale"][1].get<double>() + t["translate"][1].get<double>(),
                                q[2].get<double>() * t["scale"][2].get<double>() + t["translate"][2].get<double>()});
          }
    }
  };
  const json& b = city["CityObjects"][id];
  add(b);
  for (const json& child : b.value("children", json::array())) add(city["CityObjects"][child.get<std::string>()]);
  return vertices;
}

// Points through gdaltransform (PROJ as GDAL uses it), one line each.
std::vector<std::array<double, 3>> gdaltransform(const std::vector<std::array<double, 3>>& points, const std::string& from,
                                                 const std::string& to, const fs::path& scratch) {
  const fs::path in = scratch / "points.txt";
  {
    std::ofstream out(in);
    out.precision(17);
    for (const auto& p : points) out << p[0] << " " << p[1] << " " << p[2] << "\n";
  }
  const Result r = run_shell("gdaltransform -s_srs " + from + " -t_srs " + to + " < " + in.string());
  std::vector<std::array<double, 3>> result;
  std::stringstream lines(r.output);
  for (std::string line; std::getline(lines, line);) {
    std::array<double, 3> p;
    if (std::sscanf(line.c_str(), "%lf %lf %lf", &p[0], &p[1], &p[2]) == 3) result.push_back(p);
  }
  EXPECT_EQ(result.size(), points.size()) << r.output.substr(0, 400);
  return result;
}

double metres_between(double lon1, double lat1, double lon2, double lat2) {
  const double r = 6371000, k = M_PI / 180;
  return r * std::hypot((lon2 - lon1) * k * std::cos(lat1 * k), (lat2 - lat1) * k);
}

// The tileset in CesiumJS (tests/tools/cesium_viewer.html, Cesium from build/tools/cesium) in
// headless Chromium, with SwiftShader for WebGL: the JSON line the page logs when every tile the
// view needs is drawn, and its screenshot. Empty when Chromium or Cesium is missing.
json cesium_view(const fs::path& tileset, const fs::path& shot, const fs::path& scratch) {
  const fs::path cesium = fs::path(CITY3D_TOOLS) / "cesium";
  std::string browser;
  for (const char* b : {"chromium", "chromium-browser"})
    if (have(b)) browser = b;
  if (browser.empty() || !fs::exists(cesium / "Cesium.js")) return json();
  const std::string url = "file://" + std::string(CITY3D_SOURCE) + "/tests/tools/cesium_viewer.html?cesium=file://" +
                          cesium.string() + "/&tileset=file://" + tileset.string() + "&pick=1";
  const Result r = run_shell("timeout 300 " + browser +
                             " --headless --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader"
                             " --allow-file-access-from-files --disable-background-networking --disable-component-update"
                             " --disable-sync --no-first-run --user-data-dir=" + (scratch / "chromium").string() +
                             " --enable-logging=stderr --v=0 --window-size=800,600 --virtual-time-budget=180000"
                             " --screenshot=" + shot.string() + " '" + url + "'");
  for (const std::string& marker : {std::string("city3d viewer ready "), std::string("city3d viewer failed")}) {
    const auto at = r.output.find(marker);
    if (at == std::string::npos) continue;
    if (marker.find("failed") != std::string::npos) {
      ADD_FAILURE() << r.output.substr(at, 600);
      return json::object();
    }
    const auto end = r.output.find("\", source:", at);
    std::string text = r.output.substr(at + marker.size(), end - at - marker.size());
    return json::parse(text);
  }
  ADD_FAILURE() << "the viewer logged nothing:\n" << r.output.substr(0, 3000);
  return json::object();
}

// What a screenshot of the tileset shows: pixels that are not the white background in its middle
// part and in its outer band, and of those the reddish ones (the roofs).
struct Pixels {
  std::size_t middle = 0, middle_drawn = 0, middle_roof = 0, border = 0, border_drawn = 0;
};

Pixels count_pixels(const fs::path& png) {
  Pixels p;
  const city3d::test::PngPixels image = city3d::test::read_png(png.string());
  EXPECT_FALSE(image.samples.empty()) << png;
  EXPECT_GE(image.bands, 3) << png << ": not a colour image";
  if (image.samples.empty() || image.bands < 3) return p;
  const int w = image.width, h = image.height;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int r = image.at(x, y, 0), g = image.at(x, y, 1), b = image.at(x, y, 2);
      const bool drawn = r < 235 || g < 235 || b < 235;
      const bool roof = r > g + 15 && r > b + 15;
      const bool middle = x > w / 4 && x < 3 * w / 4 && y > h / 4 && y < 3 * h / 4;
      const bool border = x < w / 20 || x >= w - w / 20 || y < h / 20 || y >= h - h / 20;
      if (middle) ++p.middle, p.middle_drawn += drawn, p.middle_roof += drawn && roof;
      if (border) ++p.border, p.border_drawn += drawn;
    }
  return p;
}

// One run with --3dtiles, shared by the tests of a fixture.
struct TileRun {
  fs::path out;
  Result result;
  json city;
  json tileset;
  std::vector<TileRef> tiles;
};

void make_run(TileRun& run, const fs::path& out, const std::string& arguments) {
  run.out = out;
  fs::remove_all(out);
  run.result = run_shell(std::string(CITY3D_EXE) + " reconstruct " + arguments + " --no-progress -o " + out.string());
  if (run.result.exit_code != 0) return;
  run.city = json::parse(read_file(out / "buildings.city.json"));
  run.tileset = json::parse(read_file(out / "3dtiles" / "tileset.json"));
  collect_tiles(run.tileset["root"], kIdentity, run.tiles);
}

std::vector<std::string> building_ids(const json& city) {
  std::vector<std::string> ids;
  for (const auto& [id, object] : city["CityObjects"].items())
    if (object["type"] == "Building") ids.push_back(id);
  std::sort(ids.begin(), ids.end());
  return ids;
}

// --- the checks, for the sample and the Delft block alike ---------------------------------------

// 3D Tiles 1.1: version, every tile's region holds its children's, geometric errors never grow
// towards the leaves and are 0 at the finest, REPLACE refinement, content files that exist, and
// tile transforms that are rotations (east, north, up) with a translation on the globe.
void expect_valid_tileset(const TileRun& run) {
  const json& t = run.tileset;
  EXPECT_EQ(t["asset"]["version"], "1.1");
  EXPECT_EQ(t["asset"]["generator"], std::string("city3d ") + CITY3D_VERSION);
  EXPECT_GE(t["geometricError"].get<double>(), t["root"]["geometricError"].get<double>());
  std::size_t contents = 0;
  std::function<void(const json&)> walk = [&](const json& tile) {
    const auto region = tile["boundingVolume"]["region"].get<std::vector<double>>();
    ASSERT_EQ(region.size(), 6u);
    EXPECT_LT(region[0], region[2]);
    EXPECT_LT(region[1], region[3]);
    EXPECT_LE(region[4], region[5]);
    EXPECT_EQ(tile["refine"], "REPLACE");
    if (tile.contains("content")) {
      ++contents;
      const fs::path file = run.out / "3dtiles" / tile["content"]["uri"].get<std::string>();
      EXPECT_TRUE(fs::exists(file)) << file;
    }
    if (!tile.contains("children")) EXPECT_EQ(tile["geometricError"].get<double>(), 0.0);
    if (tile.contains("transform")) {
      const auto m = tile["transform"].get<std::array<double, 16>>();
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          double d = 0;
          for (int k = 0; k < 3; ++k) d += m[a * 4 + k] * m[b * 4 + k];
          EXPECT_NEAR(d, a == b ? 1.0 : 0.0, 1e-9);
        }
      EXPECT_NEAR(std::sqrt(m[12] * m[12] + m[13] * m[13] + m[14] * m[14]), 6.37e6, 0.03e6);  // on the Earth
    }
    for (const json& child : tile.value("children", json::array())) {
      EXPECT_LE(child["geometricError"].get<double>(), tile["geometricError"].get<double>());
      const auto inner = child["boundingVolume"]["region"].get<std::vector<double>>();
      EXPECT_GE(inner[0], region[0] - 1e-12);
      EXPECT_GE(inner[1], region[1] - 1e-12);
      EXPECT_LE(inner[2], region[2] + 1e-12);
      EXPECT_LE(inner[3], region[3] + 1e-12);
      EXPECT_GE(inner[4], region[4] - 1e-6);
      EXPECT_LE(inner[5], region[5] + 1e-6);
      walk(child);
    }
  };
  walk(t["root"]);
  EXPECT_GT(contents, 0u);
}

// Every building with a model once in the coarse tiles (its LoD1.2) and once in the fine tiles (its
// LoD2.2), its id and attributes in the property table as the CityJSON has them, each feature ID in
// range and drawn, each primitive of one semantic surface with its material.
void expect_buildings_as_metadata(const TileRun& run) {
  std::multiset<std::string> coarse, fine;
  for (const TileRef& ref : run.tiles) {
    if (!ref.tile->contains("content")) continue;
    const std::string uri = (*ref.tile)["content"]["uri"];
    const Glb g = read_glb(run.out / "3dtiles" / uri);
    const bool is_fine = uri.find("_fine.glb") != std::string::npos;
    ASSERT_EQ(g.gltf["extensionsUsed"], json({"EXT_mesh_features", "EXT_structural_metadata"}));
    const std::vector<std::string> ids = property_column(g, "id");
    const std::vector<std::string> lods = property_column(g, "lod");
    const std::vector<std::string> h70 = property_column(g, "b3_h_dak_70p");
    const std::vector<std::string> volume = property_column(g, "b3_volume_lod22");
    std::vector<bool> drawn(ids.size(), false);
    for (const json& primitive : g.gltf["meshes"][0]["primitives"]) {
      const json& ids_ext = primitive["extensions"]["EXT_mesh_features"]["featureIds"][0];
      EXPECT_EQ(ids_ext["featureCount"], ids.size());
      EXPECT_EQ(ids_ext["propertyTable"], 0);
      const std::string material = g.gltf["materials"][primitive["material"].get<int>()]["name"];
      EXPECT_TRUE(material == "GroundSurface" || material == "WallSurface" || material == "RoofSurface") << material;
      const std::vector<float> features = accessor_values<float>(g, primitive["attributes"]["_FEATURE_ID_0"]);
      const std::vector<std::uint32_t> indices = accessor_values<std::uint32_t>(g, primitive["indices"]);
      EXPECT_EQ(indices.size() % 3, 0u);
      for (std::uint32_t i : indices) {
        ASSERT_LT(i, features.size());
        ASSERT_GE(features[i], 0.0f);
        ASSERT_LT(features[i], static_cast<float>(ids.size()));
        drawn[static_cast<std::size_t>(features[i])] = true;
      }
    }
    for (std::size_t k = 0; k < ids.size(); ++k) {
      EXPECT_TRUE(drawn[k]) << ids[k] << " in " << uri;
      ASSERT_TRUE(run.city["CityObjects"].contains(ids[k])) << ids[k];
      const json& attributes = run.city["CityObjects"][ids[k]]["attributes"];
      // The coarse tile shows a building's lowest level (LoD1.2), the fine one its highest (LoD2.2).
      const std::string written = attributes["lods"];
      EXPECT_EQ(lods[k], is_fine ? written.substr(written.size() - 3) : written.substr(0, 3)) << ids[k];
      // The same numbers as the CityJSON attributes, to the bit (noData where they are null).
      for (const auto& [column, name] : {std::make_pair(&h70, "b3_h_dak_70p"), std::make_pair(&volume, "b3_volume_lod22")}) {
        if (attributes[name].is_null()) EXPECT_EQ((*column)[k], "") << ids[k] << " " << name;
        else EXPECT_EQ(std::stod((*column)[k]), attributes[name].get<double>()) << ids[k] << " " << name;
      }
      (is_fine ? fine : coarse).insert(ids[k]);
    }
  }
  const std::vector<std::string> ids = building_ids(run.city);
  EXPECT_EQ(std::vector<std::string>(coarse.begin(), coarse.end()), ids);
  EXPECT_EQ(std::vector<std::string>(fine.begin(), fine.end()), ids);
}

// A building's LoD2.2 vertices in the fine tiles lie where PROJ (gdaltransform, EPSG:28992 to
// EPSG:4326) puts its CityJSON vertices in plan (1 cm), at their NAP height plus the geoid height in
// Delft (43.57 m by the Amersfoort datum's ellipsoid, EGM96 43.46 m).
void expect_vertices_on_the_globe(const TileRun& run, const fs::path& scratch, std::size_t buildings) {
  std::size_t checked = 0;
  for (const TileRef& ref : run.tiles) {
    if (!ref.tile->contains("content") || checked >= buildings) continue;
    const std::string uri = (*ref.tile)["content"]["uri"];
    if (uri.find("_fine.glb") == std::string::npos) continue;
    const Glb g = read_glb(run.out / "3dtiles" / uri);
    const std::vector<std::string> ids = property_column(g, "id");
    const std::vector<GlobeVertex> vertices = globe_vertices(g, ref.transform);
    for (std::size_t k = 0; k < ids.size() && checked < buildings; ++k, ++checked) {
      const std::vector<std::array<double, 3>> rd = cityjson_vertices(run.city, ids[k], "2.2");
      const std::vector<std::array<double, 3>> wgs = gdaltransform(rd, "EPSG:28992", "EPSG:4326", scratch);
      ASSERT_EQ(wgs.size(), rd.size());
      std::size_t matched = 0;
      for (const GlobeVertex& v : vertices) {
        if (v.feature != static_cast<int>(k)) continue;
        double best = 1e9;
        std::size_t nearest = 0;
        for (std::size_t i = 0; i < wgs.size(); ++i) {
          const double d = metres_between(v.lon, v.lat, wgs[i][0], wgs[i][1]) + 10 * std::fabs(v.h - 43.57 - rd[i][2]);
          if (d < best) best = d, nearest = i;
        }
        EXPECT_LT(metres_between(v.lon, v.lat, wgs[nearest][0], wgs[nearest][1]), 0.01) << ids[k];
        EXPECT_NEAR(v.h - rd[nearest][2], 43.5, 0.3) << ids[k];  // NAP to ellipsoidal height in Delft
        ++matched;
      }
      EXPECT_GE(matched, rd.size()) << ids[k];
    }
  }
  EXPECT_EQ(checked, buildings);
}

// CesiumJS draws every building, in the middle of its view and nowhere near its edges, the roofs
// reddish; the building it picks has the CityJSON's id and attributes, and the point picked lies in
// that building's footprint (gdaltransform back to RD New) at a roof's height.
void expect_cesium_draws_and_picks(const TileRun& run, const fs::path& footprints, const fs::path& scratch) {
  const fs::path shot = scratch / "cesium.png";
  const json view = cesium_view(run.out / "3dtiles" / "tileset.json", shot, scratch);
  if (view.is_null()) GTEST_SKIP() << "chromium or build/tools/cesium missing (scripts/setup.sh test installs both)";
  const std::vector<std::string> ids = building_ids(run.city);
  EXPECT_EQ(view["features"], ids.size()) << view.dump();
  const Pixels p = count_pixels(shot);
  EXPECT_GT(p.middle_drawn, p.middle / 10) << "the middle of the view shows too little";
  EXPECT_GT(p.middle_roof, p.middle_drawn / 4) << "too few roof-coloured pixels";
  EXPECT_LT(p.border_drawn, p.border / 200) << "buildings at the edges of the view";
  ASSERT_TRUE(view.contains("picked") && view["picked"].is_object()) << view.dump();
  const json& picked = view["picked"];
  const std::string id = picked["properties"]["id"];
  ASSERT_TRUE(run.city["CityObjects"].contains(id)) << id;
  const json& attributes = run.city["CityObjects"][id]["attributes"];
  EXPECT_EQ(picked["properties"]["b3_h_dak_70p"], attributes["b3_h_dak_70p"]);
  EXPECT_EQ(picked["properties"]["status"], attributes["status"]);
  ASSERT_TRUE(picked.contains("lon")) << picked.dump();
  const auto rd = gdaltransform({{picked["lon"].get<double>(), picked["lat"].get<double>(), 0.0}}, "EPSG:4326",
                                "EPSG:28992", scratch);
  ASSERT_EQ(rd.size(), 1u);
  city3d::FootprintReadOptions options;
  options.id_field = "gml_id";
  bool inside = false;
  for (const city3d::Footprint& f : city3d::read_footprints(footprints.string(), options).footprints) {
    if (f.id != id) continue;
    for (const city3d::Polygon2& polygon : f.polygons) {
      // Even-odd crossing test, grown by 0.2 m: a pick on the roof's edge lies on the footprint's.
      for (double dx : {-0.2, 0.0, 0.2})
        for (double dy : {-0.2, 0.0, 0.2}) {
          const double x = rd[0][0] + dx, y = rd[0][1] + dy;
          bool in = false;
          const auto& ring = polygon.outer;
          for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++)
            if ((ring[i].y > y) != (ring[j].y > y) &&
                x < (ring[j].x - ring[i].x) * (y - ring[i].y) / (ring[j].y - ring[i].y) + ring[i].x)
              in = !in;
          inside = inside || in;
        }
    }
  }
  EXPECT_TRUE(inside) << id << " picked at RD " << rd[0][0] << ", " << rd[0][1];
  const double nap = picked["height"].get<double>() - 43.5;
  EXPECT_GT(nap, attributes["b3_h_maaiveld"].get<double>() + 1.0) << picked.dump();
  EXPECT_LT(nap, attributes["h_ridge"].get<double>() + 0.5) << picked.dump();
}

class Tiles : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("city3d_tiles_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    const std::string d = CITY3D_SAMPLE_DATA;
    make_run(run_, dir_ / "out",
             d + "/delft_sample_1.las " + d + "/delft_sample_2.las -f " + d +
                 "/delft_sample_footprints.gpkg --id-field gml_id --3dtiles --crs EPSG:7415 --no-html");
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static fs::path dir_;
  static TileRun run_;
};
fs::path Tiles::dir_;
TileRun Tiles::run_;

}  // namespace

TEST_F(Tiles, tileset_is_3d_tiles_1_1_with_regions_that_hold_their_children_and_errors_that_shrink_to_0) {
  ASSERT_EQ(run_.result.exit_code, 0) << run_.result.output;
  expect_valid_tileset(run_);
  // The sample's 15 buildings fit one leaf: its LoD1.2 tile refined by its LoD2.2 tile.
  EXPECT_EQ(run_.tileset["root"]["content"]["uri"], "tiles/0_0_0_coarse.glb");
  EXPECT_EQ(run_.tileset["root"]["children"][0]["content"]["uri"], "tiles/0_0_0_fine.glb");
  // The coarse tile's error: how far its blocks' tops lie from the LoD2.2 roofs' vertices (metres);
  // the tileset's, the tallest building (nothing drawn at all).
  const double coarse = run_.tileset["root"]["geometricError"];
  EXPECT_GT(coarse, 1.0);
  EXPECT_LT(coarse, 20.0);
  double tallest = 0;
  for (const auto& [id, object] : run_.city["CityObjects"].items())
    if (object["type"] == "Building")
      tallest = std::max(tallest, object["attributes"]["h_ridge"].get<double>() - object["attributes"]["b3_h_maaiveld"].get<double>());
  EXPECT_NEAR(run_.tileset["geometricError"].get<double>(), tallest, 0.05);
}

TEST_F(Tiles, every_tile_is_valid_gltf_2_by_the_khronos_validator) {
  ASSERT_EQ(run_.result.exit_code, 0) << run_.result.output;
  const fs::path modules = fs::path(CITY3D_TOOLS) / "node_modules";
  if (!have("node") || !fs::exists(modules / "gltf-validator")) GTEST_SKIP() << "node or gltf-validator missing (scripts/setup.sh test)";
  std::string files;
  std::size_t count = 0;
  for (const auto& e : fs::directory_iterator(run_.out / "3dtiles" / "tiles")) files += " " + e.path().string(), ++count;
  EXPECT_EQ(count, 2u);
  const Result r = run_shell("node " + std::string(CITY3D_SOURCE) + "/tests/tools/validate_gltf.js " + modules.string() + files);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n') >= 2, true) << r.output;
  EXPECT_EQ(r.output.find("errors 0, warnings 0") != std::string::npos, true) << r.output;
  for (const std::string bad : {" error ", " warning "}) EXPECT_EQ(r.output.find(bad), std::string::npos) << r.output;
}

TEST_F(Tiles, every_building_is_once_in_the_coarse_and_once_in_the_fine_tiles_with_its_id_and_attributes) {
  ASSERT_EQ(run_.result.exit_code, 0) << run_.result.output;
  expect_buildings_as_metadata(run_);
}

TEST_F(Tiles, vertices_lie_on_the_globe_where_proj_puts_the_cityjson_vertices) {
  ASSERT_EQ(run_.result.exit_code, 0) << run_.result.output;
  if (!have("gdaltransform")) GTEST_SKIP() << "gdaltransform (gdal-bin) not installed";
  expect_vertices_on_the_globe(run_, dir_, 4);
}

TEST_F(Tiles, cesium_draws_every_building_and_picks_one_within_its_footprint) {
  ASSERT_EQ(run_.result.exit_code, 0) << run_.result.output;
  expect_cesium_draws_and_picks(run_, fs::path(CITY3D_SAMPLE_DATA) / "delft_sample_footprints.gpkg", dir_);
}

TEST_F(Tiles, tileset_is_byte_identical_for_one_and_two_jobs) {
  ASSERT_EQ(run_.result.exit_code, 0) << run_.result.output;
  const std::string d = CITY3D_SAMPLE_DATA;
  TileRun two;
  make_run(two, dir_ / "two",
           d + "/delft_sample_1.las " + d + "/delft_sample_2.las -f " + d +
               "/delft_sample_footprints.gpkg --id-field gml_id --3dtiles --crs EPSG:7415 --no-html -j 2 --block-size 20");
  ASSERT_EQ(two.result.exit_code, 0) << two.result.output;
  std::size_t files = 0;
  for (const auto& e : fs::recursive_directory_iterator(run_.out / "3dtiles")) {
    if (!e.is_regular_file()) continue;
    const fs::path other = two.out / "3dtiles" / fs::relative(e.path(), run_.out / "3dtiles");
    EXPECT_EQ(read_file(e.path()), read_file(other)) << other;
    ++files;
  }
  EXPECT_EQ(files, 3u);
}

// The acceptance on the Delft block: --gpkg --3dtiles gives lod12_3d, lod13_3d and lod22_3d
// of 160 MultiPolygonZ features in RD New + NAP height, CityJSON metadata naming that compound CRS
// and the city3d version, a tileset that validates, and CesiumJS drawing the block.
TEST(TilesDelft, delft_block_with_gpkg_and_3dtiles_gives_every_layer_a_valid_tileset_and_a_cesium_view) {
  const std::string d = std::string(CITY3D_SHARED_DATA) + "/ahn3_delft";
  if (!fs::exists(d + "/ahn3_cropped_1.las")) GTEST_SKIP() << "../shared/data is not beside the repository";
  const fs::path dir = fs::temp_directory_path() / ("city3d_tiles_delft_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  TileRun run;
  make_run(run, dir / "out",
           d + "/ahn3_cropped_1.las " + d + "/ahn3_cropped_2.las -f " + d +
               "/footprints/bgt_pand_laz_area.gpkg --id-field gml_id --gpkg --3dtiles --crs EPSG:7415 -j 2 --no-html");
  ASSERT_EQ(run.result.exit_code, 0) << run.result.output;
  EXPECT_EQ(run.city["metadata"]["referenceSystem"], "https://www.opengis.net/def/crs/EPSG/0/7415");
  EXPECT_EQ(run.city["metadata"]["city3d"]["version"], CITY3D_VERSION);
  ASSERT_EQ(building_ids(run.city).size(), 160u);
  if (have("ogrinfo")) {
    for (const char* layer : {"lod12_3d", "lod13_3d", "lod22_3d"}) {
      const Result info = run_shell("ogrinfo -ro -so " + (run.out / "buildings.gpkg").string() + " " + layer);
      EXPECT_NE(info.output.find("Geometry: 3D Multi Polygon"), std::string::npos) << layer;
      EXPECT_NE(info.output.find("Feature Count: 160"), std::string::npos) << layer;
      EXPECT_NE(info.output.find("COMPOUNDCRS[\"Amersfoort / RD New + NAP height\""), std::string::npos) << layer;
    }
  }
  expect_valid_tileset(run);
  EXPECT_GE(run.tiles.size(), 5u);  // a root and at least one leaf of each quadrant the block fills
  expect_buildings_as_metadata(run);
  const fs::path modules = fs::path(CITY3D_TOOLS) / "node_modules";
  if (have("node") && fs::exists(modules / "gltf-validator")) {
    std::string files;
    for (const auto& e : fs::directory_iterator(run.out / "3dtiles" / "tiles")) files += " " + e.path().string();
    const Result r = run_shell("node " + std::string(CITY3D_SOURCE) + "/tests/tools/validate_gltf.js " + modules.string() + files);
    EXPECT_EQ(r.exit_code, 0) << r.output;
  }
  if (have("gdaltransform")) expect_vertices_on_the_globe(run, dir, 3);
  expect_cesium_draws_and_picks(run, d + "/footprints/bgt_pand_laz_area.gpkg", dir);
  fs::remove_all(dir);
}
