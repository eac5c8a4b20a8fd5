// Tests of the footprint readers: the 160 Delft footprints in four OGR formats, City3D's OBJ
// footprints, and small hand-made broken inputs under tests/data/footprints.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/footprint_io.hpp"
#include "city3d/log.hpp"
#include "city3d/rings.hpp"

namespace city3d {
namespace {

const std::string kDelft = std::string(CITY3D_SHARED_DATA) + "/ahn3_delft/footprints/";
const std::string kCity3d = std::string(CITY3D_SHARED_DATA) + "/city3d_repo/";
namespace fs = std::filesystem;
const std::string kLocal = std::string(CITY3D_TEST_DATA) + "/footprints/";

// Independent figures for the Delft layer, from SpatiaLite through ogrinfo:
//   ogrinfo -q -dialect sqlite -sql "select sum(ST_NPoints(geometry)) -
//     sum(ST_NumInteriorRing(geometry) + 1), sum(ST_Area(geometry)) from buildingpart"
//     bgt_pand_laz_area.gpkg        -> 1601 vertices (closing vertices excluded), 8654.0347 m2
constexpr std::size_t kDelftFootprints = 160;
constexpr std::size_t kDelftVertices = 1601;
constexpr double kDelftArea = 8654.03467670769;
// The only footprint with a hole (ST_NumInteriorRing > 0): 4 + 4 vertices, 41.787485500241 m2.
const std::string kHoleId = "b31bd5f7b-00ba-11e6-b420-2bdcc4ab5d7f";

double signed_ring_area(const Ring2& ring) {  // signed, positive when counter-clockwise
  double sum = 0.0;
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const Point2& a = ring[i];
    const Point2& b = ring[(i + 1) % ring.size()];
    sum += (a.x - ring[0].x) * (b.y - ring[0].y) - (b.x - ring[0].x) * (a.y - ring[0].y);
  }
  return 0.5 * sum;
}

double footprint_area(const Footprint& footprint) {  // holes are clockwise, so they subtract
  double area = 0.0;
  for (const Polygon2& polygon : footprint.polygons) {
    area += signed_ring_area(polygon.outer);
    for (const Ring2& hole : polygon.holes) area += signed_ring_area(hole);
  }
  return area;
}

std::size_t vertex_count(const Footprint& footprint) {
  std::size_t n = 0;
  for (const Polygon2& polygon : footprint.polygons) {
    n += polygon.outer.size();
    for (const Ring2& hole : polygon.holes) n += hole.size();
  }
  return n;
}

const Footprint* find(const FootprintSet& set, const std::string& id) {
  for (const Footprint& footprint : set.footprints) {
    if (footprint.id == id) return &footprint;
  }
  return nullptr;
}

const SkippedFootprint* find_skipped(const FootprintSet& set, const std::string& id) {
  for (const SkippedFootprint& skipped : set.skipped) {
    if (skipped.id == id) return &skipped;
  }
  return nullptr;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

/// Runs `read` and returns the IoError's message; fails the test when nothing (or something else)
/// is thrown.
template <typename Read>
std::string io_error_of(Read read) {
  try {
    read();
  } catch (const IoError& error) {
    return error.what();
  } catch (const std::exception& error) {
    ADD_FAILURE() << "expected IoError, got: " << error.what();
    return {};
  }
  ADD_FAILURE() << "expected IoError, nothing was thrown";
  return {};
}

/// Every outer ring counter-clockwise, every hole clockwise, no closing vertex, no consecutive
/// duplicates, at least 3 vertices.
void expect_normal_form(const Footprint& footprint) {
  auto check_ring = [&](const Ring2& ring, bool outer) {
    ASSERT_GE(ring.size(), 3u) << footprint.id;
    if (outer) {
      EXPECT_GT(signed_ring_area(ring), 0.0) << footprint.id << ": outer ring not counter-clockwise";
    } else {
      EXPECT_LT(signed_ring_area(ring), 0.0) << footprint.id << ": hole not clockwise";
    }
    for (std::size_t i = 0; i < ring.size(); ++i) {
      const Point2& a = ring[i];
      const Point2& b = ring[(i + 1) % ring.size()];
      EXPECT_FALSE(a.x == b.x && a.y == b.y) << footprint.id << ": repeated vertex " << i;
    }
  };
  ASSERT_FALSE(footprint.polygons.empty()) << footprint.id;
  for (const Polygon2& polygon : footprint.polygons) {
    check_ring(polygon.outer, true);
    for (const Ring2& hole : polygon.holes) check_ring(hole, false);
  }
}

class QuietLog : public ::testing::Test {
 protected:
  void SetUp() override {
    level_ = log_level();
    set_log_level(LogLevel::quiet);
  }
  void TearDown() override { set_log_level(level_); }
  LogLevel level_ = LogLevel::warning;
};

// ---------------------------------------------------------------------------------------------
// The Delft footprints in four formats.

struct DelftSource {
  std::string file;
  std::string driver;
  std::string layer;
};

std::ostream& operator<<(std::ostream& out, const DelftSource& source) { return out << source.file; }

const std::vector<DelftSource> kDelftSources = {
    {"bgt_pand_laz_area.gpkg", "GPKG", "buildingpart"},
    {"bgt_pand_laz_area.shp", "ESRI Shapefile", "bgt_pand_laz_area"},
    {"bgt_pand_laz_area.geojson", "GeoJSON", "bgt_pand_laz_area"},
    {"bgt_pand.sqlite", "SQLite", "buildingpart"},
};

class DelftFootprints : public ::testing::TestWithParam<DelftSource> {};

TEST_P(DelftFootprints, reads_all_160_footprints_with_their_ids_srs_and_one_hole) {
  FootprintReadOptions options;
  options.id_field = "gml_id";
  const FootprintSet set = read_footprints(kDelft + GetParam().file, options);

  EXPECT_EQ(set.driver, GetParam().driver);
  EXPECT_EQ(set.layer, GetParam().layer);
  EXPECT_EQ(set.id_field, "gml_id");
  EXPECT_EQ(set.srs, "EPSG:28992");
  EXPECT_EQ(set.feature_count, kDelftFootprints);
  EXPECT_EQ(set.footprints.size(), kDelftFootprints);
  EXPECT_TRUE(set.skipped.empty()) << set.skipped.front().id << ": " << set.skipped.front().reason;
  EXPECT_EQ(set.repaired, 0u);
  EXPECT_EQ(set.with_holes, 1u);

  std::set<std::string> ids;
  std::size_t vertices = 0;
  double area = 0.0;
  for (const Footprint& footprint : set.footprints) {
    ids.insert(footprint.id);
    EXPECT_EQ(footprint.polygons.size(), 1u) << footprint.id;
    EXPECT_GE(footprint.fid, 0) << footprint.id;
    expect_normal_form(footprint);
    vertices += vertex_count(footprint);
    area += footprint_area(footprint);
  }
  EXPECT_EQ(ids.size(), kDelftFootprints);
  EXPECT_EQ(vertices, kDelftVertices);
  EXPECT_NEAR(area, kDelftArea, 1e-3);

  const Footprint* with_hole = find(set, kHoleId);
  ASSERT_NE(with_hole, nullptr);
  ASSERT_EQ(with_hole->polygons[0].holes.size(), 1u);
  EXPECT_EQ(with_hole->polygons[0].outer.size(), 4u);
  EXPECT_EQ(with_hole->polygons[0].holes[0].size(), 4u);
  EXPECT_NEAR(footprint_area(*with_hole), 41.787485500241, 1e-6);
}

INSTANTIATE_TEST_SUITE_P(FourFormats, DelftFootprints, ::testing::ValuesIn(kDelftSources),
                         [](const auto& info) {
                           std::string name = info.param.driver;
                           std::replace(name.begin(), name.end(), ' ', '_');
                           return name;
                         });

TEST(DelftFootprintsAcrossFormats, give_the_same_ids_and_vertices_within_a_micrometre) {
  FootprintReadOptions options;
  options.id_field = "gml_id";
  const FootprintSet reference = read_footprints(kDelft + kDelftSources[0].file, options);
  ASSERT_EQ(reference.footprints.size(), kDelftFootprints);
  for (std::size_t s = 1; s < kDelftSources.size(); ++s) {
    const FootprintSet other = read_footprints(kDelft + kDelftSources[s].file, options);
    ASSERT_EQ(other.footprints.size(), reference.footprints.size()) << kDelftSources[s].file;
    for (const Footprint& expected : reference.footprints) {
      const Footprint* actual = find(other, expected.id);
      ASSERT_NE(actual, nullptr) << kDelftSources[s].file << " lacks " << expected.id;
      ASSERT_EQ(actual->polygons.size(), expected.polygons.size()) << expected.id;
      for (std::size_t p = 0; p < expected.polygons.size(); ++p) {
        std::vector<Ring2> want = {expected.polygons[p].outer};
        std::vector<Ring2> got = {actual->polygons[p].outer};
        want.insert(want.end(), expected.polygons[p].holes.begin(), expected.polygons[p].holes.end());
        got.insert(got.end(), actual->polygons[p].holes.begin(), actual->polygons[p].holes.end());
        ASSERT_EQ(got.size(), want.size()) << expected.id;
        for (std::size_t r = 0; r < want.size(); ++r) {
          ASSERT_EQ(got[r].size(), want[r].size()) << expected.id << " ring " << r;
          for (std::size_t v = 0; v < want[r].size(); ++v) {
            EXPECT_NEAR(got[r][v].x, want[r][v].x, 1e-6) << kDelftSources[s].file << " " << expected.id;
            EXPECT_NEAR(got[r][v].y, want[r][v].y, 1e-6) << kDelftSources[s].file << " " << expected.id;
          }
        }
      }
    }
  }
}

TEST(DelftFootprints, clockwise_source_ring_is_flipped_keeping_its_first_vertex) {
  // First feature in every format (ogrinfo -fid 1 bgt_pand_laz_area.gpkg), clockwise in the source:
  // POLYGON ((84967.573 447497.445, 84967.538 447497.33, ..., 84967.602 447497.541, 84967.573 ...))
  FootprintReadOptions options;
  options.id_field = "gml_id";
  const FootprintSet set = read_footprints(kDelft + "bgt_pand_laz_area.gpkg", options);
  const Footprint* footprint = find(set, "b31e1feb1-00ba-11e6-b420-2bdcc4ab5d7f");
  ASSERT_NE(footprint, nullptr);
  EXPECT_EQ(footprint->fid, 1);
  const Ring2& outer = footprint->polygons.at(0).outer;
  ASSERT_EQ(outer.size(), 7u);
  EXPECT_DOUBLE_EQ(outer[0].x, 84967.573);
  EXPECT_DOUBLE_EQ(outer[0].y, 447497.445);
  EXPECT_DOUBLE_EQ(outer[1].x, 84967.602);
  EXPECT_DOUBLE_EQ(outer[1].y, 447497.541);
  EXPECT_DOUBLE_EQ(outer[6].x, 84967.538);
  EXPECT_DOUBLE_EQ(outer[6].y, 447497.33);
}

TEST(DelftFootprints, feature_ids_are_the_ids_when_no_id_field_is_named) {
  const FootprintSet set = read_footprints(kDelft + "bgt_pand_laz_area.gpkg");
  EXPECT_EQ(set.id_field, "FID");
  EXPECT_EQ(set.layer, "buildingpart");
  ASSERT_EQ(set.footprints.size(), kDelftFootprints);
  // GeoPackage FIDs run 1..160 (ogrinfo -fid 1 shows gml_id b31e1feb1-...).
  std::set<std::string> ids;
  for (const Footprint& footprint : set.footprints) {
    EXPECT_EQ(footprint.id, std::to_string(footprint.fid));
    ids.insert(footprint.id);
  }
  EXPECT_EQ(ids.size(), kDelftFootprints);
  EXPECT_EQ(*ids.begin(), "1");
  ASSERT_NE(find(set, "160"), nullptr);
  EXPECT_DOUBLE_EQ(find(set, "1")->polygons.at(0).outer.at(0).x, 84967.573);
}

TEST(DelftFootprints, naming_the_fid_column_as_id_field_uses_the_feature_ids) {
  // bgt_pand.sqlite: "FID Column = ogc_fid"; the first feature is ogc_fid 109 (ogrinfo -q -al).
  FootprintReadOptions options;
  options.id_field = "ogc_fid";
  const FootprintSet set = read_footprints(kDelft + "bgt_pand.sqlite", options);
  EXPECT_EQ(set.id_field, "FID");
  ASSERT_EQ(set.footprints.size(), kDelftFootprints);
  EXPECT_EQ(set.footprints.front().id, "109");
  EXPECT_EQ(set.footprints.front().fid, 109);
}

TEST(DelftFootprints, attribute_filter_keeps_only_matching_footprints) {
  // ogrinfo -q -al -geom=NO -where "bag_pnd > 503100000020000" bgt_pand_laz_area.gpkg
  //   | grep -c OGRFeature  -> 82 (the same for the .shp; .sqlite names the field identificatiebagpnd)
  constexpr std::size_t kMatching = 82;
  FootprintReadOptions options;
  options.id_field = "gml_id";
  options.attribute_filter = "bag_pnd > 503100000020000";
  for (const std::string file : {"bgt_pand_laz_area.gpkg", "bgt_pand_laz_area.shp"}) {
    const FootprintSet set = read_footprints(kDelft + file, options);
    EXPECT_EQ(set.footprints.size(), kMatching) << file;
    EXPECT_EQ(set.feature_count, kMatching) << file;
  }
  options.attribute_filter = "identificatiebagpnd > 503100000020000";
  EXPECT_EQ(read_footprints(kDelft + "bgt_pand.sqlite", options).footprints.size(), kMatching);
}

TEST(DelftFootprints, bbox_filter_keeps_only_footprints_whose_box_meets_it) {
  // ogrinfo -q -al -geom=NO -spat 84900 447500 84950 447550 <file> | grep -c OGRFeature -> 27 for
  // all four files; SpatiaLite's envelope test agrees: select count(*) from buildingpart where
  // ST_MaxX(geometry) >= 84900 and ST_MinX(geometry) <= 84950 and ST_MaxY(geometry) >= 447500
  // and ST_MinY(geometry) <= 447550  -> 27.
  constexpr std::size_t kInBox = 27;
  Box2 box;
  box.add({84900.0, 447500.0});
  box.add({84950.0, 447550.0});
  FootprintReadOptions options;
  options.id_field = "gml_id";
  options.bbox = box;
  for (const DelftSource& source : kDelftSources) {
    const FootprintSet set = read_footprints(kDelft + source.file, options);
    EXPECT_EQ(set.footprints.size(), kInBox) << source.file;
    EXPECT_EQ(set.feature_count, kInBox) << source.file;
    for (const Footprint& footprint : set.footprints) {
      Box2 bounds;
      for (const Point2& p : footprint.polygons.at(0).outer) bounds.add(p);
      EXPECT_TRUE(bounds.intersects(box)) << source.file << " " << footprint.id;
    }
  }
}

TEST(DelftFootprints, attribute_and_bbox_filters_combine) {
  // ogrinfo -q -al -geom=NO -where "bag_pnd > 503100000020000" -spat 84900 447500 84950 447550
  //   bgt_pand_laz_area.gpkg | grep -c OGRFeature  -> 12
  Box2 box;
  box.add({84900.0, 447500.0});
  box.add({84950.0, 447550.0});
  FootprintReadOptions options;
  options.attribute_filter = "bag_pnd > 503100000020000";
  options.bbox = box;
  EXPECT_EQ(read_footprints(kDelft + "bgt_pand_laz_area.gpkg", options).footprints.size(), 12u);
}

TEST(DelftFootprints, lists_the_layers_of_a_source) {
  EXPECT_EQ(list_footprint_layers(kDelft + "bgt_pand_laz_area.gpkg"),
            std::vector<std::string>{"buildingpart"});
  EXPECT_EQ(list_footprint_layers(kDelft + "bgt_pand_laz_area.shp"),
            std::vector<std::string>{"bgt_pand_laz_area"});
}

// ---------------------------------------------------------------------------------------------
// Broken sources: each must be an IoError naming the file and the problem.

TEST(FootprintErrors, missing_file_is_reported_as_no_such_file) {
  const std::string message = io_error_of([] { read_footprints(kLocal + "nowhere.gpkg"); });
  EXPECT_TRUE(contains(message, "footprints: cannot open ")) << message;
  EXPECT_TRUE(contains(message, "nowhere.gpkg: no such file")) << message;
  const std::string obj_message = io_error_of([] { read_footprints(kLocal + "nowhere.obj"); });
  EXPECT_TRUE(contains(obj_message, "nowhere.obj: no such file")) << obj_message;
  const std::string list_message = io_error_of([] { list_footprint_layers(kLocal + "nowhere.shp"); });
  EXPECT_TRUE(contains(list_message, "nowhere.shp: no such file")) << list_message;
}

TEST(FootprintErrors, text_file_is_reported_as_not_a_vector_source) {
  const std::string message = io_error_of([] { read_footprints(kLocal + "not_a_vector.txt"); });
  EXPECT_TRUE(contains(message, "not_a_vector.txt")) << message;
  EXPECT_TRUE(contains(message, "not a vector source")) << message;
}

TEST(FootprintErrors, unknown_layer_is_reported_with_the_available_layers) {
  FootprintReadOptions options;
  options.layer = "pand";
  const std::string message =
      io_error_of([&] { read_footprints(kDelft + "bgt_pand_laz_area.gpkg", options); });
  EXPECT_TRUE(contains(message, "footprints: no layer 'pand' in ")) << message;
  EXPECT_TRUE(contains(message, "bgt_pand_laz_area.gpkg (layers: buildingpart)")) << message;
}

TEST(FootprintErrors, unknown_id_field_is_reported_with_the_available_fields) {
  FootprintReadOptions options;
  options.id_field = "identificatiebagpnd";  // truncated to bag_pnd in this file
  const std::string message =
      io_error_of([&] { read_footprints(kDelft + "bgt_pand_laz_area.shp", options); });
  EXPECT_TRUE(contains(message, "no field 'identificatiebagpnd'")) << message;
  EXPECT_TRUE(contains(message, "bgt_pand_laz_area.shp layer 'bgt_pand_laz_area'")) << message;
  EXPECT_TRUE(contains(message, "fields: src_fid, gml_id, lokaalid, bag_pnd")) << message;
}

TEST(FootprintErrors, bad_attribute_filter_is_reported_with_gdals_reason) {
  FootprintReadOptions options;
  options.attribute_filter = "bag_pnd >>> 3";
  const std::string message =
      io_error_of([&] { read_footprints(kDelft + "bgt_pand_laz_area.gpkg", options); });
  EXPECT_TRUE(contains(message, "bad attribute filter 'bag_pnd >>> 3'")) << message;
  EXPECT_TRUE(contains(message, "bgt_pand_laz_area.gpkg")) << message;
  EXPECT_TRUE(contains(message, "GDAL: ")) << message;
}

TEST(FootprintErrors, a_filter_that_breaks_the_drivers_own_sql_is_named_when_the_read_fails) {
  // Accepted as a filter, but spliced into the GeoPackage's R-tree query it comments the rest out.
  FootprintReadOptions options;
  options.attribute_filter = "1=1 --";
  options.bbox = Box2{{84800, 447400}, {85100, 447700}};
  const std::string message =
      io_error_of([&] { read_footprints(kDelft + "bgt_pand_laz_area.gpkg", options); });
  EXPECT_TRUE(contains(message, "error while reading")) << message;
  EXPECT_TRUE(contains(message, "with --where \"1=1 --\"")) << message;
}

TEST(FootprintErrors, layer_without_polygons_is_reported) {
  const std::string message = io_error_of([] { read_footprints(kLocal + "points_only.geojson"); });
  EXPECT_TRUE(contains(message, "points_only.geojson layer 'trees' has no polygon features")) << message;
}

TEST(FootprintErrors, naming_a_point_layer_of_a_multi_layer_source_is_reported) {
  FootprintReadOptions options;
  options.layer = "trees";
  const std::string message = io_error_of([&] { read_footprints(kLocal + "two_layers.vrt", options); });
  EXPECT_TRUE(contains(message, "two_layers.vrt layer 'trees' has no polygon features")) << message;
}

// ---------------------------------------------------------------------------------------------
// Hand-made broken features (tests/data/footprints/broken_features.geojson, id field "name").

class BrokenFeatures : public QuietLog {
 protected:
  FootprintSet read(bool repair) {
    FootprintReadOptions options;
    options.id_field = "name";
    options.repair = repair;
    return read_footprints(kLocal + "broken_features.geojson", options);
  }
};

TEST_F(BrokenFeatures, good_features_are_kept_and_bad_ones_skipped_with_reasons) {
  const FootprintSet set = read(true);
  EXPECT_EQ(set.driver, "GeoJSON");
  EXPECT_EQ(set.feature_count, 10u);
  EXPECT_EQ(set.feature_count, set.footprints.size() + set.skipped.size());
  std::vector<std::string> kept;
  for (const Footprint& footprint : set.footprints) {
    kept.push_back(footprint.id);
    expect_normal_form(footprint);
  }
  EXPECT_EQ(kept, (std::vector<std::string>{"square", "bowtie", "hole_wrong_orientation", "multi",
                                            "repeated_vertices_with_z"}));
  ASSERT_EQ(set.skipped.size(), 5u);
  auto reason_of = [&](const std::string& id) {
    const SkippedFootprint* skipped = find_skipped(set, id);
    return skipped != nullptr ? skipped->reason : "(not skipped)";
  };
  EXPECT_EQ(reason_of("empty"), "empty geometry");
  EXPECT_EQ(reason_of("no_geometry"), "no geometry");
  EXPECT_TRUE(contains(reason_of("point"), "not a polygon (Point)")) << reason_of("point");
  EXPECT_TRUE(contains(reason_of("square"), "duplicated id")) << reason_of("square");
  EXPECT_TRUE(contains(reason_of("sliver"), "invalid polygon")) << reason_of("sliver");
  EXPECT_TRUE(contains(reason_of("sliver"), "repair left no polygon")) << reason_of("sliver");
  // The first "square" (0..10) is the one kept, not the duplicate at x = 100.
  EXPECT_DOUBLE_EQ(find(set, "square")->polygons.at(0).outer.at(0).x, 0.0);
}

// The same polygon under two ids made two models in one place. The second is skipped, naming the
// first, whichever vertex its rings start at, whichever way they run and in whatever order its holes
// and parts come; a polygon a millimetre away is another building.
TEST_F(BrokenFeatures, the_same_polygon_under_another_id_is_skipped_naming_the_first) {
  const fs::path path =
      fs::temp_directory_path() / ("city3d_same_shape_" + std::to_string(::getpid()) + ".geojson");
  const auto feature = [](const std::string& id, const std::string& type, const std::string& coordinates) {
    return R"({"type":"Feature","properties":{"name":")" + id + R"("},"geometry":{"type":")" + type +
           R"(","coordinates":)" + coordinates + "}}";
  };
  const std::string features[] = {
      feature("first", "Polygon",
              "[[[0,0],[10,0],[10,10],[0,10],[0,0]],[[2,2],[2,4],[4,4],[4,2],[2,2]],"
              "[[6,6],[6,8],[8,8],[8,6],[6,6]]]"),
      // Starting at another vertex, clockwise, its holes the other way round.
      feature("copy", "Polygon",
              "[[[10,10],[10,0],[0,0],[0,10],[10,10]],[[6,6],[6,8],[8,8],[8,6],[6,6]],"
              "[[2,2],[2,4],[4,4],[4,2],[2,2]]]"),
      feature("shifted", "Polygon", "[[[0.001,0],[10.001,0],[10.001,10],[0.001,10],[0.001,0]]]"),
      feature("parts", "MultiPolygon",
              "[[[[20,0],[24,0],[24,4],[20,4],[20,0]]],[[[30,0],[34,0],[34,4],[30,4],[30,0]]]]"),
      feature("parts_again", "MultiPolygon",
              "[[[[34,4],[30,4],[30,0],[34,0],[34,4]]],[[[20,0],[24,0],[24,4],[20,4],[20,0]]]]")};
  {
    std::ofstream out(path);
    out << R"({"type":"FeatureCollection","features":[)";
    for (std::size_t i = 0; i < std::size(features); ++i) out << (i ? "," : "") << features[i];
    out << "]}";
  }
  FootprintReadOptions options;
  options.id_field = "name";
  const FootprintSet set = read_footprints(path.string(), options);
  fs::remove(path);
  std::vector<std::string> kept;
  for (const Footprint& footprint : set.footprints) kept.push_back(footprint.id);
  EXPECT_EQ(kept, (std::vector<std::string>{"first", "shifted", "parts"}));
  ASSERT_EQ(set.skipped.size(), 2u);
  const SkippedFootprint* copy = find_skipped(set, "copy");
  ASSERT_NE(copy, nullptr);
  EXPECT_TRUE(contains(copy->reason, "the same polygon as first (fid 0")) << copy->reason;
  const SkippedFootprint* again = find_skipped(set, "parts_again");
  ASSERT_NE(again, nullptr);
  EXPECT_TRUE(contains(again->reason, "the same polygon as parts")) << again->reason;
}

