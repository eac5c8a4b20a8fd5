// Issue 24: nothing silently wrong. The ordinary mistakes of a new user, each caught, stated, or
// given its own output: twin tiles, footprints the tiles only partly cover, clouds of the same name
// or the same bytes, a non-unique id field, runs that build nothing, reruns into a folder, and the
// small things of the command line. Each test checks outputs (ids, counts, status, coverage, exit
// code), not the wording of messages; real data where it exists (../shared/data), else made here.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "batch/input_check.hpp"
#include "city3d/footprint_io.hpp"
#include "city3d/point_cloud_io.hpp"
#include "las_writer.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

struct Result {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

Result run_shell(const std::string& command_line) {
  Result r;
  FILE* pipe = popen((command_line + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

Result run(const std::string& arguments) { return run_shell(std::string(CITY3D_EXE) + " " + arguments); }

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

const std::string kShared = CITY3D_SHARED_DATA;
const std::string kDelft = kShared + "/ahn3_delft";
const std::string kTile1 = kDelft + "/ahn3_cropped_1.las";
const std::string kTile2 = kDelft + "/ahn3_cropped_2.las";
const std::string kGpkg = kDelft + "/footprints/bgt_pand_laz_area.gpkg";
const std::string kSample = CITY3D_SAMPLE_DATA;

/// report.json of an output folder.
json report(const fs::path& out) { return json::parse(read_file(out / "report.json")); }

/// id -> that building's row of report.json.
std::map<std::string, json> rows_by_id(const fs::path& out) {
  std::map<std::string, json> rows;
  const json whole = report(out);
  for (const json& row : whole.at("buildings")) rows[row.at("id").get<std::string>()] = row;
  return rows;
}

class Mistakes : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("city3d_mistakes_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }
  static void require_shared_data() {
    if (!fs::exists(kTile1)) GTEST_SKIP() << "../shared/data is not beside the repository";
  }
  fs::path dir_;
};

}  // namespace

// --- 1. twins: a folder with LAS and LAZ of the same tiles doubled every point ---

TEST_F(Mistakes, folder_with_las_and_laz_twins_reads_each_tile_once) {
  require_shared_data();
  const std::string tail = " -f " + kGpkg + " --id-field gml_id -j 2 --no-progress -o ";
  ASSERT_EQ(run("reconstruct " + kTile1 + " " + kTile2 + tail + (dir_ / "las").string()).exit_code, 0);
  const Result folder = run("reconstruct " + kDelft + tail + (dir_ / "folder").string());
  ASSERT_EQ(folder.exit_code, 0) << folder.output;
  // The same points per building (76,818 -> 153,636 before), so the same models.
  const auto las = rows_by_id(dir_ / "las"), twins = rows_by_id(dir_ / "folder");
  ASSERT_EQ(twins.size(), 160u);
  std::size_t points = 0;
  for (const auto& [id, row] : las) {
    ASSERT_TRUE(twins.count(id)) << id;
    EXPECT_EQ(twins.at(id).at("points"), row.at("points")) << id;
    points += row.at("points").get<std::size_t>();
  }
  EXPECT_GT(points, 70000u);
  EXPECT_EQ(read_file(dir_ / "folder" / "buildings.city.json"), read_file(dir_ / "las" / "buildings.city.json"));
}

// The LAZ set's manifest gives each pair's point-block SHA-256: files of one SHA hold the same
// points (a LAS file and its LAZ, and the same records as LAS 1.2, 1.3 and 1.4), and only those.
TEST(Twins, files_of_the_laz_set_are_one_tile_exactly_when_their_point_blocks_are_the_same) {
  const fs::path set = kShared + "/laz";
  if (!fs::exists(set / "manifest.json")) GTEST_SKIP() << "../shared/data is not beside the repository";
  const json manifest = json::parse(read_file(set / "manifest.json"));
  std::map<std::string, std::string> sha_of;  // file name -> point-block SHA-256
  for (const json& pair : manifest.at("pairs")) {
    // Two files without points have the same (empty) block; in other point formats they are other tiles.
    const std::string name = pair.at("name").get<std::string>(),
                      sha = pair.at("point_block_sha256").get<std::string>() + " " + pair.at("point_format").dump();
    sha_of[name + ".las"] = sha_of[name + ".laz"] = sha;
  }
  ASSERT_EQ(sha_of.size(), 52u);
  std::vector<std::string> files, expected;
  std::set<std::string> seen;
  for (const auto& [name, sha] : sha_of) {  // sorted by name: NAME.las before NAME.laz
    files.push_back((set / "cases" / name).string());
    if (seen.insert(sha).second) expected.push_back(files.back());
  }
  EXPECT_EQ(expected.size(), 23u);  // 26 pairs, three of them the records of another pair
  EXPECT_EQ(city3d::detail::distinct_inputs(files), expected);
}

TEST_F(Mistakes, tiles_of_one_header_but_other_end_records_are_both_read) {
  std::vector<city3d::test::LasPoint> points;
  for (int i = 0; i < 500; ++i) points.push_back({85000.0 + (i % 20) * 0.5, 447550.0 + (i / 20) * 0.5, 5.0 + i % 3, 6});
  city3d::test::write_las((dir_ / "a.las").string(), points);
  // The same header facts (count, bounds, scale, offset), one record at the end swapped.
  std::swap(points[498], points[499]);
  city3d::test::write_las((dir_ / "b.las").string(), points);
  // And a twin in all but the first record's class.
  points[0].classification = 2;
  std::swap(points[498], points[499]);
  city3d::test::write_las((dir_ / "c.las").string(), points);
  const std::vector<std::string> files = {(dir_ / "a.las").string(), (dir_ / "b.las").string(),
                                          (dir_ / "c.las").string()};
  EXPECT_EQ(city3d::detail::distinct_inputs(files), files);
  // And the same file's bytes under another name is still one tile.
  fs::copy_file(dir_ / "a.las", dir_ / "d.las");
  EXPECT_EQ(city3d::detail::distinct_inputs({files[0], (dir_ / "d.las").string()}), std::vector<std::string>{files[0]});
}

// --- 3. clouds of the same file name overwrote each other's model and shared an id ---

TEST_F(Mistakes, clouds_of_the_same_name_get_ids_from_their_paths_and_files_of_their_own) {
  const fs::path dales = kShared + "/city3d_dev/Dales3d/00011.ply", vaihingen = kShared + "/city3d_dev/Vaihingen/00011.ply";
  if (!fs::exists(dales)) GTEST_SKIP() << "../shared/data is not beside the repository";
  const Result r = run("reconstruct " + dales.string() + " " + vaihingen.string() + " --no-progress -o " +
                       (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto rows = rows_by_id(dir_ / "out");
  ASSERT_EQ(rows.size(), 2u);
  ASSERT_TRUE(rows.count("Dales3d/00011")) << r.output;
  ASSERT_TRUE(rows.count("Vaihingen/00011")) << r.output;
  // Each note says how its id was made; each building has its own model file and CityJSON object.
  for (const auto& [id, row] : rows) EXPECT_TRUE(contains(row.at("note").get<std::string>(), "id: the path below")) << id;
  EXPECT_NE(rows.at("Dales3d/00011").at("points"), rows.at("Vaihingen/00011").at("points"));
  std::size_t models = 0;
  for (const auto& entry : fs::directory_iterator(dir_ / "out" / "models")) models += entry.path().extension() == ".obj";
  EXPECT_EQ(models, 2u);
  const json city = json::parse(read_file(dir_ / "out" / "buildings.city.json"));
  EXPECT_TRUE(city.at("CityObjects").contains("Dales3d/00011"));
  EXPECT_TRUE(city.at("CityObjects").contains("Vaihingen/00011"));
  // A file of the same name beside them again, in one of the folders' copies: x.ply and x.PLY do
  // not meet, but a path that is still shared keeps its extension.
  fs::create_directories(dir_ / "twin");
  fs::copy_file(vaihingen, dir_ / "twin" / "00011.ply");
  fs::copy_file(vaihingen, dir_ / "twin" / "00011.PLY");
  const Result same_folder = run("reconstruct " + (dir_ / "twin").string() + " --no-progress -o " + (dir_ / "out2").string());
  ASSERT_EQ(same_folder.exit_code, 0) << same_folder.output;
  const auto rows2 = rows_by_id(dir_ / "out2");
  EXPECT_EQ(rows2.size(), 2u);
  EXPECT_TRUE(rows2.count("00011.ply") && rows2.count("00011.PLY")) << same_folder.output;
}

// --- 4. two clouds of identical bytes: the second was "read once" and vanished without a row ---

TEST_F(Mistakes, clouds_of_identical_bytes_are_two_buildings_with_a_row_each) {
  const fs::path cloud = kShared + "/city3d_dev/AHN3/00262.ply";
  if (!fs::exists(cloud)) GTEST_SKIP() << "../shared/data is not beside the repository";
  fs::create_directories(dir_ / "clouds");
  fs::copy_file(cloud, dir_ / "clouds" / "a.ply");
  fs::copy_file(cloud, dir_ / "clouds" / "b.ply");
  const Result r = run("reconstruct " + (dir_ / "clouds").string() + " --no-progress -o " + (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto rows = rows_by_id(dir_ / "out");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows.at("a").at("points"), rows.at("b").at("points"));
  EXPECT_EQ(rows.at("a").at("status"), rows.at("b").at("status"));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "models" / "a.obj"));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "models" / "b.obj"));
  // The same file named twice is still one building.
  const Result twice = run("reconstruct " + (dir_ / "clouds" / "a.ply").string() + " " + (dir_ / "clouds").string() +
                           " --no-progress -o " + (dir_ / "out2").string());
  ASSERT_EQ(twice.exit_code, 0) << twice.output;
  EXPECT_EQ(rows_by_id(dir_ / "out2").size(), 2u);
}

// --- 2. footprints the tiles given only partly cover came out ok and wrong ---

namespace {

// The seven footprints across the Delft seam (x = 85000) with the share of their area in tile 1
// (x < 85000): b11282794 99.9%, b31bdfb64 91.9%, b11282799 72.6%, b31bdfb67 46.0%, b31be22a8 30.8%,
// b1105d28c (fid 95) 13.8%, b31bdfb6a 4.1%; and b31bdd428, wholly in tile 2.
const std::vector<std::string> kSeam = {
    "b11282794-00ba-11e6-b420-2bdcc4ab5d7f", "b31bdfb64-00ba-11e6-b420-2bdcc4ab5d7f",
    "b11282799-00ba-11e6-b420-2bdcc4ab5d7f", "b31bdfb67-00ba-11e6-b420-2bdcc4ab5d7f",
    "b31be22a8-00ba-11e6-b420-2bdcc4ab5d7f", "b1105d28c-00ba-11e6-b420-2bdcc4ab5d7f",
    "b31bdfb6a-00ba-11e6-b420-2bdcc4ab5d7f"};
const std::string kInTile2 = "b31bdd428-00ba-11e6-b420-2bdcc4ab5d7f";

std::string seam_where() {
  std::string where = "--where \"gml_id IN ('" + kInTile2 + "'";
  for (const std::string& id : kSeam) where += ", '" + id + "'";
  return where + ")\"";
}

}  // namespace

TEST_F(Mistakes, footprints_the_tiles_cover_only_in_part_are_partial_in_every_output_and_fail_a_strict_run) {
  require_shared_data();
  const std::string tail = " -f " + kGpkg + " --id-field gml_id " + seam_where() + " --gpkg -j 2 --no-progress -o ";
  // Both tiles: every seam footprint is covered in full, and ok.
  const Result both = run("reconstruct " + kTile1 + " " + kTile2 + tail + (dir_ / "both").string());
  ASSERT_EQ(both.exit_code, 0) << both.output;
  auto rows = rows_by_id(dir_ / "both");
  ASSERT_EQ(rows.size(), 8u);
  for (const std::string& id : kSeam) {
    EXPECT_EQ(rows.at(id).at("status"), "ok") << id;
    EXPECT_EQ(rows.at(id).at("coverage"), 1.0) << id;
  }
  // Tile 1 alone: the six it cuts by more than 1% of their area are partial, the seventh ok; the
  // footprint wholly in tile 2 has coverage 0 (and no points, so skipped).
  const Result one = run("reconstruct " + kTile1 + tail + (dir_ / "one").string());
  ASSERT_EQ(one.exit_code, 0) << one.output;
  rows = rows_by_id(dir_ / "one");
  ASSERT_EQ(rows.size(), 8u);
  EXPECT_EQ(rows.at(kSeam[0]).at("status"), "ok");
  EXPECT_GE(rows.at(kSeam[0]).at("coverage").get<double>(), 0.95);
  double previous = 1.0;
  for (std::size_t k = 1; k < kSeam.size(); ++k) {
    const json& row = rows.at(kSeam[k]);
    EXPECT_EQ(row.at("status"), "partial") << kSeam[k];
    const double coverage = row.at("coverage").get<double>();
    EXPECT_LT(coverage, 0.95) << kSeam[k];
    EXPECT_LT(coverage, previous) << kSeam[k];  // in the order of their share in tile 1
    previous = coverage;
    EXPECT_NE(row.at("level"), "none") << kSeam[k];  // still reconstructed, from what points there are
  }
  EXPECT_LT(rows.at(kSeam[6]).at("coverage").get<double>(), 0.1);
  EXPECT_EQ(rows.at(kInTile2).at("status"), "skipped");
  EXPECT_EQ(rows.at(kInTile2).at("coverage"), 0.0);
  EXPECT_EQ(report(dir_ / "one").at("summary").at("partial"), 6);
  // The same in CityJSON's attributes and in the GeoPackage.
  const json city = json::parse(read_file(dir_ / "one" / "buildings.city.json"));
  const json& fid95 = city.at("CityObjects").at("b1105d28c-00ba-11e6-b420-2bdcc4ab5d7f").at("attributes");
  EXPECT_EQ(fid95.at("status"), "partial");
  EXPECT_LT(fid95.at("coverage").get<double>(), 0.2);
  const Result gpkg = run_shell("ogrinfo -q -sql \"SELECT gml_id, status, coverage FROM buildings WHERE status = "
                                "'partial'\" " + (dir_ / "one" / "buildings.gpkg").string());
  ASSERT_EQ(gpkg.exit_code, 0) << gpkg.output;
  std::size_t partial_features = 0;
  for (std::size_t at = gpkg.output.find("status (String) = partial"); at != std::string::npos;
       at = gpkg.output.find("status (String) = partial", at + 1))
    ++partial_features;
  EXPECT_EQ(partial_features, 6u) << gpkg.output;
  EXPECT_TRUE(contains(gpkg.output, "coverage (Real) = 0.14")) << gpkg.output;
  // --strict makes it a failure: 4 on the whole block with tile 1 (6 partial of 160), 5 here, where
  // they are most of the buildings (the run's main problem).
  EXPECT_EQ(run("reconstruct " + kTile1 + " -f " + kGpkg + " --id-field gml_id -j 2 --no-progress --no-html --strict -o " +
                (dir_ / "strict").string())
                .exit_code,
            4);
  EXPECT_EQ(run("reconstruct " + kTile1 + tail + (dir_ / "strict_most").string() + " --strict").exit_code, 5);
  // --min-coverage 0 turns the check off.
  const Result off = run("reconstruct " + kTile1 + tail + (dir_ / "off").string() + " --min-coverage 0");
  ASSERT_EQ(off.exit_code, 0) << off.output;
  EXPECT_EQ(report(dir_ / "off").at("summary").at("partial"), 0);
  EXPECT_EQ(rows_by_id(dir_ / "off").at(kSeam[5]).at("coverage"), rows.at(kSeam[5]).at("coverage"));
}

// --- 5. a non-unique --id-field: 159 warnings, then 1 ok and 159 skipped, exit 0 ---

TEST_F(Mistakes, an_id_field_most_footprints_share_is_one_error_naming_the_fields_that_are_ids) {
  require_shared_data();
  const Result r = run("reconstruct " + kTile1 + " " + kTile2 + " -f " + kGpkg + " --id-field rel_hoogte --no-progress -o " +
                       (dir_ / "out").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "out")) << "a run refused on its inputs leaves no folder";
  EXPECT_FALSE(contains(r.output, "warning")) << "one error, not a warning per footprint:\n" << r.output;
  EXPECT_TRUE(contains(r.output, "rel_hoogte")) << r.output;
  for (const char* id_field : {"gml_id", "lokaalid", "bag_pnd"}) EXPECT_TRUE(contains(r.output, id_field)) << r.output;
}

TEST_F(Mistakes, a_few_duplicated_ids_are_skipped_each_and_the_others_reconstructed) {
  // The sample's footprints with a field "pid": gml_id, but the same value for two of the 15.
  const fs::path footprints = dir_ / "pid.gpkg";
  const Result made = run_shell("ogr2ogr -f GPKG " + footprints.string() + " " + kSample +
                                "/delft_sample_footprints.gpkg -dialect sqlite -sql \"SELECT *, CASE WHEN gml_id IN "
                                "('b31e1d795-00ba-11e6-b420-2bdcc4ab5d7f', 'b11282794-00ba-11e6-b420-2bdcc4ab5d7f') "
                                "THEN 'twice' ELSE gml_id END AS pid FROM buildingpart\" -nln buildingpart");
  ASSERT_EQ(made.exit_code, 0) << made.output;
  const Result r = run("reconstruct " + kSample + "/delft_sample_1.las " + kSample + "/delft_sample_2.las -f " +
                       footprints.string() + " --id-field pid --no-progress -o " + (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json whole = report(dir_ / "out");
  EXPECT_EQ(whole.at("summary").at("buildings"), 15);
  EXPECT_EQ(whole.at("summary").at("skipped"), 1);
  EXPECT_EQ(whole.at("summary").at("ok").get<int>() + whole.at("summary").at("fallback").get<int>(), 14);
  // The first feature of an id keeps it; the second's row says whose it is (skipped rows come last).
  std::vector<std::string> twice;
  for (const json& row : whole.at("buildings"))
    if (row.at("id") == "twice") twice.push_back(row.at("status").get<std::string>() + " " + row.at("reason").get<std::string>());
  ASSERT_EQ(twice.size(), 2u);
  EXPECT_TRUE(twice[0] == "ok " || twice[0].rfind("fallback ", 0) == 0) << twice[0];
  EXPECT_EQ(twice[1].rfind("skipped duplicated id (first at fid", 0), 0u) << twice[1];
}

// --- 6. runs that build nothing exited 0 ---

TEST_F(Mistakes, a_filter_that_leaves_no_footprint_is_an_error_before_anything_is_written) {
  const std::string base = "reconstruct " + kSample + "/delft_sample_1.las -f " + kSample +
                           "/delft_sample_footprints.gpkg --id-field gml_id --no-progress ";
  Result r = run(base + "--where \"gml_id = 'nope'\" -o " + (dir_ / "where").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "where"));
  EXPECT_TRUE(contains(r.output, "gml_id = 'nope'")) << r.output;
  r = run(base + "--bbox 0,0,10,10 -o " + (dir_ / "bbox").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "bbox"));
  // A filter that keeps one is a run.
  r = run(base + "--where \"gml_id = 'b31be49eb-00ba-11e6-b420-2bdcc4ab5d7f'\" -o " + (dir_ / "one").string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(report(dir_ / "one").at("summary").at("buildings"), 1);
}

TEST_F(Mistakes, tiles_without_the_building_class_build_nothing_exit_1_and_name_the_classes_present) {
  // The sample tiles with every building point made class 1: a run skips every footprint.
  for (const char* tile : {"delft_sample_1.las", "delft_sample_2.las"}) {
    const city3d::PointCloud cloud = city3d::read_point_cloud(kSample + "/" + tile, city3d::kFieldClassification);
    std::vector<city3d::test::LasPoint> points;
    for (std::size_t i = 0; i < cloud.size(); ++i)
      points.push_back({cloud.points[i].x, cloud.points[i].y, cloud.points[i].z,
                        static_cast<std::uint8_t>(cloud.classification[i] == 6 ? 1 : cloud.classification[i])});
    city3d::test::write_las((dir_ / tile).string(), points);
  }
  const std::string tiles = (dir_ / "delft_sample_1.las").string() + " " + (dir_ / "delft_sample_2.las").string();
  const std::string tail = " -f " + kSample + "/delft_sample_footprints.gpkg --id-field gml_id --no-progress -o ";
  const Result r = run("reconstruct " + tiles + tail + (dir_ / "none").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  const json whole = report(dir_ / "none");  // the report is written, every row with its reason
  EXPECT_EQ(whole.at("summary").at("buildings"), 15);
  EXPECT_EQ(whole.at("summary").at("skipped"), 15);
  // The last lines name the option and the classes the tiles do hold (1 and 2, not 6).
  EXPECT_TRUE(contains(r.output, "--building-classes")) << r.output;
  EXPECT_TRUE(contains(r.output, "1 (unclassified")) << r.output;
  EXPECT_TRUE(contains(r.output, "2 (ground")) << r.output;
  EXPECT_FALSE(contains(r.output, "6 (building")) << r.output;
  EXPECT_EQ(run("reconstruct " + tiles + tail + (dir_ / "strict").string() + " --strict").exit_code, 1);
  // With the class the points have, the same tiles give buildings (and ground 2 stays ground).
  const Result fixed = run("reconstruct " + tiles + tail + (dir_ / "fixed").string() + " --building-classes 1");
  EXPECT_EQ(fixed.exit_code, 0) << fixed.output;
  EXPECT_EQ(report(dir_ / "fixed").at("summary").at("skipped"), 0);
}

TEST_F(Mistakes, a_run_whose_buildings_mostly_share_one_problem_says_so_and_fails_strict_with_5) {
  require_shared_data();
  // Tile 2 alone under the block's 160 footprints: 132 lie outside it.
  const std::string args = "reconstruct " + kTile2 + " -f " + kGpkg + " --id-field gml_id -j 2 --no-progress --no-html -o ";
  const Result r = run(args + (dir_ / "lax").string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const json whole = report(dir_ / "lax");
  EXPECT_GT(whole.at("summary").at("skipped").get<int>(), 80);
  EXPECT_TRUE(contains(r.output, "outside every tile given")) << r.output;
  EXPECT_EQ(run(args + (dir_ / "strict").string() + " --strict").exit_code, 5);
  // Both tiles: no main problem, 0 under --strict.
  EXPECT_EQ(run("reconstruct " + kTile1 + " " + kTile2 + " -f " + kGpkg +
                " --id-field gml_id -j 2 --no-progress --no-html --strict -o " + (dir_ / "both").string())
                .exit_code,
            0);
}

// --- 7. reruns into a folder: quiet about the journal, about the time, about what they removed ---

TEST_F(Mistakes, a_rerun_counts_what_it_took_from_the_journal_and_names_the_outputs_it_removed) {
  const std::string args = "reconstruct " + kSample + "/delft_sample_1.las " + kSample + "/delft_sample_2.las -f " +
                           kSample + "/delft_sample_footprints.gpkg --id-field gml_id --no-progress -o " +
                           (dir_ / "out").string();
  Result r = run(args + " --gpkg");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(report(dir_ / "out").at("summary").at("resumed"), 0);
  ASSERT_TRUE(fs::exists(dir_ / "out" / "buildings.gpkg"));
  // The same run again: every building from the journal, and the summary says so.
  r = run(args + " --gpkg");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(report(dir_ / "out").at("summary").at("resumed"), 15);
  EXPECT_TRUE(contains(r.output, "15 of them taken from the journal")) << r.output;
  // Without --gpkg: buildings.gpkg of the earlier run goes, with a warning naming it.
  r = run(args);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "out" / "buildings.gpkg"));
  EXPECT_TRUE(contains(r.output, "warning: output: removed buildings.gpkg")) << r.output;
  // Other parameters: the journal is set aside and the earlier models replaced, with warnings.
  r = run(args + " --lambda-data 0.5");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(report(dir_ / "out").at("summary").at("resumed"), 0);
  EXPECT_TRUE(contains(r.output, "is from another run")) << r.output;
  EXPECT_TRUE(contains(r.output, "model files an earlier run")) << r.output;
}

// --- 8. the smaller things a newcomer trips on ---

TEST(CommandLineMistakes, a_misspelt_option_gets_the_nearest_one_and_lod_2_is_refused) {
  Result r = run("reconstruct x.las --id-feild gml_id");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(contains(r.output, "did you mean '--id-field'")) << r.output;
  r = run("reconstruct x.las --frobnicate");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_FALSE(contains(r.output, "did you mean")) << r.output;
  for (const char* lod : {"2", "1", "2.1", "2.2,3"}) {
    r = run(std::string("reconstruct x.las --lod ") + lod);
    EXPECT_EQ(r.exit_code, 2) << lod;
  }
  EXPECT_EQ(run("reconstruct x.las --lod 2.2 --print-config").exit_code, 0);
}

TEST(CommandLineMistakes, help_is_a_command_too) {
  const Result help = run("help"), flag = run("--help");
  EXPECT_EQ(help.exit_code, 0) << help.output;
  EXPECT_EQ(help.output, flag.output);
  EXPECT_TRUE(contains(help.output, "exit codes:"));
}

TEST(CommandLineMistakes, info_takes_a_folder_and_lists_a_footprint_sources_fields) {
  if (!fs::exists(kTile1)) GTEST_SKIP() << "../shared/data is not beside the repository";
  Result r = run("info " + kDelft);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::size_t files = 0;
  for (std::size_t at = r.output.find("file: "); at != std::string::npos; at = r.output.find("file: ", at + 1)) ++files;
  EXPECT_EQ(files, 4u) << r.output;  // two tiles, each as LAS and LAZ
  EXPECT_TRUE(contains(r.output, "points: 640510\n")) << r.output;
  r = run("info " + kGpkg);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "  gml_id: String, 160 distinct *\n")) << r.output;
  EXPECT_TRUE(contains(r.output, "  rel_hoogte: Integer, 1 distinct\n")) << r.output;
}

