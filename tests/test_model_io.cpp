// Tests of the OBJ / PLY model writers against reference files and by reading the output back.
#include <gtest/gtest.h>

#include <cstdlib>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "city3d/error.hpp"
#include "city3d/model_io.hpp"

namespace fs = std::filesystem;
using namespace city3d;

namespace {

// A unit-ish box (2 x 1 x 3 m) in a local frame, faces counter-clockwise seen from outside.
BuildingModel box_model(const std::string& id, Point3 origin) {
  BuildingModel m;
  m.id = id;
  m.origin = origin;
  m.mesh.vertices = {{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {0, 1, 0}, {0, 0, 3}, {2, 0, 3}, {2, 1, 3}, {0, 1, 3}};
  m.mesh.faces = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  return m;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The reference files hold "@VERSION@" where the writer puts the library version.
std::string reference(const std::string& name) {
  std::string text = read_text(fs::path(CITY3D_TEST_DATA) / "model" / name);
  const std::string tag = "@VERSION@";
  for (auto pos = text.find(tag); pos != std::string::npos; pos = text.find(tag))
    text.replace(pos, tag.size(), CITY3D_VERSION);
  return text;
}

class ModelWriter : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("city3d_model_io_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

}  // namespace

TEST_F(ModelWriter, writes_obj_in_world_coordinates_matching_reference) {
  const fs::path out = dir_ / "box.obj";
  write_model(out.string(), box_model("NL.IMBAG.Pand.0503100000018603", {84916.949, 447413.3, 5.977}),
              {MeshFormat::obj, false});
  EXPECT_EQ(read_text(out), reference("box_world.obj"));
}

TEST_F(ModelWriter, writes_obj_in_local_coordinates_with_origin_comment) {
  const fs::path out = dir_ / "box.obj";
  write_model(out.string(), box_model("b1", {84916.949, 447413.3, 5.977}), {MeshFormat::obj, true});
  EXPECT_EQ(read_text(out), reference("box_local.obj"));
}

TEST_F(ModelWriter, keeps_millimetres_at_rd_new_magnitudes) {
  BuildingModel m = box_model("b", {85000.0, 447000.0, 0.0});
  m.mesh.vertices[0] = {0.0004, 0.0016, 0.0};  // world 85000.0004, 447000.0016
  const fs::path out = dir_ / "b.obj";
  write_model(out.string(), m, {MeshFormat::obj, false});
  const std::string text = read_text(out);
  EXPECT_NE(text.find("v 85000.0004 447000.0016 0.0000\n"), std::string::npos) << text;
}

TEST_F(ModelWriter, merged_obj_has_one_group_per_building_with_offset_indices) {
  const fs::path out = dir_ / "all.obj";
  write_models(out.string(), {box_model("a", {0, 0, 0}), box_model("b", {10, 0, 0})}, {MeshFormat::obj, false});
  const std::string text = read_text(out);
  EXPECT_NE(text.find("o a\n"), std::string::npos);
  EXPECT_NE(text.find("o b\n"), std::string::npos);
  // The second building's first face uses its own vertices 9..16.
  EXPECT_NE(text.find("o b\nv 10.0000 0.0000 0.0000\n"), std::string::npos);
  EXPECT_NE(text.find("f 9 12 11 10\n"), std::string::npos);
  EXPECT_EQ(text.find("f 1 4 3 2\n"), text.rfind("f 1 4 3 2\n"));
}

TEST_F(ModelWriter, writes_ascii_ply_matching_reference) {
  const fs::path out = dir_ / "box.ply";
  write_model(out.string(), box_model("b1", {100.0, 200.0, 0.5}), {MeshFormat::ply_ascii, false});
  EXPECT_EQ(read_text(out), reference("box_world_ascii.ply"));
}

TEST_F(ModelWriter, writes_binary_ply_that_reads_back_exactly) {
  const fs::path out = dir_ / "box.ply";
  const BuildingModel m = box_model("b1", {84916.949, 447413.3, 5.977});
  write_model(out.string(), m, {MeshFormat::ply_binary, false});
  const std::string text = read_text(out);
  const std::string end = "end_header\n";
  const auto body = text.find(end);
  ASSERT_NE(body, std::string::npos);
  EXPECT_NE(text.find("format binary_little_endian 1.0\n"), std::string::npos);
  EXPECT_NE(text.find("element vertex 8\n"), std::string::npos);
  EXPECT_NE(text.find("element face 6\n"), std::string::npos);
  const char* p = text.data() + body + end.size();
  for (const Point3& v : m.mesh.vertices) {
    double xyz[3];
    std::memcpy(xyz, p, sizeof xyz);  // the test host is little-endian (x86-64)
    p += sizeof xyz;
    EXPECT_DOUBLE_EQ(xyz[0], v.x + m.origin.x);
    EXPECT_DOUBLE_EQ(xyz[1], v.y + m.origin.y);
    EXPECT_DOUBLE_EQ(xyz[2], v.z + m.origin.z);
  }
  for (const auto& face : m.mesh.faces) {
    ASSERT_EQ(static_cast<unsigned char>(*p), face.size());
    ++p;
    for (std::uint32_t v : face) {
      std::int32_t index;
      std::memcpy(&index, p, 4);
      p += 4;
      EXPECT_EQ(index, static_cast<std::int32_t>(v));
    }
  }
  EXPECT_EQ(p, text.data() + text.size());
}

TEST_F(ModelWriter, merged_ply_records_building_ids_and_per_face_index) {
  const fs::path out = dir_ / "all.ply";
  write_models(out.string(), {box_model("first", {0, 0, 0}), box_model("second", {5, 0, 0})},
               {MeshFormat::ply_ascii, false});
  const std::string text = read_text(out);
  EXPECT_NE(text.find("comment building 0 first\n"), std::string::npos);
  EXPECT_NE(text.find("comment building 1 second\n"), std::string::npos);
  EXPECT_NE(text.find("property int building\n"), std::string::npos);
  EXPECT_NE(text.find("\n4 8 11 10 9 1\n"), std::string::npos) << text;
}

TEST_F(ModelWriter, rejects_faces_with_out_of_range_vertices) {
  BuildingModel m = box_model("broken", {0, 0, 0});
  m.mesh.faces.push_back({0, 1, 42});
  try {
    write_model((dir_ / "x.obj").string(), m, {MeshFormat::obj, false});
    FAIL() << "no exception";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("broken"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("vertex 42"), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(dir_ / "x.obj"));
}

TEST_F(ModelWriter, reports_unwritable_path_and_leaves_no_temporary_file) {
  const fs::path out = dir_ / "no_such_dir" / "x.obj";
  try {
    write_model(out.string(), box_model("b", {0, 0, 0}), {MeshFormat::obj, false});
    FAIL() << "no exception";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_dir/x.obj"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_empty(dir_));
}

TEST_F(ModelWriter, overwrites_atomically_without_leftovers) {
  const fs::path out = dir_ / "b.obj";
  write_model(out.string(), box_model("old", {0, 0, 0}), {MeshFormat::obj, false});
  write_model(out.string(), box_model("new", {0, 0, 0}), {MeshFormat::obj, false});
  EXPECT_NE(read_text(out).find("o new\n"), std::string::npos);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

TEST(ModelFileName, replaces_unsafe_characters_and_never_returns_a_hidden_name) {
  EXPECT_EQ(model_file_name("NL.IMBAG.Pand.0503100000018603", MeshFormat::obj), "NL.IMBAG.Pand.0503100000018603.obj");
  EXPECT_EQ(model_file_name("a/b c:d", MeshFormat::ply_binary), "a_b_c_d-9ce7b96e.ply");
  EXPECT_EQ(model_file_name("", MeshFormat::obj), "_-811c9dc5.obj");
  EXPECT_EQ(model_file_name("..", MeshFormat::obj), "_..-a3d4a70d.obj");
}

// A 300-character id (or a cloud's 240-character file name) made a name the file system refused, and
// the run ended: the name is cut to 200 bytes, with the hash of the whole id.
TEST(ModelFileName, a_long_id_is_cut_to_two_hundred_bytes_and_keeps_its_hash) {
  const std::string a(300, 'a'), b = std::string(299, 'a') + "b";
  const std::string name = model_file_name(a, MeshFormat::obj);
  EXPECT_EQ(name.size(), 200u + 9u + 4u);
  EXPECT_EQ(name.substr(0, 200), std::string(200, 'a'));
  EXPECT_NE(name, model_file_name(b, MeshFormat::obj));
  EXPECT_EQ(model_file_name(std::string(200, 'a'), MeshFormat::obj), std::string(200, 'a') + ".obj");
  const fs::path dir = fs::temp_directory_path() / "city3d_long_name";
  fs::create_directories(dir);
  write_model((dir / name).string(), box_model(a, {0, 0, 0}), {MeshFormat::obj, false});
  EXPECT_TRUE(fs::exists(dir / name));
  fs::remove_all(dir);
}

// Issue 24 item 3: ids that differ only in characters a file name cannot hold shared one model file.
TEST(ModelFileName, distinct_ids_never_share_a_file_name) {
  EXPECT_NE(model_file_name("a b", MeshFormat::obj), model_file_name("a_b", MeshFormat::obj));
  EXPECT_EQ(model_file_name("a_b", MeshFormat::obj), "a_b.obj");
  EXPECT_NE(model_file_name("Dales3d/00011", MeshFormat::obj), model_file_name("Dales3d_00011", MeshFormat::obj));
  EXPECT_NE(model_file_name("Dales3d/00011", MeshFormat::obj), model_file_name("Dales3d:00011", MeshFormat::obj));
}

TEST(MeshFormatName, parses_known_names_and_rejects_others) {
  EXPECT_EQ(parse_mesh_format("obj"), MeshFormat::obj);
  EXPECT_EQ(parse_mesh_format("ply"), MeshFormat::ply_binary);
  EXPECT_EQ(parse_mesh_format("ply-ascii"), MeshFormat::ply_ascii);
  EXPECT_THROW(parse_mesh_format("stl"), ConfigError);
}

/// A city object of one geometry.
CityObject one_lod(const BuildingModel& m, const std::string& lod, Attributes attributes = {}) {
  return CityObject{m.id, {{lod, m}}, std::move(attributes)};
}

TEST_F(ModelWriter, writes_cityjson_matching_reference) {
  const fs::path out = dir_ / "box.city.json";
  CityObject object = one_lod(box_model("b1", {84916.9491, 447413.3, 5.977}), "1.2",
                              {{"status", std::string("ok")}, {"rmse", 0.125}, {"points", std::int64_t{1234}},
                               {"note", AttributeValue{}}, {"strict", false}});
  write_cityjson(out.string(), {object}, {"EPSG:28992", 0.001, ""}, {84916, 447413, 5});
  EXPECT_EQ(read_text(out), reference("box.city.json"));
}

TEST_F(ModelWriter, cityjson_uses_the_transform_it_is_given) {
  // Scale 0.0001 (the default) and a given translation: 84916.9491 - 84900 = 16.9491 m = 169491 units.
  const fs::path out = dir_ / "t.city.json";
  write_cityjson(out.string(), {one_lod(box_model("b1", {84916.9491, 447413.3, 5.977}), "2.2")}, CityJsonOptions{},
                 {84900, 447400, 0});
  const std::string text = read_text(out);
  EXPECT_NE(text.find("\"transform\":{\"scale\":[0.0001,0.0001,0.0001],\"translate\":[84900,447400,0]}"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("\"vertices\":[[169491,133000,59770],"), std::string::npos) << text;
}

TEST_F(ModelWriter, cityjson_shares_vertices_and_labels_faces_by_normal) {
  const fs::path out = dir_ / "two.city.json";
  write_cityjson(out.string(), {one_lod(box_model("a", {0, 0, 0}), "2.2"), one_lod(box_model("b", {10, 0, 0}), "2.2")},
                 {"", 0.001, ""}, {0, 0, 0});
  const std::string text = read_text(out);
  // 8 distinct vertices per building, none shared across buildings: 16 in all.
  std::size_t vertices = 0;
  for (auto pos = text.find("\"vertices\":[[") + 12; pos < text.size(); ++pos)
    if (text[pos] == '[') ++vertices;
  EXPECT_EQ(vertices, 16u);
  // Face order floor, roof, 4 walls -> ground 0, wall 1, roof 2.
  EXPECT_NE(text.find("\"values\":[[0,2,1,1,1,1]]"), std::string::npos) << text;
  EXPECT_EQ(text.find("referenceSystem"), std::string::npos);
}

TEST_F(ModelWriter, cityjson_building_with_three_lods_and_two_parts_validates) {
  // Three levels of detail on one Building, sharing vertices; a level whose model has two detached
  // blocks (a multipolygon footprint) gives two BuildingParts of one Solid each, since a Solid has
  // one exterior shell and a Building has no MultiSolid.
  BuildingModel two = box_model("b", {85000, 447000, 0});
  const BuildingModel other = box_model("", {0, 0, 0});
  for (const Point3& p : other.mesh.vertices) two.mesh.vertices.push_back({p.x + 5, p.y, p.z});
  for (auto face : other.mesh.faces) {
    for (auto& v : face) v += 8;
    two.mesh.faces.push_back(face);
  }
  const BuildingModel one = box_model("b", {85000, 447000, 0});
  CityObject object{"b", {{"1.2", one}, {"1.3", one}, {"2.2", two}}, {{"status", std::string("ok")}}};
  const fs::path out = dir_ / "lods.city.json";
  write_cityjson(out.string(), {object}, {"EPSG:28992", 0.0001, ""}, {84999, 446999, 0});
  const std::string text = read_text(out);
  EXPECT_NE(text.find("\"b\":{\"type\":\"Building\",\"attributes\":{\"status\":\"ok\"},\"geometry\":[{\"type\":\"Solid\",\"lod\":\"1.2\""),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("{\"type\":\"Solid\",\"lod\":\"1.3\",\"boundaries\":[[[[0,3,2,1]]"), std::string::npos) << text;
  EXPECT_NE(text.find("\"children\":[\"b-2.2-1\",\"b-2.2-2\"]}"), std::string::npos) << text;
  EXPECT_NE(text.find("\"b-2.2-2\":{\"type\":\"BuildingPart\",\"parents\":[\"b\"],\"geometry\":[{\"type\":\"Solid\",\"lod\":\"2.2\",\"boundaries\":[[[[8,11,10,9]]"),
            std::string::npos)
      << text;
  // 8 + 8 vertices: LoD1.2 and LoD1.3 reuse LoD2.2's first block.
  std::size_t vertices = 0;
  for (auto pos = text.find("\"vertices\":[[") + 12; pos < text.size(); ++pos)
    if (text[pos] == '[') ++vertices;
  EXPECT_EQ(vertices, 16u);

  const std::string schemas = CITY3D_SCHEMAS;
  if (!fs::exists(schemas) || !fs::exists(CITY3D_AJV)) GTEST_SKIP() << "no schemas or ajv-cli: not validated";
  std::string command = std::string(CITY3D_AJV) + " validate --spec=draft7 --strict=false -s " + schemas +
                        "/cityjson.schema.json";
  for (const char* r : {"appearance", "cityobjects", "geomprimitives", "geomtemplates", "metadata"})
    command += " -r " + schemas + "/" + r + ".schema.json";
  command += " -d " + out.string() + " > " + (dir_ / "ajv.txt").string() + " 2>&1";
  EXPECT_EQ(std::system(command.c_str()), 0) << read_text(dir_ / "ajv.txt");
}

TEST(SurfaceTypes, uses_given_semantics_when_present) {
  BuildingModel m = box_model("b", {0, 0, 0});
  m.surfaces.assign(m.mesh.faces.size(), SurfaceType::roof);
  for (SurfaceType t : surface_types(m)) EXPECT_EQ(t, SurfaceType::roof);
  m.surfaces.clear();
  const auto types = surface_types(m);
  ASSERT_EQ(types.size(), 6u);
  EXPECT_EQ(types[0], SurfaceType::ground);
  EXPECT_EQ(types[1], SurfaceType::roof);
  EXPECT_EQ(types[2], SurfaceType::wall);
}

TEST_F(ModelWriter, cityjsonseq_writes_header_then_one_feature_per_line) {
  const fs::path out = dir_ / "all.city.jsonl";
  {
    CityJsonSeqWriter writer(out.string(), {"EPSG:28992", 0.001, ""}, {84000, 447000, 0});
    writer.add(one_lod(box_model("a", {84001, 447002, 1}), "2.2", {{"status", std::string("ok")}}));
    writer.add(one_lod(box_model("b", {84010, 447002, 1}), "2.2"));
    EXPECT_FALSE(fs::exists(out));  // only under its final name once closed
    writer.close();
  }
  std::ifstream in(out);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[0],
            "{\"type\":\"CityJSON\",\"version\":\"2.0\",\"transform\":{\"scale\":[0.001,0.001,0.001],\"translate\":["
            "84000,447000,0]},\"metadata\":{\"referenceSystem\":\"https://www.opengis.net/def/crs/EPSG/0/28992\","
            "\"geographicalExtent\":[84001,447002,1,84012,447003,4]},\"CityObjects\":{},\"vertices\":[]}");
  EXPECT_EQ(lines[1].rfind("{\"type\":\"CityJSONFeature\",\"id\":\"a\",\"CityObjects\":{\"a\":{", 0), 0u);
  // Building a's first vertex: (84001 - 84000, 447002 - 447000, 1 - 0) m in millimetres.
  EXPECT_NE(lines[1].find("\"vertices\":[[1000,2000,1000],"), std::string::npos) << lines[1];
  EXPECT_NE(lines[2].find("\"vertices\":[[10000,2000,1000],"), std::string::npos) << lines[2];
}

TEST_F(ModelWriter, cityjsonseq_leaves_nothing_when_not_closed) {
  const fs::path out = dir_ / "partial.city.jsonl";
  {
    CityJsonSeqWriter writer(out.string(), {"", 0.001, ""}, {0, 0, 0});
    writer.add(one_lod(box_model("a", {0, 0, 0}), "2.2"));
  }
  EXPECT_TRUE(fs::is_empty(dir_));
}