TEST_F(BrokenFeatures, ids_of_a_real_field_are_written_whole_or_to_the_last_digit_that_tells_them_apart) {
  // 16-digit integers in a real field (as sources that export big ids as doubles keep them): OGR's
  // own text has 15 digits, 1.23456789012346e+15 for both of the first two, so they were one id.
  const fs::path path =
      fs::temp_directory_path() / ("city3d_real_ids_" + std::to_string(::getpid()) + ".geojson");
  {
    std::ofstream out(path);
    out << R"({"type":"FeatureCollection","features":[)";
    const char* ids[] = {"1234567890123456.0", "1234567890123457.0", "503100000028000.5", "0.1"};
    for (int k = 0; k < 4; ++k)
      out << (k ? "," : "") << R"({"type":"Feature","properties":{"key":)" << ids[k]
          << R"(},"geometry":{"type":"Polygon","coordinates":[[[)" << 20 * k << ",0],[" << 20 * k + 10
          << ",0],[" << 20 * k + 10 << ",10],[" << 20 * k << ",10],[" << 20 * k << ",0]]]}}";
    out << "]}";
  }
  FootprintReadOptions options;
  options.id_field = "key";
  const FootprintSet set = read_footprints(path.string(), options);
  std::size_t features = 0;
  const std::vector<FieldSummary> fields = summarise_fields(path.string(), options, 100, features);
  fs::remove(path);
  std::vector<std::string> ids;
  for (const Footprint& f : set.footprints) ids.push_back(f.id);
  EXPECT_EQ(ids,
            (std::vector<std::string>{"1234567890123456", "1234567890123457", "503100000028000.5", "0.1"}));
  EXPECT_TRUE(set.skipped.empty());
  const auto key =
      std::find_if(fields.begin(), fields.end(), [](const FieldSummary& f) { return f.name == "key"; });
  ASSERT_NE(key, fields.end());
  EXPECT_EQ(key->type, "Real");
  EXPECT_TRUE(key->unique(features)) << key->distinct;
}