TEST_F(Mistakes, the_progress_line_shows_tiles_being_read_and_waits_for_a_sample_before_an_eta) {
  const Result r = run("reconstruct " + kSample + "/delft_sample_1.las " + kSample + "/delft_sample_2.las -f " + kSample +
                       "/delft_sample_footprints.gpkg --id-field gml_id --progress -o " + (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::vector<std::string> lines;
  std::stringstream ss(r.output);
  for (std::string line; std::getline(ss, line, '\r');) lines.push_back(line);
  ASSERT_GT(lines.size(), 16u) << r.output;
  EXPECT_TRUE(contains(lines[1], "reading 2 tiles")) << lines[1];
  for (std::size_t k = 2; k < 2 + 4; ++k) EXPECT_FALSE(contains(lines[k], "s left")) << lines[k];
  EXPECT_TRUE(contains(lines[10], "s left")) << lines[10];
  // The last line points to the page a person reads.
  EXPECT_TRUE(contains(r.output, "report " + (dir_ / "out" / "report.html").string())) << r.output;
}

TEST_F(Mistakes, verbose_parameters_are_printed_without_float_noise) {
  const Result r = run("reconstruct " + kSample + "/delft_sample_1.las -f " + kSample +
                       "/delft_sample_footprints.gpkg --id-field gml_id --where \"gml_id = "
                       "'b31be49eb-00ba-11e6-b420-2bdcc4ab5d7f'\" -v --no-progress -o " + (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "planes.max_distance = 0.2\n")) << r.output;
  EXPECT_FALSE(contains(r.output, "0000000000")) << r.output;
}

TEST_F(Mistakes, a_terminated_run_says_what_is_kept_and_the_rerun_resumes) {
  require_shared_data();
  const fs::path out = dir_ / "out";
  // Terminated once three buildings are in the journal (its header and two records); a run that ends
  // before (it failed) ends the wait too, and the test fails on its exit status.
  const std::string command = "(" + std::string(CITY3D_EXE) + " reconstruct " + kTile1 + " " + kTile2 +
                              " -f " + kGpkg + " --id-field gml_id --no-progress -j 1 -o " + out.string() +
                              " & pid=$!; " + "while kill -0 $pid 2>/dev/null && [ \"$(cat " + out.string() +
                              "/resume.journal 2>/dev/null | wc -l)\" -lt 3 ]; do "
                              "sleep 0.02; done; kill -TERM $pid; wait $pid; echo \"exit=$?\")";
  const Result r = run_shell(command);
  EXPECT_TRUE(contains(r.output, "exit=143")) << r.output;
  EXPECT_TRUE(contains(r.output, "interrupted")) << r.output;
  const Result again = run("reconstruct " + kTile1 + " " + kTile2 + " -f " + kGpkg + " --id-field gml_id -j 2 --no-progress -o " +
                           out.string());
  ASSERT_EQ(again.exit_code, 0) << again.output;
  const json whole = report(out);
  EXPECT_GE(whole.at("summary").at("resumed").get<int>(), 2);
  EXPECT_EQ(whole.at("summary").at("buildings"), 160);
}

TEST_F(Mistakes, evaluating_a_model_against_a_whole_tile_warns_that_the_points_reach_beyond_it) {
  const fs::path model = kShared + "/city3d_dev/AHN3/00262.obj", own = kShared + "/city3d_dev/AHN3/00262.ply";
  if (!fs::exists(model)) GTEST_SKIP() << "../shared/data is not beside the repository";
  Result r = run("evaluate " + model.string() + " " + own.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(contains(r.output, "warning")) << r.output;
  EXPECT_TRUE(contains(r.output, "points beyond the model: 0 ")) << r.output;
  // A model of the sample block against the whole tile it came from.
  ASSERT_EQ(run("reconstruct " + kSample + "/delft_sample_1.las -f " + kSample + "/delft_sample_footprints.gpkg " +
                "--id-field gml_id --where \"gml_id = 'b31be49eb-00ba-11e6-b420-2bdcc4ab5d7f'\" --no-progress -o " +
                (dir_ / "out").string())
                .exit_code,
            0);
  r = run("evaluate " + (dir_ / "out" / "models" / "b31be49eb-00ba-11e6-b420-2bdcc4ab5d7f.obj").string() + " " + kSample +
          "/delft_sample_1.las");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "warning: evaluate:")) << r.output;
}

TEST_F(Mistakes, a_shard_that_builds_nothing_succeeds_and_its_merge_says_so) {
  // Tile 2 alone, the block in 4 shards of 100 m blocks: shard 3 builds nothing. Each shard must
  // finish with 0 (4 under --strict for partial buildings: a Slurm merge
  // waits for every shard to succeed); the merge of all of them judges the run.
  require_shared_data();
  const std::string args = "reconstruct " + kTile2 + " -f " + kGpkg +
                           " --id-field gml_id --block-size 100 --no-progress --no-html --strict -o ";
  std::string folders;
  for (int k = 1; k <= 4; ++k) {
    const fs::path folder = dir_ / ("shard" + std::to_string(k));
    folders += " " + folder.string();
    const Result r = run(args + folder.string() + " --shard " + std::to_string(k) + "/4");
    EXPECT_TRUE(r.exit_code == 0 || r.exit_code == 4) << "shard " << k << ": " << r.output;
  }
  // Shard 3 has no building of its own (its blocks' footprints went to the others' tiles' runs).
  const json third = report(dir_ / "shard3");
  EXPECT_EQ(third.at("summary").at("ok").get<int>() + third.at("summary").at("fallback").get<int>() +
                third.at("summary").at("partial").get<int>(),
            0)
      << "shard 3 was meant to build nothing";
  const Result merged = run("merge" + folders + " --strict -o " + (dir_ / "merged").string());
  EXPECT_EQ(merged.exit_code, 5) << merged.output;  // 132 of 160 outside the tile
  EXPECT_EQ(report(dir_ / "merged").at("summary").at("buildings"), 160);
}

// --- 8. mistakes a user tried (ninety of them, 2026-11-27): what was wrong and marked ok, or lost ---

namespace {
const std::string kSampleTiles = kSample + "/delft_sample_1.las " + kSample + "/delft_sample_2.las";
const std::string kSampleFootprints = " -f " + kSample + "/delft_sample_footprints.gpkg --id-field gml_id";

// The sample's footprints as read, to write variants of them.
city3d::FootprintSet sample_footprints() {
  city3d::FootprintReadOptions read;
  read.id_field = "gml_id";
  return city3d::read_footprints(kSample + "/delft_sample_footprints.gpkg", read);
}
}  // namespace

TEST_F(Mistakes, a_jobs_count_beyond_the_threads_to_be_had_runs_on_as_many_as_there_is_work_for) {
  // -j 50000 aborted ("terminate called without an active exception"): a thread that could not be
  // started was never joined.
  const Result many = run("reconstruct " + kSampleTiles + kSampleFootprints + " -j 100000 --no-progress -o " +
                          (dir_ / "many").string());
  ASSERT_EQ(many.exit_code, 0) << many.output;
  ASSERT_EQ(run("reconstruct " + kSampleTiles + kSampleFootprints + " -j 1 --no-progress -o " +
                (dir_ / "one").string())
                .exit_code,
            0);
  EXPECT_EQ(read_file(dir_ / "many" / "buildings.city.json"),
            read_file(dir_ / "one" / "buildings.city.json"));
}

TEST_F(Mistakes, v_repeated_in_one_word_is_v_given_twice) {
  const std::string tail = kSampleFootprints + " --lod 1.2 --no-progress -o ";
  const Result twice = run("reconstruct " + kSampleTiles + tail + (dir_ / "a").string() + " -v -v");
  const Result word = run("reconstruct " + kSampleTiles + tail + (dir_ / "b").string() + " -vv");
  ASSERT_EQ(twice.exit_code, 0) << twice.output;
  ASSERT_EQ(word.exit_code, 0) << word.output;
  const auto lines = [](const std::string& text) { return std::count(text.begin(), text.end(), '\n'); };
  EXPECT_EQ(lines(word.output), lines(twice.output)) << word.output;
  EXPECT_GT(lines(word.output),
            lines(run("reconstruct " + kSampleTiles + tail + (dir_ / "c").string() + " -v").output));
}

TEST_F(Mistakes, a_folder_given_as_the_configuration_file_is_refused) {
  const Result r = run("reconstruct " + kSampleTiles + kSampleFootprints + " --config " + dir_.string() +
                       " --no-progress -o " + (dir_ / "out").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(Mistakes, empty_and_blank_ids_are_skipped_as_null_ones_are) {
  const fs::path footprints = dir_ / "ids.gpkg";
  const Result made =
      run_shell("ogr2ogr -f GPKG " + footprints.string() + " " + kSample +
                "/delft_sample_footprints.gpkg -dialect sqlite -sql \"SELECT *, CASE gml_id WHEN "
                "'b31e1d795-00ba-11e6-b420-2bdcc4ab5d7f' THEN '' WHEN "
                "'b11282794-00ba-11e6-b420-2bdcc4ab5d7f' THEN '  ' ELSE gml_id END AS pid FROM "
                "buildingpart\" -nln buildingpart");
  ASSERT_EQ(made.exit_code, 0) << made.output;
  const Result r = run("reconstruct " + kSampleTiles + " -f " + footprints.string() +
                       " --id-field pid --lod 1.2 --no-progress -o " + (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json whole = report(dir_ / "out");
  EXPECT_EQ(whole.at("summary").at("buildings"), 15);
  EXPECT_EQ(whole.at("summary").at("skipped"), 2);
  for (const json& row : whole.at("buildings")) {
    const std::string id = row.at("id").get<std::string>();
    EXPECT_NE(id.find_first_not_of(' '), std::string::npos) << "a building of a blank id";
    if (row.at("status") == "skipped")
      EXPECT_EQ(row.at("reason").get<std::string>().rfind("no id", 0), 0u) << row;
  }
  const json city = json::parse(read_file(dir_ / "out" / "buildings.city.json"));
  for (const auto& [id, object] : city.at("CityObjects").items())
    EXPECT_NE(id.find_first_not_of(' '), std::string::npos) << "a CityObject of a blank id";
}

TEST_F(Mistakes, a_ground_field_of_dates_is_refused_and_one_of_other_numbers_is_not_taken_for_the_ground) {
  const std::string tail = " --lod 1.2 --no-progress -o ";
  // 'created' holds dates ("2014-07-09" was read as 2014 m); bag_pnd is a building number (5.03e14 m).
  const Result dates = run("reconstruct " + kSampleTiles + kSampleFootprints + " --ground-field created" +
                           tail + (dir_ / "dates").string());
  EXPECT_EQ(dates.exit_code, 1) << dates.output;
  EXPECT_FALSE(fs::exists(dir_ / "dates"));
  ASSERT_EQ(
      run("reconstruct " + kSampleTiles + kSampleFootprints + tail + (dir_ / "measured").string()).exit_code,
      0);
  const Result numbers = run("reconstruct " + kSampleTiles + kSampleFootprints + " --ground-field bag_pnd" +
                             tail + (dir_ / "numbers").string());
  ASSERT_EQ(numbers.exit_code, 0) << numbers.output;
  const auto measured = rows_by_id(dir_ / "measured"), with_field = rows_by_id(dir_ / "numbers");
  std::size_t noted = 0;
  for (const auto& [id, row] : with_field) {
    if (row.at("status") == "skipped") continue;
    EXPECT_EQ(row.at("ground_z"), measured.at(id).at("ground_z")) << id;
    EXPECT_EQ(row.at("ground_method"), measured.at(id).at("ground_method")) << id;
    EXPECT_EQ(row.at("volume_lod12"), measured.at(id).at("volume_lod12")) << id;
    noted += contains(row.at("note").get<std::string>(), "bag_pnd");
  }
  EXPECT_GE(noted, 10u);
  // A text field of heights, one of them not a number: that one measured, the others taken.
  const fs::path footprints = dir_ / "floor.gpkg";
  ASSERT_EQ(run_shell("ogr2ogr -f GPKG " + footprints.string() + " " + kSample +
                      "/delft_sample_footprints.gpkg -dialect sqlite -sql \"SELECT *, CASE gml_id WHEN "
                      "'b31e1d795-00ba-11e6-b420-2bdcc4ab5d7f' THEN 'unknown' ELSE '0.25' END AS floor FROM "
                      "buildingpart\" -nln buildingpart")
                .exit_code,
            0);
  const Result mixed = run("reconstruct " + kSampleTiles + " -f " + footprints.string() +
                           " --id-field gml_id --ground-field floor" + tail + (dir_ / "mixed").string());
  ASSERT_EQ(mixed.exit_code, 0) << mixed.output;
  for (const auto& [id, row] : rows_by_id(dir_ / "mixed")) {
    if (row.at("status") == "skipped") continue;
    if (id == "b31e1d795-00ba-11e6-b420-2bdcc4ab5d7f") {
      EXPECT_EQ(row.at("ground_method"), measured.at(id).at("ground_method"));
    } else {
      EXPECT_EQ(row.at("ground_method"), "footprint attribute") << id;
      EXPECT_DOUBLE_EQ(row.at("ground_z").get<double>(), 0.25) << id;
    }
  }
  // Heights of another datum for one footprint (43 m below, as ellipsoidal heights against NAP): not
  // taken, the ground measured around it is, and its note says why.
  const fs::path datum = dir_ / "datum.gpkg";
  ASSERT_EQ(run_shell("ogr2ogr -f GPKG " + datum.string() + " " + kSample +
                      "/delft_sample_footprints.gpkg -dialect sqlite -sql \"SELECT *, CASE gml_id WHEN "
                      "'b31e1d795-00ba-11e6-b420-2bdcc4ab5d7f' THEN -43.2 ELSE -0.5 END AS floor FROM "
                      "buildingpart\" -nln buildingpart")
                .exit_code,
            0);
  const Result below = run("reconstruct " + kSampleTiles + " -f " + datum.string() +
                           " --id-field gml_id --ground-field floor" + tail + (dir_ / "below").string());
  ASSERT_EQ(below.exit_code, 0) << below.output;
  for (const auto& [id, row] : rows_by_id(dir_ / "below")) {
    if (row.at("status") == "skipped") continue;
    if (id == "b31e1d795-00ba-11e6-b420-2bdcc4ab5d7f") {
      EXPECT_EQ(row.at("ground_z"), measured.at(id).at("ground_z"));
      EXPECT_TRUE(
          contains(row.at("note").get<std::string>(), "(-43.2) more than 10 m below the ground measured"))
          << row;
    } else {
      EXPECT_EQ(row.at("ground_method"), "footprint attribute") << id;  // half a metre below: taken
    }
  }
}

TEST_F(Mistakes, a_folder_of_tiles_is_not_the_output_folder_and_a_mesh_among_clouds_is_named) {
  fs::create_directories(dir_ / "tiles");
  for (const char* f : {"delft_sample_1.las", "delft_sample_2.las"})
    fs::copy_file(kSample + "/" + f, dir_ / "tiles" / f);
  // The second run into the folder read the first one's models.ply as a tile, took the journal for
  // another run's and removed every model.
  const Result same = run("reconstruct " + (dir_ / "tiles").string() + kSampleFootprints +
                          " --format ply --merged --no-progress -o " + (dir_ / "tiles").string());
  EXPECT_EQ(same.exit_code, 2) << same.output;
  std::size_t entries = 0;
  for (const auto& e : fs::directory_iterator(dir_ / "tiles"))
    entries += e.is_regular_file() || e.is_directory();
  EXPECT_EQ(entries, 2u) << "nothing written among the tiles";
  // A model among the tiles is read as points, and said to be a mesh.
  ASSERT_EQ(run("reconstruct " + kSampleTiles + kSampleFootprints +
                " --lod 1.2 --format ply --merged --no-progress -o " + (dir_ / "out").string())
                .exit_code,
            0);
  fs::copy_file(dir_ / "out" / "models.ply", dir_ / "tiles" / "models.ply");
  const Result with_mesh = run("reconstruct " + (dir_ / "tiles").string() + kSampleFootprints +
                               " --lod 1.2 --no-progress -o " + (dir_ / "again").string());
  EXPECT_TRUE(contains(with_mesh.output, (dir_ / "tiles" / "models.ply").string() + " is a mesh of"))
      << with_mesh.output;
  EXPECT_TRUE(contains(run("info " + (dir_ / "tiles" / "models.ply").string()).output, "faces: "))
      << "info names it too";
}

TEST_F(Mistakes, files_of_a_run_in_a_folder_without_its_journal_are_not_replaced) {
  fs::create_directories(dir_ / "mine");
  { std::ofstream(dir_ / "mine" / "report.csv") << "my own table\n"; }
  const Result r = run("reconstruct " + kSampleTiles + kSampleFootprints + " --no-progress -o " +
                       (dir_ / "mine").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(read_file(dir_ / "mine" / "report.csv"), "my own table\n");
  EXPECT_FALSE(fs::exists(dir_ / "mine" / "models"));
  // A run's own folder (its journal beside its files) is resumed as before.
  ASSERT_EQ(run("reconstruct " + kSampleTiles + kSampleFootprints + " --lod 1.2 --no-progress -o " +
                (dir_ / "run").string())
                .exit_code,
            0);
  const Result again = run("reconstruct " + kSampleTiles + kSampleFootprints +
                           " --lod 1.2 --no-progress -o " + (dir_ / "run").string());
  EXPECT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(report(dir_ / "run").at("summary").at("resumed"), 15);
}

TEST_F(Mistakes, ground_z_with_footprints_and_a_cityjson_to_evaluate_are_refused) {
  const Result z = run("reconstruct " + kSampleTiles + kSampleFootprints +
                       " --ground-z 100 --no-progress -o " + (dir_ / "out").string());
  EXPECT_EQ(z.exit_code, 2) << z.output;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
  ASSERT_EQ(run("reconstruct " + kSampleTiles + kSampleFootprints + " --lod 1.2 --no-progress -o " +
                (dir_ / "run").string())
                .exit_code,
            0);
  const Result json_model = run("evaluate " + (dir_ / "run" / "buildings.city.json").string() + " " +
                                kSample + "/delft_sample_1.las");
  EXPECT_EQ(json_model.exit_code, 1) << json_model.output;
  EXPECT_TRUE(contains(json_model.output, "not an OBJ file")) << json_model.output;
}

// -f given twice took the second layer only: the first one's buildings were left out without a word.
// Two footprint sources, or two selections of one, are refused; an option repeated with the same value,
// or any other option repeated (the last value wins, for scripts that append overrides), is not.
TEST_F(Mistakes, two_footprint_layers_or_two_selections_are_refused_and_other_repeats_take_the_last) {
  const fs::path other = dir_ / "other.gpkg";
  fs::copy_file(kSample + "/delft_sample_footprints.gpkg", other);
  for (const std::string& twice :
       {" -f " + other.string(), std::string(" --where \"fid < 3\" --where \"fid > 5\""),
        std::string(" --bbox 0,0,1,1 --bbox 0,0,2,2")}) {
    const Result r = run("reconstruct " + kSampleTiles + kSampleFootprints + twice + " --no-progress -o " +
                         (dir_ / "out").string());
    EXPECT_EQ(r.exit_code, 2) << twice << r.output;
    EXPECT_FALSE(fs::exists(dir_ / "out")) << twice;
  }
  const Result same =
      run("reconstruct " + kSampleTiles + kSampleFootprints + kSampleFootprints +
          " --lod 1.2 --lambda-data 0.5 --lambda-data 0.34 --no-progress -q -o " + (dir_ / "same").string());
  ASSERT_EQ(same.exit_code, 0) << same.output;
  const std::string parameters = read_file(dir_ / "same" / "run.json");
  EXPECT_TRUE(contains(parameters, "\"lambda-data\": 0.34")) << parameters;
  EXPECT_FALSE(rows_by_id(dir_ / "same").empty());
}

TEST_F(Mistakes, a_tile_given_without_footprints_and_points_at_ground_level_are_noted) {
  // A whole tile as one building's cloud: 17,327 of its 40,957 points are ground.
  const Result tile = run("reconstruct " + kSample + "/delft_sample_1.las --lod 1.2 --no-progress -o " +
                          (dir_ / "tile").string());
  ASSERT_EQ(tile.exit_code, 0) << tile.output;
  const auto rows = rows_by_id(dir_ / "tile");
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_TRUE(contains(rows.begin()->second.at("note").get<std::string>(), "classified ground"))
      << rows.begin()->second;
  // A PLY's labels are not LAS classes (DALES labels vegetation 2): its points are not taken for ground.
  {
    std::ofstream ply(dir_ / "labelled.ply");
    ply << "ply\nformat ascii 1.0\nelement vertex 400\nproperty float x\nproperty float y\nproperty float z\n"
           "property uchar label\nend_header\n";
    for (int i = 0; i < 20; ++i)
      for (int j = 0; j < 20; ++j) ply << 0.5 * i << ' ' << 0.5 * j << ' ' << 5 + 0.1 * i << " 2\n";
  }
  const Result labelled = run("reconstruct " + (dir_ / "labelled.ply").string() +
                              " --lod 1.2 --no-progress -o " + (dir_ / "labelled").string());
  ASSERT_EQ(labelled.exit_code, 0) << labelled.output;
  EXPECT_FALSE(contains(labelled.output, "classified ground")) << labelled.output;
  // The same building in degrees (4.36 E, 52.01 N): planes cannot be found, and the note says why.
  {
    std::ofstream ply(dir_ / "degrees.ply");
    ply << "ply\nformat ascii 1.0\nelement vertex 400\nproperty double x\nproperty double y\nproperty double "
           "z\n"
           "end_header\n";
    ply.precision(12);
    for (int i = 0; i < 20; ++i)
      for (int j = 0; j < 20; ++j)
        ply << 4.36 + 7e-6 * i << ' ' << 52.01 + 4.5e-6 * j << ' ' << 5 + 0.1 * i << "\n";
  }
  const Result degrees = run("reconstruct " + (dir_ / "degrees.ply").string() +
                             " --lod 1.2 --no-progress -o " + (dir_ / "degrees").string());
  ASSERT_TRUE(fs::exists(dir_ / "degrees" / "report.json")) << degrees.output;
  EXPECT_TRUE(contains(rows_by_id(dir_ / "degrees").begin()->second.at("note").get<std::string>(),
                       "degrees of longitude"));
  // Every height set to 0: each building's points stand at its ground (the blocks are 1 m slabs).
  const city3d::PointCloud cloud = city3d::read_point_cloud(kSample + "/delft_sample_1.las",
                                                            city3d::kFieldXyz | city3d::kFieldClassification);
  std::vector<city3d::test::LasPoint> flat;
  for (std::size_t i = 0; i < cloud.size(); ++i)
    flat.push_back({cloud.points[i].x, cloud.points[i].y, 0.0, cloud.classification[i]});
  city3d::test::write_las((dir_ / "flat.las").string(), flat);
  const Result r = run("reconstruct " + (dir_ / "flat.las").string() + kSampleFootprints +
                       " --lod 1.2 --no-progress -o " + (dir_ / "flat").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::size_t built = 0, noted = 0;
  for (const auto& [id, row] : rows_by_id(dir_ / "flat")) {
    if (row.at("status") == "skipped") continue;
    ++built;
    noted += contains(row.at("note").get<std::string>(), "less than 1 m above its ground");
  }
  EXPECT_GT(built, 5u);
  EXPECT_EQ(noted, built);
  // The real heights give no such note.
  ASSERT_EQ(run("reconstruct " + kSampleTiles + kSampleFootprints + " --lod 1.2 --no-progress -o " +
                (dir_ / "real").string())
                .exit_code,
            0);
  for (const auto& [id, row] : rows_by_id(dir_ / "real"))
    EXPECT_FALSE(contains(row.at("note").get<std::string>(), "above its ground")) << id;
}

TEST_F(Mistakes, point_clouds_in_a_subfolder_of_a_folder_given_are_named_as_not_read) {
  fs::create_directories(dir_ / "tiles" / "more");
  fs::copy_file(kSample + "/delft_sample_1.las", dir_ / "tiles" / "delft_sample_1.las");
  fs::copy_file(kSample + "/delft_sample_2.las", dir_ / "tiles" / "more" / "delft_sample_2.las");
  const Result r = run("reconstruct " + (dir_ / "tiles").string() + kSampleFootprints +
                       " --lod 1.2 --no-progress -o " + (dir_ / "out").string());
  EXPECT_TRUE(contains(r.output, "subfolders of " + (dir_ / "tiles").string() + " are not read (more)"))
      << r.output;
  const Result all =
      run("reconstruct " + (dir_ / "tiles").string() + " " + (dir_ / "tiles" / "more").string() +
          kSampleFootprints + " --lod 1.2 --no-progress -o " + (dir_ / "all").string());
  EXPECT_FALSE(contains(all.output, "not read")) << "given too: " << all.output;
  EXPECT_EQ(report(dir_ / "all").at("summary").at("partial"), 0) << "both tiles read";
  // An output folder of city3d's inside the tiles' folder holds PLY models, not points: it is not named,
  // or a user would be told to read the models as tiles.
  const Result inside =
      run("reconstruct " + (dir_ / "tiles").string() + " " + (dir_ / "tiles" / "more").string() +
          kSampleFootprints + " --lod 1.2 --format ply --merged --no-progress -o " +
          (dir_ / "tiles" / "out").string());
  ASSERT_EQ(inside.exit_code, 0) << inside.output;
  ASSERT_TRUE(fs::exists(dir_ / "tiles" / "out" / "models.ply"));
  const Result again =
      run("reconstruct " + (dir_ / "tiles").string() + " " + (dir_ / "tiles" / "more").string() +
          kSampleFootprints + " --lod 1.2 --format ply --merged --no-progress -o " +
          (dir_ / "tiles" / "out").string());
  EXPECT_FALSE(contains(again.output, "not read")) << again.output;
}

TEST_F(Mistakes, a_header_whose_bounds_leave_out_points_is_named_and_coverage_is_measured_from_the_points) {
  // The sample's first tile rewritten twice: with its true bounds, and with a header max x 25 m short.
  const city3d::PointCloud cloud = city3d::read_point_cloud(kSample + "/delft_sample_1.las",
                                                            city3d::kFieldXyz | city3d::kFieldClassification);
  std::vector<city3d::test::LasPoint> points;
  double max_x = -1e300;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    points.push_back({cloud.points[i].x, cloud.points[i].y, cloud.points[i].z, cloud.classification[i]});
    max_x = std::max(max_x, cloud.points[i].x);
  }
  city3d::test::write_las((dir_ / "true.las").string(), points);
  city3d::test::LasWriteOptions shrunk;
  shrunk.claimed_max_x = max_x - 25.0;
  city3d::test::write_las((dir_ / "short.las").string(), points, shrunk);
  const std::string tail =
      " " + kSample + "/delft_sample_2.las" + kSampleFootprints + " --lod 1.2 --no-progress -o ";
  ASSERT_EQ(run("reconstruct " + (dir_ / "true.las").string() + tail + (dir_ / "true").string()).exit_code,
            0);
  const Result r = run("reconstruct " + (dir_ / "short.las").string() + tail + (dir_ / "short").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "beyond its header's bounds")) << r.output;
  const auto truth = rows_by_id(dir_ / "true");
  for (const auto& [id, row] : rows_by_id(dir_ / "short")) {
    EXPECT_EQ(row.at("status"), truth.at(id).at("status")) << id;
    EXPECT_EQ(row.at("coverage"), truth.at(id).at("coverage")) << id;
  }
}

// --- 9. a second round of mistakes (2026-11-27) ---

TEST_F(Mistakes, inputs_where_the_run_writes_are_refused_and_kept) {
  // Footprints named buildings.gpkg in the output folder: --gpkg wrote over them.
  fs::create_directories(dir_ / "work");
  fs::copy_file(kSample + "/delft_sample_footprints.gpkg", dir_ / "work" / "buildings.gpkg");
  const std::string before = read_file(dir_ / "work" / "buildings.gpkg");
  const Result r = run("reconstruct " + kSampleTiles + " -f " + (dir_ / "work" / "buildings.gpkg").string() +
                       " --id-field gml_id --gpkg --no-progress -o " + (dir_ / "work").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(read_file(dir_ / "work" / "buildings.gpkg"), before);
  // evaluate --residuals naming one of its inputs wrote its CSV over it.
  const std::string smoke = kShared + "/city3d_smoke/AHN3/00295";
  if (!fs::exists(smoke + ".ply")) GTEST_SKIP() << "../shared/data is not beside the repository";
  fs::copy_file(smoke + ".ply", dir_ / "points.ply");
  const std::string points = read_file(dir_ / "points.ply");
  const Result e = run("evaluate " + smoke + ".obj " + (dir_ / "points.ply").string() + " --residuals " +
                       (dir_ / "points.ply").string());
  EXPECT_EQ(e.exit_code, 2) << e.output;
  EXPECT_EQ(read_file(dir_ / "points.ply"), points);
}

TEST_F(Mistakes, a_footprint_no_tolerance_simplifies_enough_is_skipped_and_the_others_are_built) {
  // 300 squares in one multipolygon: 1,200 vertices, none of them removable; the run ended at it.
  std::ostringstream squares;
  squares << "{\"type\":\"FeatureCollection\",\"features\":[{\"type\":\"Feature\",\"properties\":{\"gml_id\":"
             "\"many\"},\"geometry\":{\"type\":\"MultiPolygon\",\"coordinates\":[";
  for (int k = 0; k < 300; ++k) {
    const double x = 84960.0 + 2.0 * (k % 20), y = 447400.0 + 2.0 * (k / 20);
    squares << (k ? "," : "") << "[[[" << x << "," << y << "],[" << x + 1 << "," << y << "],[" << x + 1 << ","
            << y + 1 << "],[" << x << "," << y + 1 << "],[" << x << "," << y << "]]]";
  }
  squares << "]}}]}";
  { std::ofstream(dir_ / "many.geojson") << squares.str(); }
  const fs::path footprints = dir_ / "footprints.gpkg";
  fs::copy_file(kSample + "/delft_sample_footprints.gpkg", footprints);
  const Result appended =
      run_shell("ogr2ogr -append -update -a_srs EPSG:28992 -nln buildingpart -nlt MULTIPOLYGON " +
                footprints.string() + " " + (dir_ / "many.geojson").string());
  ASSERT_EQ(appended.exit_code, 0) << appended.output;
  const Result r = run("reconstruct " + kSampleTiles + " -f " + footprints.string() +
                       " --id-field gml_id --lod 1.2 --no-progress -o " + (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto rows = rows_by_id(dir_ / "out");
  ASSERT_EQ(rows.size(), 16u);
  EXPECT_EQ(rows.at("many").at("status"), "skipped");
  EXPECT_EQ(rows.at("many").at("stage"), "footprint");
  std::size_t built = 0;
  for (const auto& [id, row] : rows) built += row.at("status") == "ok";
  EXPECT_EQ(built, 15u);
}

TEST_F(Mistakes, a_source_of_two_polygon_layers_needs_layer_and_a_model_is_no_footprint_file) {
  const fs::path two = dir_ / "two.gpkg";
  fs::copy_file(kSample + "/delft_sample_footprints.gpkg", two);
  ASSERT_EQ(run_shell("ogr2ogr -update " + two.string() + " " + kSample +
                      "/delft_sample_footprints.gpkg -nln parcels " +
                      "-dialect sqlite -sql \"SELECT gml_id, ST_Buffer(GEOMETRY, 3) AS geom FROM "
                      "buildingpart\" -nlt POLYGON")
                .exit_code,
            0);
  const std::string tail = " --id-field gml_id --lod 1.2 --no-progress -o ";
  const Result r = run("reconstruct " + kSampleTiles + " -f " + two.string() + tail + (dir_ / "a").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_TRUE(contains(r.output, "parcels")) << r.output;
  EXPECT_EQ(run("reconstruct " + kSampleTiles + " -f " + two.string() + " --layer buildingpart" + tail +
                (dir_ / "b").string())
                .exit_code,
            0);
  // An empty polygon layer beside the footprints' (a template layer) is nothing to choose between.
  const fs::path empty = dir_ / "empty.gpkg";
  fs::copy_file(kSample + "/delft_sample_footprints.gpkg", empty);
  ASSERT_EQ(run_shell("ogr2ogr -update " + empty.string() + " " + kSample +
                      "/delft_sample_footprints.gpkg -nln " + "template -where \"1=0\" -nlt POLYGON")
                .exit_code,
            0);
  const Result one =
      run("reconstruct " + kSampleTiles + " -f " + empty.string() + tail + (dir_ / "e").string());
  EXPECT_EQ(one.exit_code, 0) << one.output;
  EXPECT_EQ(report(dir_ / "e").at("summary").at("buildings"), 15);
  // City3D's own model of a building, given as its footprints: its walls were footprints.
  const std::string smoke = kShared + "/city3d_smoke/AHN3/00295";
  if (!fs::exists(smoke + ".ply")) GTEST_SKIP() << "../shared/data is not beside the repository";
  const Result model =
      run("reconstruct " + smoke + ".ply -f " + smoke + ".obj" + tail + (dir_ / "c").string());
  EXPECT_EQ(model.exit_code, 1) << model.output;
  EXPECT_FALSE(fs::exists(dir_ / "c"));
}

TEST_F(Mistakes,
       a_height_datum_alone_a_weight_beyond_the_solvers_and_a_shapefile_without_its_dbf_are_refused) {
  const std::string tail = " --id-field gml_id --lod 1.2 --no-progress -o " + (dir_ / "out").string();
  EXPECT_EQ(run("reconstruct " + kSampleTiles + kSampleFootprints + " --crs EPSG:5709 --no-progress -o " +
                (dir_ / "out").string())
                .exit_code,
            2);
  EXPECT_EQ(run("reconstruct " + kSampleTiles + kSampleFootprints + " --lambda-data 1e308 --no-progress -o " +
                (dir_ / "out").string())
                .exit_code,
            2);
  // A negative block size was taken as 0; strtod read "0x10" as 16.
  for (const char* option : {" --block-size -5", " --group-area -1", " -j 0x10"})
    EXPECT_EQ(run("reconstruct " + kSampleTiles + kSampleFootprints + option + " --no-progress -o " +
                  (dir_ / "out").string())
                  .exit_code,
              2)
        << option;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
  ASSERT_EQ(run_shell("ogr2ogr -f \"ESRI Shapefile\" " + (dir_ / "fp.shp").string() + " " + kSample +
                      "/delft_sample_footprints.gpkg")
                .exit_code,
            0);
  ASSERT_EQ(run("reconstruct " + kSampleTiles + " -f " + (dir_ / "fp.shp").string() + tail).exit_code, 0);
  fs::remove(dir_ / "fp.dbf");
  fs::remove_all(dir_ / "out");
  const Result r = run("reconstruct " + kSampleTiles + " -f " + (dir_ / "fp.shp").string() + tail);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(contains(r.output, (dir_ / "fp.dbf").string())) << r.output;
}

TEST_F(Mistakes, evaluate_places_a_local_coordinates_model_at_its_origin) {
  const std::string tail = kSampleFootprints + " --lod 1.2 --no-progress -o ";
  ASSERT_EQ(run("reconstruct " + kSampleTiles + tail + (dir_ / "world").string()).exit_code, 0);
  ASSERT_EQ(run("reconstruct " + kSampleTiles + tail + (dir_ / "local").string() + " --local-coordinates")
                .exit_code,
            0);
  const std::string name = "b11282794-00ba-11e6-b420-2bdcc4ab5d7f.obj",
                    points = " " + kSample + "/delft_sample_1.las";
  const auto without_path = [](std::string text) { return text.substr(text.find("\npoints:")); };
  const Result world = run("evaluate " + (dir_ / "world" / "models" / name).string() + points);
  const Result local = run("evaluate " + (dir_ / "local" / "models" / name).string() + points);
  ASSERT_EQ(local.exit_code, 0) << local.output;
  EXPECT_EQ(without_path(local.output), without_path(world.output));
}

TEST_F(Mistakes, evaluate_calls_two_cubes_on_one_edge_not_manifold_and_an_open_shell_without_volume) {
  // Each cube of its own eight vertices: closed and manifold by the indices, not once coincident
  // vertices are one (val3dity's 304), as evaluate's val3dity line said beside "manifold: yes".
  std::ofstream obj(dir_ / "cubes.obj");
  for (const double o : {0.0, 1.0})
    for (int k = 0; k < 8; ++k)
      obj << "v " << o + (k & 1) << ' ' << o + ((k >> 1) & 1) << ' ' << ((k >> 2) & 1) << "\n";
  for (const int o : {0, 8})
    for (const auto& f : std::vector<std::array<int, 4>>{
             {1, 3, 4, 2}, {5, 6, 8, 7}, {1, 2, 6, 5}, {3, 7, 8, 4}, {1, 5, 7, 3}, {2, 4, 8, 6}})
      obj << "f " << f[0] + o << ' ' << f[1] + o << ' ' << f[2] + o << ' ' << f[3] + o << "\n";
  obj.close();
  std::ofstream open_shell(dir_ / "open.obj");
  for (int k = 0; k < 8; ++k)
    open_shell << "v " << (k & 1) << ' ' << ((k >> 1) & 1) << ' ' << ((k >> 2) & 1) << "\n";
  for (const auto& f :
       std::vector<std::array<int, 4>>{{1, 3, 4, 2}, {1, 2, 6, 5}, {3, 7, 8, 4}, {1, 5, 7, 3}, {2, 4, 8, 6}})
    open_shell << "f " << f[0] << ' ' << f[1] << ' ' << f[2] << ' ' << f[3] << "\n";
  open_shell.close();
  std::ofstream ply(dir_ / "points.ply");
  ply << "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float "
         "z\nend_header\n"
         "0.5 0.5 1\n0.2 0.7 1\n1.5 1.5 1\n1.2 1.7 1\n";
  ply.close();
  const Result cubes =
      run("evaluate " + (dir_ / "cubes.obj").string() + " " + (dir_ / "points.ply").string());
  EXPECT_TRUE(contains(cubes.output, "val3dity: 304")) << cubes.output;
  EXPECT_TRUE(contains(cubes.output, "manifold: no")) << cubes.output;
  const Result shell = run("evaluate " + (dir_ / "open.obj").string() + " " + (dir_ / "points.ply").string());
  EXPECT_TRUE(contains(shell.output, "closed: no")) << shell.output;
  EXPECT_TRUE(contains(shell.output, "volume: none (not closed)")) << shell.output;
}

TEST_F(Mistakes, withheld_points_are_left_out_and_heights_beyond_the_header_are_named) {
  // Tile 1 with every building point doubled 3 m higher and flagged withheld (as a filter that marks
  // points instead of deleting them writes it); tile 2 with its header's highest z lowered by 5 m (a
  // z scale or offset changed without the bounds).
  const city3d::PointCloud one = city3d::read_point_cloud(kSample + "/delft_sample_1.las",
                                                          city3d::kFieldXyz | city3d::kFieldClassification);
  std::vector<city3d::test::LasPoint> points;
  std::size_t doubled = 0;
  for (std::size_t i = 0; i < one.size(); ++i) {
    points.push_back({one.points[i].x, one.points[i].y, one.points[i].z, one.classification[i]});
    if (one.classification[i] != 6) continue;
    points.push_back({one.points[i].x, one.points[i].y, one.points[i].z + 3.0, 6 | 0x80});
    ++doubled;
  }
  city3d::test::write_las((dir_ / "one.las").string(), points);
  fs::copy_file(kSample + "/delft_sample_2.las", dir_ / "two.las");
  {
    std::fstream two(dir_ / "two.las", std::ios::in | std::ios::out | std::ios::binary);
    double max_z = 0;
    two.seekg(211);  // LAS 1.2 header: max z
    two.read(reinterpret_cast<char*>(&max_z), sizeof max_z);
    max_z -= 5.0;
    two.seekp(211);
    two.write(reinterpret_cast<const char*>(&max_z), sizeof max_z);
  }
  const std::string tail = kSampleFootprints + " --no-progress -o ";
  const Result r = run("reconstruct " + (dir_ / "one.las").string() + " " + (dir_ / "two.las").string() +
                       tail + (dir_ / "marked").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(
      contains(r.output, "one.las: " + std::to_string(doubled) + " points flagged withheld are left out"))
      << r.output;
  EXPECT_TRUE(contains(r.output, "two.las: its points' heights span z")) << r.output;
  EXPECT_TRUE(contains(r.output, "check its z scale and offset")) << r.output;
  EXPECT_FALSE(contains(r.output, "one.las: its points' heights")) << r.output;
  // The models are those of the sample itself: no withheld point reached a building.
  ASSERT_EQ(run("reconstruct " + kSampleTiles + tail + (dir_ / "sample").string()).exit_code, 0);
  const auto marked = rows_by_id(dir_ / "marked"), sample = rows_by_id(dir_ / "sample");
  ASSERT_EQ(marked.size(), sample.size());
  for (const auto& [id, row] : sample) {
    EXPECT_EQ(marked.at(id).at("points"), row.at("points")) << id;
    EXPECT_EQ(marked.at(id).at("h_roof_max"), row.at("h_roof_max")) << id;
    EXPECT_EQ(marked.at(id).at("faces"), row.at("faces")) << id;
  }
  // `city3d info` counts them apart from the classes.
  const Result info = run("info " + (dir_ / "one.las").string());
  EXPECT_TRUE(contains(info.output, "withheld: " + std::to_string(doubled))) << info.output;
  EXPECT_TRUE(contains(info.output, "points: " + std::to_string(one.size() + doubled))) << info.output;
}

TEST_F(Mistakes, a_footprint_whose_cells_hold_mostly_other_classes_is_partial) {
  // Tile 1 of the sample with its building points made class 1 (a tile not classified, beside one
  // that is): b11282799 lies on both, and was built from tile 2's 156 of its 551 points into a ridge
  // 10 m above its highest point, and called ok.
  const city3d::PointCloud one = city3d::read_point_cloud(kSample + "/delft_sample_1.las",
                                                          city3d::kFieldXyz | city3d::kFieldClassification);
  std::vector<city3d::test::LasPoint> points;
  for (std::size_t i = 0; i < one.size(); ++i)
    points.push_back({one.points[i].x, one.points[i].y, one.points[i].z,
                      static_cast<std::uint8_t>(one.classification[i] == 6 ? 1 : one.classification[i])});
  city3d::test::write_las((dir_ / "one.las").string(), points);
  const std::string tiles = (dir_ / "one.las").string() + " " + kSample + "/delft_sample_2.las";
  const Result r =
      run("reconstruct " + tiles + kSampleFootprints + " --no-progress -o " + (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto rows = rows_by_id(dir_ / "out");
  const json& straddling = rows.at("b11282799-00ba-11e6-b420-2bdcc4ab5d7f");
  EXPECT_EQ(straddling.at("status"), "partial") << straddling;
  EXPECT_LT(straddling.at("building_coverage").get<double>(), 0.5) << straddling;
  EXPECT_EQ(straddling.at("coverage").get<double>(), 1.0) << straddling;  // the tiles do cover it
  EXPECT_TRUE(contains(straddling.at("reason").get<std::string>(), "other classes only")) << straddling;
  // --strict fails such a run, as it fails one with a tile missing (here with 5: most of the buildings
  // on tile 1 are skipped, the main problem).
  EXPECT_NE(run("reconstruct " + tiles + kSampleFootprints + " --strict --no-progress -o " +
                (dir_ / "strict").string())
                .exit_code,
            0);
  // 0 turns the check off.
  ASSERT_EQ(run("reconstruct " + tiles + kSampleFootprints + " --min-building-coverage 0 --no-progress -o " +
                (dir_ / "off").string())
                .exit_code,
            0);
  EXPECT_EQ(rows_by_id(dir_ / "off").at("b11282799-00ba-11e6-b420-2bdcc4ab5d7f").at("status"), "ok");
  // The sample as it is: every building's own points in nearly all of its cells, no building partial.
  ASSERT_EQ(run("reconstruct " + kSampleTiles + kSampleFootprints + " --no-progress -o " +
                (dir_ / "sample").string())
                .exit_code,
            0);
  for (const auto& [id, row] : rows_by_id(dir_ / "sample")) {
    EXPECT_NE(row.at("status"), "partial") << id;
    EXPECT_GE(row.at("building_coverage").get<double>(), 0.6) << id;
  }
}

TEST_F(Mistakes,
       tiles_without_the_ground_class_are_named_and_a_ground_class_that_is_a_building_class_refused) {
  // The sample tiles with their ground points made class 1: every floor would be a roof's lowest point.
  std::string tiles;
  for (const char* tile : {"delft_sample_1.las", "delft_sample_2.las"}) {
    const city3d::PointCloud cloud =
        city3d::read_point_cloud(kSample + "/" + tile, city3d::kFieldClassification);
    std::vector<city3d::test::LasPoint> points;
    for (std::size_t i = 0; i < cloud.size(); ++i)
      points.push_back(
          {cloud.points[i].x, cloud.points[i].y, cloud.points[i].z,
           static_cast<std::uint8_t>(cloud.classification[i] == 2 ? 1 : cloud.classification[i])});
    city3d::test::write_las((dir_ / tile).string(), points);
    tiles += " " + (dir_ / tile).string();
  }
  const Result r = run("reconstruct" + tiles + kSampleFootprints + " --lod 1.2 --no-progress -o " +
                       (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(
      contains(r.output, "the tiles hold no point of the ground class 2 (--ground-class) but of classes 1 "))
      << r.output;
  std::size_t noted = 0;
  for (const auto& [id, row] : rows_by_id(dir_ / "out")) {
    EXPECT_EQ(row.at("ground_method"), "lowest building point") << id;
    noted += contains(row.at("note").get<std::string>(), "no ground point near it");
  }
  EXPECT_EQ(noted, 15u);
  // --ignore-classes takes the ground from every point around the footprints: near the real ground.
  ASSERT_EQ(run("reconstruct" + tiles + kSampleFootprints + " --lod 1.2 --ignore-classes --no-progress -o " +
                (dir_ / "ignored").string())
                .exit_code,
            0);
  const auto ignored = rows_by_id(dir_ / "ignored");
  ASSERT_EQ(run("reconstruct " + kSampleTiles + kSampleFootprints + " --lod 1.2 --no-progress -o " +
                (dir_ / "sample").string())
                .exit_code,
            0);
  for (const auto& [id, row] : rows_by_id(dir_ / "sample")) {
    EXPECT_EQ(ignored.at(id).at("ground_method"), "ground percentile") << id;
    EXPECT_NEAR(ignored.at(id).at("ground_z").get<double>(), row.at("ground_z").get<double>(), 0.5) << id;
  }
  // The ground class among the building classes: a contradiction, refused before anything is read.
  const Result both = run("reconstruct " + kSampleTiles + kSampleFootprints +
                          " --ground-class 6 --no-progress -o " + (dir_ / "both").string());
  EXPECT_EQ(both.exit_code, 2) << both.output;
  EXPECT_TRUE(contains(both.output, "also a building class")) << both.output;
  EXPECT_FALSE(fs::exists(dir_ / "both"));
}

TEST_F(Mistakes, a_single_building_cloud_leaves_its_noise_out_and_names_a_stray_far_below_its_points) {
  // A 20 x 20 m roof at 8-10 m, and one point 30 m below it: class 7 (noise) in the LAS, unclassified
  // in the PLY (which has no LAS classes).
  std::vector<city3d::test::LasPoint> points;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j)
      points.push_back({1000 + 0.5 * i, 2000 + 0.5 * j, 8 + 0.1 * std::min(i, 39 - i), 6});
  points.push_back({1010, 2010, -22, 7});
  city3d::test::write_las((dir_ / "noise.las").string(), points);
  const Result las = run("reconstruct " + (dir_ / "noise.las").string() + " --lod 1.2 --no-progress -o " +
                         (dir_ / "las").string());
  ASSERT_EQ(las.exit_code, 0) << las.output;
  const json row = rows_by_id(dir_ / "las").at("noise");
  EXPECT_EQ(row.at("points"), 1600) << row;
  EXPECT_GT(row.at("ground_z").get<double>(), 7.9) << row;  // the roof's lowest point, not -22
  EXPECT_TRUE(contains(row.at("note").get<std::string>(), "1 points classified noise (7, 18) left out"))
      << row;
  {
    std::ofstream ply(dir_ / "stray.ply");
    ply << "ply\nformat ascii 1.0\nelement vertex " << points.size()
        << "\nproperty double x\nproperty double y\n"
        << "property double z\nend_header\n";
    for (const auto& p : points) ply << p.x << ' ' << p.y << ' ' << p.z << '\n';
  }
  const Result ply = run("reconstruct " + (dir_ / "stray.ply").string() + " --lod 1.2 --no-progress -o " +
                         (dir_ / "ply").string());
  ASSERT_EQ(ply.exit_code, 0) << ply.output;
  const std::string note = rows_by_id(dir_ / "ply").at("stray").at("note").get<std::string>();
  EXPECT_TRUE(contains(note, "1 point more than 10 m below all but the lowest 0.1% (down to z -22.000"))
      << note;
  EXPECT_TRUE(contains(ply.output, "strays?")) << ply.output;  // and a warning
  // The same roof in millimetres: 20 km across.
  {
    std::ofstream mm(dir_ / "mm.ply");
    mm << "ply\nformat ascii 1.0\nelement vertex " << points.size() - 1
       << "\nproperty double x\nproperty double y\n"
       << "property double z\nend_header\n";
    for (std::size_t k = 0; k + 1 < points.size(); ++k)
      mm << 1000 * points[k].x << ' ' << 1000 * points[k].y << ' ' << 1000 * points[k].z << '\n';
  }
  const Result mm = run("reconstruct " + (dir_ / "mm.ply").string() + " --lod 1.2 --no-progress -o " +
                        (dir_ / "mm").string());
  ASSERT_TRUE(fs::exists(dir_ / "mm" / "report.json")) << mm.output;
  EXPECT_TRUE(contains(
      rows_by_id(dir_ / "mm").at("mm").at("note").get<std::string>(),
      "it spans 19500 m in plan, more than any building (--max-footprint-size 5000 m): coordinates in "
      "millimetres"))
      << mm.output;
}

TEST_F(Mistakes, records_beyond_a_las_headers_count_are_named_not_dropped_in_silence) {
  // The sample's tile 1 with its header's count halved: the other half of its records follows unread.
  fs::copy_file(kSample + "/delft_sample_1.las", dir_ / "half.las");
  std::uint32_t count = 0;
  {
    std::fstream f(dir_ / "half.las", std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(107);  // LAS 1.2 header: number of point records
    f.read(reinterpret_cast<char*>(&count), sizeof count);
    const std::uint32_t half = count / 2;
    f.seekp(107);
    f.write(reinterpret_cast<const char*>(&half), sizeof half);
  }
  const std::string uncounted = std::to_string(count - count / 2);
  const Result r = run("reconstruct " + (dir_ / "half.las").string() + " " + kSample + "/delft_sample_2.las" +
                       kSampleFootprints + " --lod 1.2 --no-progress -o " + (dir_ / "out").string());
  EXPECT_TRUE(contains(r.output, "half.las: its header counts " + std::to_string(count / 2) +
                                     " points, but " + uncounted + " more records follow them"))
      << r.output;
  const Result info = run("info " + (dir_ / "half.las").string());
  EXPECT_TRUE(contains(info.output, "uncounted: " + uncounted + " more records")) << info.output;
  // The sample's own tiles: nothing of the kind.
  EXPECT_FALSE(contains(run("info " + kSample + "/delft_sample_1.las").output, "uncounted")) << info.output;
}

TEST_F(Mistakes, footprints_that_declare_degrees_but_hold_metres_are_not_taken_for_degrees) {
  // The sample's footprints as a GeoJSON file without a "crs" member (as many tools write RFC 7946
  // GeoJSON): WGS 84 by the standard, RD New metres in fact.
  const city3d::FootprintSet sample = sample_footprints();
  {
    std::ofstream g(dir_ / "rfc7946.geojson");
    g.precision(12);
    g << R"({"type":"FeatureCollection","features":[)";
    for (std::size_t k = 0; k < sample.footprints.size(); ++k) {
      g << (k ? "," : "") << R"({"type":"Feature","properties":{"gml_id":")" << sample.footprints[k].id
        << R"("},"geometry":{"type":"Polygon","coordinates":[[)";
      const auto& ring = sample.footprints[k].polygons.at(0).outer;
      for (std::size_t i = 0; i <= ring.size(); ++i)
        g << (i ? "," : "") << "[" << ring[i % ring.size()].x << "," << ring[i % ring.size()].y << "]";
      g << "]]}}";
    }
    g << "]}";
  }
  const std::string footprints =
      " -f " + (dir_ / "rfc7946.geojson").string() + " --id-field gml_id --no-progress";
  const Result r = run("reconstruct " + kSampleTiles + footprints + " -o " + (dir_ / "none").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(
      contains(r.output, "declares EPSG:4326 (degrees; a GeoJSON file without a \"crs\" member is WGS 84"))
      << r.output;
  EXPECT_TRUE(contains(r.output, "which are no degrees: that CRS is ignored")) << r.output;
  // No CRS in the outputs rather than WGS 84 over metres.
  EXPECT_FALSE(contains(read_file(dir_ / "none" / "buildings.city.json"), "4326"));
  // With --crs the footprints are taken to be in it, not reprojected from degrees (which PROJ refuses).
  const Result given =
      run("reconstruct " + kSampleTiles + footprints + " --crs EPSG:7415 -o " + (dir_ / "rd").string());
  ASSERT_EQ(given.exit_code, 0) << given.output;
  EXPECT_FALSE(contains(given.output, "reproject")) << given.output;
  EXPECT_EQ(report(dir_ / "rd").at("summary").at("ok"), 15) << given.output;
  EXPECT_TRUE(contains(read_file(dir_ / "rd" / "buildings.city.json"), "EPSG/0/7415"));
}

TEST_F(Mistakes, a_bbox_that_leaves_no_reprojected_footprint_says_which_crs_it_was_read_in) {
  // The sample's footprints in UTM 31N, a box in UTM given: the footprints are reprojected into the
  // points' RD New, and the box is read there.
  const fs::path utm = dir_ / "utm.gpkg";
  ASSERT_EQ(run_shell("ogr2ogr -f GPKG -t_srs EPSG:32631 " + utm.string() + " " + kSample +
                      "/delft_sample_footprints.gpkg")
                .exit_code,
            0);
  const Result r = run("reconstruct " + kSampleTiles + " -f " + utm.string() +
                       " --crs EPSG:7415 --bbox 593800,5763200,593900,5763300 --no-progress -o " +
                       (dir_ / "out").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(contains(
      r.output, "(in EPSG:28992, the point clouds' CRS: the footprints are reprojected from EPSG:32631)"))
      << r.output;
}

// A layer with two geometry columns (a CSV with an envelope beside each footprint): the first was read
// in silence, and the buildings got their envelopes. The run says which column it reads.
TEST_F(Mistakes, a_layer_of_two_geometry_columns_is_named_with_the_one_read) {
  const city3d::FootprintSet sample = sample_footprints();
  {
    std::ofstream csv(dir_ / "two.csv");
    csv.precision(12);
    csv << "gml_id,_WKTenv,_WKTfp\n";
    for (const city3d::Footprint& f : sample.footprints) {
      const auto& ring = f.polygons.at(0).outer;
      city3d::Box2 box;
      for (const city3d::Point2& p : ring) box.add(p);
      csv << f.id << ",\"POLYGON((" << box.min.x - 3 << " " << box.min.y - 3 << ", " << box.max.x + 3 << " "
          << box.min.y - 3 << ", " << box.max.x + 3 << " " << box.max.y + 3 << ", " << box.min.x - 3 << " "
          << box.max.y + 3 << ", " << box.min.x - 3 << " " << box.min.y - 3 << "))\",\"POLYGON((";
      for (std::size_t i = 0; i <= ring.size(); ++i)
        csv << (i ? ", " : "") << ring[i % ring.size()].x << " " << ring[i % ring.size()].y;
      csv << "))\"\n";
    }
  }
  const Result r = run("reconstruct " + kSampleTiles + " -f " + (dir_ / "two.csv").string() +
                       " --id-field gml_id --lod 1.2 --no-progress -o " + (dir_ / "out").string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(
      r.output, "has 2 geometry columns (geom__WKTenv, geom__WKTfp): the first, geom__WKTenv, is read"))
      << r.output;
  // One geometry column: no such warning.
  const Result one = run("reconstruct " + kSampleTiles + kSampleFootprints + " --lod 1.2 --no-progress -o " +
                         (dir_ / "one").string());
  EXPECT_FALSE(contains(one.output, "geometry columns")) << one.output;
}

// Data in a CRS of feet (EPSG:2263, US survey feet) was taken for metres in silence: every threshold of
// the method off by 3.28, areas and volumes in square and cubic feet. The run says so.
TEST_F(Mistakes, a_crs_not_in_metres_is_named_with_its_unit) {
  const Result made = run_shell("ogr2ogr -a_srs EPSG:2263 " + (dir_ / "feet.gpkg").string() + " " + kSample +
                                "/delft_sample_footprints.gpkg");
  ASSERT_EQ(made.exit_code, 0) << made.output;
  const Result r = run("reconstruct " + kSampleTiles + " -f " + (dir_ / "feet.gpkg").string() +
                       " --id-field gml_id --lod 1.2 --no-progress -o " + (dir_ / "out").string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "has its coordinates in US survey foot, 0.3048006")) << r.output;
  // The sample's own CRS is in metres: no such warning.
  const Result metres = run("reconstruct " + kSampleTiles + kSampleFootprints +
                            " --lod 1.2 --no-progress -o " + (dir_ / "metres").string());
  EXPECT_FALSE(contains(metres.output, "has its coordinates in")) << metres.output;
}

// A Shapefile's .dbf changed alone (a ground field edited in place) left the .shp's size and time as they
// were, and a rerun took every building from the journal of the earlier values. The .dbf, .shx, .prj and
// .cpg are stamped too.
TEST_F(Mistakes, a_shapefile_whose_dbf_alone_changed_is_not_resumed) {
  const Result made =
      run_shell("ogr2ogr " + (dir_ / "fp.shp").string() + " " + kSample +
                "/delft_sample_footprints.gpkg -sql \"SELECT *, 0.5 AS gz FROM buildingpart\"");
  ASSERT_EQ(made.exit_code, 0) << made.output;
  const std::string command = "reconstruct " + kSampleTiles + " -f " + (dir_ / "fp.shp").string() +
                              " --id-field gml_id --ground-field gz --lod 1.2 --no-progress -o " +
                              (dir_ / "out").string();
  ASSERT_EQ(run(command).exit_code, 0);
  const auto before = rows_by_id(dir_ / "out");
  // The ground values edited in the .dbf's own bytes (as a tool that writes the .dbf alone does).
  std::string dbf;
  {
    std::ifstream in(dir_ / "fp.dbf", std::ios::binary);
    dbf.assign(std::istreambuf_iterator<char>(in), {});
  }
  std::size_t edited = 0;
  for (std::size_t at = dbf.find("0.5"); at != std::string::npos; at = dbf.find("0.5", at + 3), ++edited)
    dbf[at] = '3';
  ASSERT_GT(edited, 0u);
  std::ofstream(dir_ / "fp.dbf", std::ios::binary) << dbf;
  const Result again = run(command);
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_FALSE(contains(again.output, "taken from the journal")) << again.output;
  std::size_t changed = 0;
  for (const auto& [id, row] : rows_by_id(dir_ / "out"))
    changed +=
        row.at("ground_z") != before.at(id).at("ground_z") || row.at("note") != before.at(id).at("note");
  EXPECT_GT(changed, 0u) << "the grounds of 3.5 m were not read";
}

// A ground field of another datum, or a relative level (BGT's rel_hoogte, 0 for every footprint), over
// heights some metres from it: the floors stood metres in the air or under the terrain, and nothing said
// so. A value taken more than 2 m from the ground measured around the footprint is noted.
TEST_F(Mistakes, a_ground_field_far_from_the_ground_measured_is_noted) {
  for (const char* value : {"3.0", "0.5"}) {
    const fs::path fp = dir_ / (std::string("gz") + value + ".gpkg");
    const Result made =
        run_shell("ogr2ogr " + fp.string() + " " + kSample +
                  "/delft_sample_footprints.gpkg -sql \"SELECT *, " + value + " AS gz FROM buildingpart\"");
    ASSERT_EQ(made.exit_code, 0) << made.output;
    const fs::path out = dir_ / (std::string("out") + value);
    const Result r = run("reconstruct " + kSampleTiles + " -f " + fp.string() +
                         " --id-field gml_id --ground-field gz --lod 1.2 --no-progress -o " + out.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::size_t taken = 0, noted = 0;
    for (const auto& [id, row] : rows_by_id(out)) {
      if (row.at("ground_method") != "footprint attribute") continue;
      ++taken;
      noted += contains(row.at("note").get<std::string>(), "m above the ground measured around it");
    }
    EXPECT_GT(taken, 5u) << value;
    if (std::string(value) == "3.0") {
      EXPECT_EQ(noted, taken) << r.output;
      EXPECT_TRUE(contains(r.output, "lie far from the ground measured around them")) << r.output;
    } else {
      EXPECT_EQ(noted, 0u);
      EXPECT_FALSE(contains(r.output, "lie far from the ground")) << r.output;
    }
  }
}

// Coordinates recorded more coarsely than a roof can be read from were taken as they were: a LAS scale of
// 1 (whole metres: RMSE 0.20 -> 0.51 m on the sample), a PLY of 32-bit floats at UTM coordinates (steps of
// 0.5 m at 5.8e6). A single-building cloud's note says so, and a tile gets a warning.
TEST_F(Mistakes, coordinates_recorded_in_coarse_steps_are_named) {
  const city3d::PointCloud smoke =
      city3d::read_point_cloud(kShared + "/city3d_smoke/AHN3/00295.ply", city3d::kFieldXyz);
  std::vector<city3d::test::LasPoint> points;
  for (const city3d::Point3& p : smoke.points) points.push_back({p.x, p.y, p.z, 6});
  city3d::test::LasWriteOptions metres;
  metres.scale = 1.0;
  city3d::test::write_las((dir_ / "metres.las").string(), points, metres);
  {
    std::ofstream ply(dir_ / "utm_float.ply");
    ply.precision(12);
    ply << "ply\nformat ascii 1.0\nelement vertex " << smoke.points.size()
        << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    for (const city3d::Point3& p : smoke.points)
      ply << p.x + 500000 << " " << p.y + 5800000 << " " << p.z << "\n";
  }
  const Result r =
      run("reconstruct " + (dir_ / "metres.las").string() + " " + (dir_ / "utm_float.ply").string() + " " +
          kShared + "/city3d_smoke/AHN3/00295.ply --no-progress -o " + (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto rows = rows_by_id(dir_ / "out");
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_TRUE(
      contains(rows.at("metres").at("note").get<std::string>(), "recorded in steps of 1 m (the LAS scale)"))
      << rows.at("metres").at("note");
  EXPECT_TRUE(
      contains(rows.at("utm_float").at("note").get<std::string>(), "in steps of 0.5 m (32-bit floats"))
      << rows.at("utm_float").at("note");
  EXPECT_FALSE(contains(rows.at("00295").at("note").get<std::string>(), "steps of"))
      << rows.at("00295").at("note");
  // A tile of whole metres.
  const city3d::PointCloud tile = city3d::read_point_cloud(kSample + "/delft_sample_1.las",
                                                           city3d::kFieldXyz | city3d::kFieldClassification);
  std::vector<city3d::test::LasPoint> tile_points;
  for (std::size_t i = 0; i < tile.points.size(); ++i)
    tile_points.push_back({tile.points[i].x, tile.points[i].y, tile.points[i].z, tile.classification[i]});
  city3d::test::write_las((dir_ / "tile.las").string(), tile_points, metres);
  const Result t = run("reconstruct " + (dir_ / "tile.las").string() + kSampleFootprints +
                       " --lod 1.2 --no-progress -o " + (dir_ / "tile").string());
  EXPECT_TRUE(contains(t.output, "tile.las: its x and y are recorded in steps of 1.000000 m (the LAS scale)"))
      << t.output;
}