TEST_F(BrokenFeatures, bow_tie_is_repaired_into_two_valid_triangles) {
  const FootprintSet set = read(true);
  EXPECT_EQ(set.repaired, 1u);
  const Footprint* bowtie = find(set, "bowtie");
  ASSERT_NE(bowtie, nullptr);
  ASSERT_EQ(bowtie->polygons.size(), 2u);
  for (const Polygon2& triangle : bowtie->polygons) {
    EXPECT_EQ(triangle.outer.size(), 3u);
    EXPECT_NEAR(signed_ring_area(triangle.outer), 25.0, 1e-9);  // (20,0)-(30,10) crossing at (25,5)
  }
}

TEST_F(BrokenFeatures, bow_tie_is_skipped_with_its_reason_when_repair_is_off) {
  const FootprintSet set = read(false);
  EXPECT_EQ(set.repaired, 0u);
  EXPECT_EQ(find(set, "bowtie"), nullptr);
  const SkippedFootprint* skipped = find_skipped(set, "bowtie");
  ASSERT_NE(skipped, nullptr);
  EXPECT_TRUE(contains(skipped->reason, "invalid polygon")) << skipped->reason;
  EXPECT_TRUE(contains(skipped->reason, "Self-intersection")) << skipped->reason;
  EXPECT_EQ(set.footprints.size(), 4u);
  EXPECT_EQ(set.skipped.size(), 6u);
}

TEST_F(BrokenFeatures, hole_given_in_the_wrong_orientation_is_reoriented) {
  const FootprintSet set = read(true);
  EXPECT_EQ(set.with_holes, 1u);
  const Footprint* footprint = find(set, "hole_wrong_orientation");
  ASSERT_NE(footprint, nullptr);
  ASSERT_EQ(footprint->polygons.size(), 1u);
  const Polygon2& polygon = footprint->polygons[0];
  ASSERT_EQ(polygon.holes.size(), 1u);
  EXPECT_NEAR(signed_ring_area(polygon.outer), 100.0, 1e-9);
  EXPECT_NEAR(signed_ring_area(polygon.holes[0]), -36.0, 1e-9);
  // The source outer ring (40 0, 40 10, 50 10, 50 0) is clockwise: flipped, first vertex kept.
  EXPECT_DOUBLE_EQ(polygon.outer[0].x, 40.0);
  EXPECT_DOUBLE_EQ(polygon.outer[1].x, 50.0);
  EXPECT_DOUBLE_EQ(polygon.outer[1].y, 0.0);
}

TEST_F(BrokenFeatures, multipolygon_keeps_both_parts_counter_clockwise) {
  const FootprintSet set = read(true);
  const Footprint* multi = find(set, "multi");
  ASSERT_NE(multi, nullptr);
  ASSERT_EQ(multi->polygons.size(), 2u);
  EXPECT_NEAR(signed_ring_area(multi->polygons[0].outer), 16.0, 1e-9);
  EXPECT_NEAR(signed_ring_area(multi->polygons[1].outer), 16.0, 1e-9);
  EXPECT_DOUBLE_EQ(multi->polygons[1].outer[0].x, 70.0);
}

TEST_F(BrokenFeatures, repeated_vertices_and_z_are_dropped) {
  const FootprintSet set = read(true);
  const Footprint* footprint = find(set, "repeated_vertices_with_z");
  ASSERT_NE(footprint, nullptr);
  const Ring2& outer = footprint->polygons.at(0).outer;
  ASSERT_EQ(outer.size(), 4u);
  const std::vector<std::pair<double, double>> expected = {{80, 0}, {84, 0}, {84, 4}, {80, 4}};
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_DOUBLE_EQ(outer[i].x, expected[i].first);
    EXPECT_DOUBLE_EQ(outer[i].y, expected[i].second);
  }
}

TEST_F(BrokenFeatures, first_polygon_layer_of_a_multi_layer_source_is_chosen) {
  EXPECT_EQ(list_footprint_layers(kLocal + "two_layers.vrt"),
            (std::vector<std::string>{"trees", "buildings"}));
  FootprintReadOptions options;
  options.id_field = "name";
  const FootprintSet set = read_footprints(kLocal + "two_layers.vrt", options);
  EXPECT_EQ(set.layer, "buildings");
  EXPECT_EQ(set.footprints.size(), 5u);
}

TEST_F(BrokenFeatures, curve_polygon_is_linearised_and_z_dropped) {
  FootprintReadOptions options;
  options.id_field = "name";
  const FootprintSet set = read_footprints(kLocal + "curved.csv", options);
  ASSERT_EQ(set.footprints.size(), 2u);
  const Footprint* disc = find(set, "disc");  // full circle through (0 0) and (10 0): radius 5
  ASSERT_NE(disc, nullptr);
  expect_normal_form(*disc);
  EXPECT_GT(disc->polygons.at(0).outer.size(), 20u);
  EXPECT_NEAR(footprint_area(*disc), M_PI * 25.0, 0.01 * M_PI * 25.0);
  const Footprint* square = find(set, "square_z");
  ASSERT_NE(square, nullptr);
  EXPECT_EQ(square->polygons.at(0).outer.size(), 4u);
  EXPECT_NEAR(footprint_area(*square), 16.0, 1e-9);
}

// ---------------------------------------------------------------------------------------------
// City3D's OBJ footprints.

TEST(ObjFootprints, city3d_footprint_001_is_one_polygon_of_60_vertices) {
  const FootprintSet set = read_footprints(kCity3d + "001_footprint.obj");
  EXPECT_EQ(set.driver, "OBJ");
  EXPECT_EQ(set.layer, "obj");
  ASSERT_EQ(set.footprints.size(), 1u);
  const Footprint& footprint = set.footprints[0];
  EXPECT_EQ(footprint.id, "0");
  ASSERT_EQ(footprint.polygons.size(), 1u);
  EXPECT_EQ(footprint.polygons[0].outer.size(), 60u);
  expect_normal_form(footprint);
  EXPECT_TRUE(set.skipped.empty());
  // The face starts at vertex 21 (f 21//21 14//14 ...), and flipping keeps the first vertex:
  // grep '^v ' 001_footprint.obj | sed -n 21p -> v 139.5676879883 77.2154998779 -5.9770002365
  EXPECT_DOUBLE_EQ(footprint.polygons[0].outer[0].x, 139.5676879883);
  EXPECT_DOUBLE_EQ(footprint.polygons[0].outer[0].y, 77.2154998779);
}

TEST(ObjFootprints, city3d_footprints_002_and_003_have_the_faces_and_vertices_of_the_file) {
  // Faces: grep -c '^f ' -> 159 and 368. Vertex references per face: awk '/^f /{n += NF - 1}'
  // -> 1752 and 3027, but Easy3D repeats each face's first vertex at its end (as a separate `v`
  // line with the same coordinates), and one face of 003 (line 6422) repeats another vertex too.
  // Counting, per face, the references whose coordinates differ from the next one (cyclically):
  //   awk '/^v /{n++; X[n]=$2; Y[n]=$3} /^f /{k=NF-1; for(i=2;i<=NF;i++){split($i,a,"/");
  //     r[i-1]=a[1]} for(i=1;i<=k;i++){j=i%k+1; if(X[r[i]]!=X[r[j]] || Y[r[i]]!=Y[r[j]]) t++}}
  //     END{print t}'  -> 1593 (002) and 2658 (003).
  const FootprintSet set002 = read_footprints(kCity3d + "002_footprint.obj");
  const FootprintSet set003 = read_footprints(kCity3d + "003_footprint.obj");
  auto total_vertices = [](const FootprintSet& set) {
    std::size_t n = 0;
    for (const Footprint& footprint : set.footprints) n += vertex_count(footprint);
    return n;
  };
  EXPECT_EQ(set002.footprints.size(), 159u);
  EXPECT_EQ(total_vertices(set002), 1593u);
  EXPECT_EQ(set003.footprints.size(), 368u);
  // One face of 003 (line 6057) crosses itself: like any OGR source, it is repaired with MakeValid,
  // which adds the crossing point to both parts (2658 + 2).
  EXPECT_EQ(set003.repaired, 1u);
  EXPECT_EQ(total_vertices(set003), 2660u);
  EXPECT_EQ(set003.footprints.back().id, "367");
  for (const Footprint& footprint : set003.footprints) expect_normal_form(footprint);
  // 003 is in RD New world coordinates (first vertex line: v 83946.140625 446902.84375 0).
  EXPECT_DOUBLE_EQ(set003.footprints.front().polygons[0].outer[0].x, 83946.1406250000);
  EXPECT_DOUBLE_EQ(set003.footprints.front().polygons[0].outer[0].y, 446902.8437500000);
}

TEST(ObjFootprints, named_objects_give_ids_and_negative_indices_count_back) {
  const FootprintSet set = read_footprints(kLocal + "named_faces.obj");
  ASSERT_EQ(set.footprints.size(), 3u);
  EXPECT_EQ(set.footprints[0].id, "house_a");
  EXPECT_EQ(set.footprints[1].id, "house_b");
  EXPECT_EQ(set.footprints[2].id, "2");  // `g` alone returns to unnamed faces
  const Ring2& triangle = set.footprints[1].polygons.at(0).outer;
  ASSERT_EQ(triangle.size(), 3u);
  EXPECT_NEAR(signed_ring_area(triangle), 4.5, 1e-12);  // (10 0)(10 3)(13 3), clockwise in the file
  EXPECT_DOUBLE_EQ(triangle[0].x, 10.0);
  EXPECT_DOUBLE_EQ(triangle[1].x, 13.0);
  EXPECT_NEAR(signed_ring_area(set.footprints[2].polygons.at(0).outer), 16.0, 1e-12);
}

TEST(ObjFootprints, bbox_filter_applies_to_obj_faces) {
  Box2 box;
  box.add({9.0, -1.0});
  box.add({20.0, 1.0});
  FootprintReadOptions options;
  options.bbox = box;
  const FootprintSet set = read_footprints(kLocal + "named_faces.obj", options);
  ASSERT_EQ(set.footprints.size(), 1u);
  EXPECT_EQ(set.footprints[0].id, "house_b");
  EXPECT_EQ(set.feature_count, 1u);
}

TEST(ObjFootprints, malformed_vertex_is_reported_with_file_and_line) {
  const std::string message = io_error_of([] { read_footprints(kLocal + "malformed_vertex.obj"); });
  EXPECT_TRUE(contains(message, "malformed_vertex.obj line 3")) << message;
  EXPECT_TRUE(contains(message, "not a number")) << message;
}

TEST(ObjFootprints, face_index_out_of_range_is_reported_with_file_and_line) {
  const std::string message = io_error_of([] { read_footprints(kLocal + "bad_index.obj"); });
  EXPECT_TRUE(contains(message, "bad_index.obj line 4")) << message;
  EXPECT_TRUE(contains(message, "vertex index 7 out of range")) << message;
}

TEST(ObjFootprints, has_one_layer_named_obj_and_no_other) {
  EXPECT_EQ(list_footprint_layers(kCity3d + "001_footprint.obj"), std::vector<std::string>{"obj"});
  FootprintReadOptions options;
  options.layer = "buildingpart";
  const std::string message = io_error_of([&] { read_footprints(kCity3d + "001_footprint.obj", options); });
  EXPECT_TRUE(contains(message, "no layer 'buildingpart' in ")) << message;
  EXPECT_TRUE(contains(message, "001_footprint.obj (layers: obj)")) << message;
}

}  // namespace
}  // namespace city3d

namespace city3d {

// Issue 14 item 9: a bow-tie footprint was repaired from GeoJSON but skipped from a City3D OBJ file.
TEST(ObjFootprints, bow_tie_face_is_repaired_into_the_same_two_triangles_as_from_geojson) {
  const fs::path dir = fs::temp_directory_path() / "city3d_obj_bowtie";
  fs::create_directories(dir);
  // The bow-tie of sample_broken.geojson ("bowtie"), as an OBJ face.
  std::ofstream(dir / "bowtie.obj") << "v 84994.546 447549.1 0\nv 84998.546 447553.1 0\nv 84998.546 447549.1 0\n"
                                       "v 84994.546 447553.1 0\no bowtie\nf 1 2 3 4\n";
  const FootprintSet obj = read_footprints((dir / "bowtie.obj").string());
  FootprintReadOptions by_name;
  by_name.id_field = "gml_id";
  const FootprintSet geojson = read_footprints(kLocal + "sample_broken.geojson", by_name);
  fs::remove_all(dir);
  ASSERT_EQ(obj.footprints.size(), 1u);
  EXPECT_TRUE(obj.skipped.empty());
  EXPECT_EQ(obj.repaired, 1u);
  EXPECT_TRUE(contains(obj.footprints[0].note, "repaired with MakeValid")) << obj.footprints[0].note;
  const Footprint* expected = nullptr;
  for (const Footprint& f : geojson.footprints)
    if (f.id == "bowtie") expected = &f;
  ASSERT_NE(expected, nullptr);
  ASSERT_EQ(obj.footprints[0].polygons.size(), expected->polygons.size());
  for (std::size_t i = 0; i < expected->polygons.size(); ++i) {
    ASSERT_EQ(obj.footprints[0].polygons[i].outer.size(), expected->polygons[i].outer.size());
    for (std::size_t k = 0; k < expected->polygons[i].outer.size(); ++k) {
      EXPECT_DOUBLE_EQ(obj.footprints[0].polygons[i].outer[k].x, expected->polygons[i].outer[k].x);
      EXPECT_DOUBLE_EQ(obj.footprints[0].polygons[i].outer[k].y, expected->polygons[i].outer[k].y);
    }
  }
}

// Footprints of too many vertices are simplified within a stated tolerance: a circle of 20,000
// vertices (radius 9 m) comes back with at most 1,000, every vertex still on the circle within the
// tolerance reported; a footprint within the cap comes back as it is.
TEST(SimplifyFootprint, many_vertices_within_the_tolerance_and_few_untouched) {
  Polygon2 circle;
  constexpr int n = 20000;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * i / n;
    circle.outer.push_back({9.0 * std::cos(a), 9.0 * std::sin(a)});
  }
  const SimplifiedFootprint s = simplify_footprint({circle}, 1000);
  EXPECT_EQ(s.vertices_before, static_cast<std::size_t>(n));
  ASSERT_EQ(s.polygons.size(), 1u);
  EXPECT_LE(s.vertices_after, 1000u);
  EXPECT_GE(s.vertices_after, 16u);  // still a circle, not a triangle
  EXPECT_EQ(s.vertices_after, s.polygons[0].outer.size());
  EXPECT_GT(s.tolerance, 0.0);
  EXPECT_LE(s.tolerance, 0.1);
  for (const Point2& v : s.polygons[0].outer) EXPECT_NEAR(std::hypot(v.x, v.y), 9.0, s.tolerance);

  const Polygon2 square{{{0, 0}, {4, 0}, {4, 4}, {0, 4}}, {}};
  const SimplifiedFootprint same = simplify_footprint({square}, 1000);
  EXPECT_EQ(same.tolerance, 0.0);
  ASSERT_EQ(same.polygons.size(), 1u);
  EXPECT_EQ(same.polygons[0].outer.size(), 4u);
}

// The least distance from any vertex of one ring to any edge of another, both ways.
double ring_gap(const Ring2& a, const Ring2& b) {
  double gap = INFINITY;
  for (const auto& [p, q] : {std::pair{&a, &b}, std::pair{&b, &a}})
    for (const Point2& v : *p)
      for (std::size_t k = 0; k < q->size(); ++k)
        gap = std::min(gap, segment_distance(v, (*q)[k], (*q)[(k + 1) % q->size()]));
  return gap;
}

// How many vertices of the polygons moved, and how far the farthest did.
std::pair<int, double> moves(const std::vector<Polygon2>& before, const std::vector<Polygon2>& after) {
  int moved = 0;
  double farthest = 0.0;
  const auto ring = [&](const Ring2& a, const Ring2& b) {
    EXPECT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
      const double d = std::hypot(a[i].x - b[i].x, a[i].y - b[i].y);
      moved += d > 0.0;
      farthest = std::max(farthest, d);
    }
  };
  EXPECT_EQ(before.size(), after.size());
  for (std::size_t p = 0; p < std::min(before.size(), after.size()); ++p) {
    ring(before[p].outer, after[p].outer);
    EXPECT_EQ(before[p].holes.size(), after[p].holes.size());
    for (std::size_t h = 0; h < std::min(before[p].holes.size(), after[p].holes.size()); ++h)
      ring(before[p].holes[h], after[p].holes[h]);
  }
  return {moved, farthest};
}

// tidy_footprint: a vertex 0.5 mm after another and a spike 1 mm wide (tip and one foot) go, in outer
// rings and holes; a circle of 3 mm edges (its vertices 6 mm apart two by two, but each within 0.01 mm
// of the line between its neighbours) and a ring of 3 vertices stay as they are.
TEST(TidyFootprint, doubled_vertices_and_hairline_spikes_go_and_curves_stay) {
  std::vector<Polygon2> polygons{
      {{{0, 0}, {12, 0}, {12.0004, 0.0003}, {12, 8}, {6.001, 8}, {6.0005, 10}, {6, 8}, {0, 8}},
       {{{2, 2}, {2, 4}, {2.0003, 4}, {4, 4}, {4, 2}}}}};
  const TidiedFootprint t = tidy_footprint(polygons, 0.002, 0.01);
  EXPECT_EQ(t.merged, 3u);  // the spike's two feet, 1 mm apart once its tip is gone, too
  EXPECT_EQ(t.spikes, 1u);
  ASSERT_EQ(polygons[0].outer.size(), 5u);  // {0,0} {12,0} {12,8}, one of the feet, {0,8}
  for (const Point2& v : polygons[0].outer) EXPECT_LE(v.y, 8.0);
  EXPECT_EQ(polygons[0].holes[0].size(), 4u);

  Polygon2 circle;
  for (int i = 0; i < 2000; ++i) {
    const double a = 2 * M_PI * i / 2000;
    circle.outer.push_back({std::cos(a), std::sin(a)});  // edges of 3.1 mm
  }
  std::vector<Polygon2> round{circle, {{{5, 5}, {5.0005, 5.0005}, {5, 5.001}}, {}}};
  const TidiedFootprint none = tidy_footprint(round, 0.002, 0.01);
  EXPECT_EQ(none.spikes, 0u);
  EXPECT_EQ(round[0].outer.size(), 2000u);
  EXPECT_EQ(round[1].outer.size(), 3u);
}

// A hole whose vertex lies on its outer ring's edge (valid in OGC's rules; every block extruded from it
// has an edge of four faces): that vertex, and only it, moves into the hole until the two rings are
// 1 cm apart, the hole keeping its orientation and area but for a sliver.
TEST(OpenPinches, a_hole_touching_its_outer_ring_moves_into_the_hole_by_the_clearance) {
  const std::vector<Polygon2> given{{{{0, 0}, {12, 0}, {12, 10}, {0, 10}}, {{{6, 0}, {4, 4}, {8, 4}}}}};
  std::vector<Polygon2> polygons = given;
  Point2 unopened{NAN, NAN};
  const std::vector<Point2> opened = open_pinches(polygons, 0.01, &unopened);
  ASSERT_EQ(opened.size(), 1u);
  EXPECT_EQ(opened[0].x, 6.0);
  EXPECT_EQ(opened[0].y, 0.0);
  EXPECT_TRUE(std::isnan(unopened.x));
  const auto [moved, farthest] = moves(given, polygons);
  EXPECT_EQ(moved, 1);
  EXPECT_LE(farthest, 0.1);
  EXPECT_GE(ring_gap(polygons[0].outer, polygons[0].holes[0]), 0.01 * 0.999);
  EXPECT_GT(polygons[0].holes[0][0].y, 0.0);  // into the hole, not out of the building
  EXPECT_LT(signed_area(polygons[0].holes[0]), 0.0);
  EXPECT_NEAR(signed_area(polygons[0].holes[0]), signed_area(given[0].holes[0]), 0.05);
}

// Two parts meeting at a corner, two holes sharing a vertex, and a ring that comes back to touch
// itself: each is opened at one vertex, the rings then at least the clearance apart.
TEST(OpenPinches, parts_meeting_at_a_corner_holes_sharing_a_vertex_and_a_self_touching_ring_are_opened) {
  {
    const std::vector<Polygon2> given{{{{0, 0}, {6, 0}, {6, 5}, {0, 5}}, {}},
                                      {{{6, 5}, {12, 5}, {12, 10}, {6, 10}}, {}}};
    std::vector<Polygon2> polygons = given;
    EXPECT_EQ(open_pinches(polygons, 0.01).size(), 1u);
    EXPECT_EQ(moves(given, polygons).first, 1);
    EXPECT_GE(ring_gap(polygons[0].outer, polygons[1].outer), 0.01 * 0.999);
  }
  {
    const std::vector<Polygon2> given{{{{0, 0}, {12, 0}, {12, 10}, {0, 10}},
                                       {{{4, 3}, {4, 5}, {6, 5}, {6, 3}}, {{6, 5}, {6, 7}, {8, 7}, {8, 5}}}}};
    std::vector<Polygon2> polygons = given;
    EXPECT_EQ(open_pinches(polygons, 0.01).size(), 1u);
    EXPECT_EQ(moves(given, polygons).first, 1);
    EXPECT_GE(ring_gap(polygons[0].holes[0], polygons[0].holes[1]), 0.01 * 0.999);
  }
  {
    // An outer ring that leaves its left side at (0, 5) for a loop round a diamond and comes back to
    // (0, 5): a hole joined to the boundary at a point (ESRI's "inverted hole").
    const std::vector<Polygon2> given{
        {{{0, 0}, {10, 0}, {10, 10}, {0, 10}, {0, 5}, {3, 7}, {6, 5}, {3, 3}, {0, 5}}, {}}};
    std::vector<Polygon2> polygons = given;
    EXPECT_EQ(open_pinches(polygons, 0.01).size(), 1u);
    EXPECT_EQ(moves(given, polygons).first, 1);
    const Ring2& r = polygons[0].outer;
    EXPECT_GE(std::hypot(r[4].x - r[8].x, r[4].y - r[8].y), 0.01 * 0.999);
    EXPECT_GT(signed_area(r), 0.0);
  }
}

// What is no pinch is left alone: vertices a few millimetres apart along one ring, a courtyard 5 cm
// from the outer wall, a single square. A hole that crosses its outer ring cannot be opened by a move:
// the polygons come back as they were, and the place is named.
TEST(OpenPinches, no_pinch_leaves_the_footprint_alone_and_crossing_rings_are_named) {
  const std::vector<Polygon2> given{
      {{{0, 0}, {6, 0}, {6.003, 0.002}, {12, 0}, {12, 10}, {0, 10}}, {{{6, 0.05}, {4, 4}, {8, 4}}}},
      {{{20, 0}, {24, 0}, {24, 4}, {20, 4}}, {}}};
  std::vector<Polygon2> polygons = given;
  EXPECT_TRUE(open_pinches(polygons, 0.01).empty());
  EXPECT_EQ(moves(given, polygons).first, 0);

  const std::vector<Polygon2> crossing{
      {{{0, 0}, {12, 0}, {12, 10}, {0, 10}}, {{{6, 0}, {4, 4}, {8, 4}, {9, -1}}}}};
  polygons = crossing;
  Point2 unopened{NAN, NAN};
  EXPECT_TRUE(open_pinches(polygons, 0.01, &unopened).empty());
  EXPECT_EQ(moves(crossing, polygons).first, 0);
  EXPECT_EQ(unopened.x, 6.0);
  EXPECT_EQ(unopened.y, 0.0);
}

}  // namespace city3d
