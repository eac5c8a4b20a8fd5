// Tests of the pipeline: on real data, tiles cropped by footprints across a tile seam, the fallback
// ladder's bottom rung, single-building clouds, report rows for broken footprints, the smoke set;
// on synthetic buildings, every stage end to end against the known shape.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>

#include "city3d/batch.hpp"
#include "city3d/crop.hpp"
#include "city3d/error.hpp"
#include "city3d/evaluation.hpp"
#include "city3d/footprint_io.hpp"
#include "city3d/mesh_check.hpp"
#include "city3d/pipeline.hpp"
#include "city3d/point_cloud_io.hpp"
#include "city3d/rings.hpp"
#include "city3d/stage_profile.hpp"
#include "pipeline/left_out.hpp"
#include "pipeline/outline.hpp"

namespace fs = std::filesystem;
using namespace city3d;

namespace {

const std::string kDelft = std::string(CITY3D_SHARED_DATA) + "/ahn3_delft";

void require_delft() {
  if (!fs::exists(kDelft + "/ahn3_cropped_1.las")) GTEST_SKIP() << "../shared/data is not beside the repository";
}

}  // namespace

// Burns the calling thread's CPU for `seconds` (its own clock, so the machine's load does not matter).
void burn_cpu(double seconds) {
  const auto now = [] {
    timespec t{};
    ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
  };
  const double end = now() + seconds;
  volatile double sink = 0.0;
  while (now() < end) sink = sink + 1.0;
}

// Issue 27: a stage's CPU is its own, a nested stage's taken out of it, a rebuild's apart; the time
// outside every stage is no stage's; threads add up.
TEST(StageProfile, nested_stages_count_exclusive_and_rebuilds_apart) {
  reset_stage_profile();
  std::thread worker([] {
    burn_cpu(0.03);  // before any stage: counted nowhere
    const StageTimer building(Stage::other);
    burn_cpu(0.02);
    {
      const StageTimer planes(Stage::planes);
      burn_cpu(0.04);
      {
        const StageTimer measure(Stage::measure);
        burn_cpu(0.03);
      }
    }
    const RebuildScope rebuilding;
    const StageTimer planes(Stage::planes);
    burn_cpu(0.05);
  });
  worker.join();
  const StageProfile p = stage_profile();
  const auto at = [](const std::array<double, kStageCount>& a, Stage s) { return a[static_cast<std::size_t>(s)]; };
  EXPECT_NEAR(at(p.first, Stage::other), 0.02, 0.01);
  EXPECT_NEAR(at(p.first, Stage::planes), 0.04, 0.01);
  EXPECT_NEAR(at(p.first, Stage::measure), 0.03, 0.01);
  EXPECT_NEAR(at(p.rebuild, Stage::planes), 0.05, 0.01);
  EXPECT_EQ(at(p.rebuild, Stage::measure), 0.0);
  EXPECT_NEAR(p.total(), 0.14, 0.02);  // not the 0.03 before the first stage
  EXPECT_STREQ(stage_name(Stage::hypothesis), "hypothesis");
}

TEST(Batch, footprints_across_the_tile_seam_get_points_from_both_tiles) {
  require_delft();
  FootprintSet set = read_footprints(kDelft + "/footprints/bgt_pand_laz_area.gpkg", {});
  ASSERT_EQ(set.footprints.size(), 160u);
  // The tiles meet at x = 85000 (../shared/data/README.md): a footprint straddles the seam when its
  // x range contains 85000. The README counts 7 of them.
  std::vector<bool> straddles;
  for (const Footprint& f : set.footprints) {
    double lo = 1e300, hi = -1e300;
    for (const Polygon2& p : f.polygons)
      for (const Point2& v : p.outer) lo = std::min(lo, v.x), hi = std::max(hi, v.x);
    straddles.push_back(lo < 85000.0 && hi > 85000.0);
  }
  ASSERT_EQ(std::count(straddles.begin(), straddles.end(), true), 7);

  Cropper cropper(set.footprints, {});
  for (const char* tile : {"/ahn3_cropped_1.las", "/ahn3_cropped_2.las"})
    cropper.add(read_point_cloud(kDelft + tile, kFieldClassification));
  const std::vector<BuildingInput> inputs = cropper.finish();
  ASSERT_EQ(inputs.size(), 160u);
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    if (!straddles[i]) continue;
    std::size_t west = 0, east = 0;
    for (const Point3& p : inputs[i].points) (p.x + inputs[i].origin.x < 85000.0 ? west : east)++;
    EXPECT_GT(west, 0u) << inputs[i].id;
    EXPECT_GT(east, 0u) << inputs[i].id;
  }
}

TEST(Batch, single_building_cloud_gets_a_convex_outline_and_its_lowest_point_as_floor) {
  const std::vector<Point3> world = {{100, 200, 5}, {110, 200, 6}, {110, 210, 7}, {100, 210, 8}, {105, 205, 9}};
  const BuildingInput in = building_from_cloud("b", world);
  EXPECT_EQ(in.origin.x, 105.0);
  EXPECT_EQ(in.origin.y, 205.0);
  ASSERT_EQ(in.footprint.polygons.size(), 1u);
  EXPECT_EQ(in.footprint.polygons[0].outer.size(), 4u);  // the interior point is not on the hull
  EXPECT_DOUBLE_EQ(in.ground_z, 5.0);
  EXPECT_EQ(in.ground_method, "lowest building point");
  const BuildingInput given = building_from_cloud("b", world, 1.5);
  EXPECT_DOUBLE_EQ(given.ground_z, 1.5);
}

// A cloud of two buildings 6 m apart (a hall and a shed, flat roofs at 8 m and 4 m over a ground at
// 0): both parts of the inferred outline are modelled, each as its own problem, in one valid model of
// two shells that leaves no point unexplained.
TEST(Batch, single_building_cloud_of_two_parts_gets_both_parts_modelled) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.03);
  std::vector<Point3> world;
  const auto roof = [&](double x0, double y0, double w, double d, double z) {
    const int n = static_cast<int>(w * d * 15.0);
    for (int i = 0; i < n; ++i) world.push_back({1000 + x0 + w * u(rng), 2000 + y0 + d * u(rng), z + noise(rng)});
  };
  roof(0, 0, 20, 12, 8.0);   // the hall
  roof(26, 2, 6, 5, 4.0);    // the shed, 6 m east of it
  world.push_back({1010, 2006, 0.0});  // a ground point: the floor at 0
  const BuildingResult r = reconstruct_building(building_from_cloud("two", world), {});
  ASSERT_TRUE(r.model.has_value()) << r.report.reason;
  EXPECT_EQ(r.report.level, ModelLevel::lod22) << r.report.reason;
  EXPECT_NE(r.report.note.find("outline: 2 parts"), std::string::npos) << r.report.note;
  EXPECT_TRUE(check_mesh(r.model->mesh).valid());
  // Two shells: vertices of each lie over one of the two roofs.
  std::size_t over_hall = 0, over_shed = 0;
  for (const Point3& v : r.model->mesh.vertices) (v.x + r.model->origin.x < 1023.0 ? over_hall : over_shed)++;
  EXPECT_GE(over_hall, 8u);
  EXPECT_GE(over_shed, 8u);
  EXPECT_LE(r.report.unexplained_points, 1.0);  // the lone ground point at most
  EXPECT_LT(r.report.rmse, 0.15);
}

TEST(Batch, building_without_points_is_skipped_with_a_reason_and_no_model) {
  BuildingInput in;
  in.id = "empty";
  in.footprint.polygons.push_back({{{0, 0}, {10, 0}, {10, 10}, {0, 10}}, {}});
  const BuildingResult r = reconstruct_building(in, {});
  EXPECT_EQ(r.report.status, BuildingStatus::skipped);
  EXPECT_EQ(r.report.reason, "no building points inside the footprint");
  EXPECT_FALSE(r.model.has_value());
}

TEST(Batch, every_delft_building_gets_a_valid_closed_model_with_few_fallbacks) {
  require_delft();
  const fs::path out = fs::temp_directory_path() / "city3d_batch_delft";
  fs::remove_all(out);
  BatchOptions options;
  options.point_clouds = {kDelft + "/ahn3_cropped_1.las", kDelft + "/ahn3_cropped_2.las"};
  options.footprints = kDelft + "/footprints/bgt_pand_laz_area.gpkg";
  options.footprint.id_field = "gml_id";
  options.output_dir = out.string();
  options.threads = 2;
  const BatchSummary s = run_batch(options);
  EXPECT_EQ(s.buildings, 160u);
  EXPECT_EQ(s.ok + s.fallback, 160u);
  // Four footprints hold fewer than ~55 building points, too few for a 40-point roof plane: they
  // fall back to LoD1 (measured on 2026-11-23). More fallbacks mean a regression.
  EXPECT_GE(s.ok, 150u);
  std::size_t models = 0;  // OBJ files (city3d.mtl, their materials, is beside them)
  for (const auto& e : fs::directory_iterator(out / "models")) models += e.path().extension() == ".obj";
  EXPECT_EQ(models, 160u);
  EXPECT_TRUE(fs::exists(out / "models" / "city3d.mtl"));

  // Issue 23: no model carries surface its points do not support. Before it, these eight carried
  // blades of 16 to 167 m2 (b31bbff5e's rose to 32.5 m over points that top out at 12.7 m). Each has
  // less than 1 m2 left (b112715ef 0.45 m2: a gap of a few centimetres in its points beside a wall,
  // measured at 1.4 m2 before unsupported samples were refined).
  std::ifstream csv(out / "report.csv");
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  std::vector<std::string> header;
  for (std::stringstream s(line); std::getline(s, line, ',');) header.push_back(line);
  const auto column = std::find(header.begin(), header.end(), "unsupported_area") - header.begin();
  ASSERT_LT(static_cast<std::size_t>(column), header.size());
  const std::vector<std::string> named = {"b31bbff5e", "b31bc9c58", "b31bc269e", "b11282794",
                                          "b112715ef", "b31be22bd", "b31bc4dbd", "b31bdd432"};
  std::size_t rows = 0, seen = 0;
  double total = 0.0;
  while (std::getline(csv, line)) {
    // Split on commas outside quotes (the note may hold commas).
    std::vector<std::string> fields(1);
    bool quoted = false;
    for (char c : line) {
      if (c == '"') quoted = !quoted;
      else if (c == ',' && !quoted) fields.emplace_back();
      else fields.back() += c;
    }
    ASSERT_GT(fields.size(), static_cast<std::size_t>(column)) << line;
    const double unsupported = std::stod(fields[static_cast<std::size_t>(column)]);
    ++rows;
    total += unsupported;
    EXPECT_LE(unsupported, 10.0) << fields[0];
    if (std::any_of(named.begin(), named.end(), [&](const std::string& n) { return fields[0].rfind(n, 0) == 0; })) {
      ++seen;
      EXPECT_LE(unsupported, 1.0) << fields[0];
    }
  }
  EXPECT_EQ(rows, 160u);
  EXPECT_EQ(seen, named.size());
  EXPECT_LT(total, 10.0);  // 6.95 m2 measured (516 m2 before issue 23; roofer's models 10.0 m2)
  fs::remove_all(out);
}

TEST(Batch, delft_block_from_laz_tiles_gives_the_same_output_as_from_las) {
  require_delft();
  std::string outputs[2];
  const char* extensions[] = {".las", ".laz"};
  for (int k = 0; k < 2; ++k) {
    const fs::path out = fs::temp_directory_path() / (std::string("city3d_batch_delft") + extensions[k]);
    fs::remove_all(out);
    BatchOptions options;
    options.point_clouds = {kDelft + "/ahn3_cropped_1" + extensions[k], kDelft + "/ahn3_cropped_2" + extensions[k]};
    options.footprints = kDelft + "/footprints/bgt_pand_laz_area.gpkg";
    options.footprint.id_field = "gml_id";
    // LoD1 keeps this test fast; the models depend on the points only through the crop, which is
    // what differs between the two readers (the LoD2 stages are deterministic given the points).
    options.reconstruction.max_level = ModelLevel::lod12;
    options.per_building_files = false;
    options.output_dir = out.string();
    options.threads = 2;
    EXPECT_EQ(run_batch(options).ok, 160u);
    std::ifstream in(out / "buildings.city.json", std::ios::binary);
    outputs[k].assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    fs::remove_all(out);
  }
  EXPECT_FALSE(outputs[0].empty());
  EXPECT_EQ(outputs[0], outputs[1]);
}

TEST(Smoke, ten_small_ahn3_buildings_give_valid_lod2_models_as_accurate_as_city3d) {
  const std::string folder = std::string(CITY3D_SHARED_DATA) + "/city3d_smoke/AHN3/";
  if (!fs::exists(folder)) GTEST_SKIP() << "../shared/data is not beside the repository";
  // RMSE of City3D's own model (the .obj beside each .ply) to the same points, measured with our
  // evaluation code: `city3d evaluate NNNNN.obj NNNNN.ply` (2026-11-23).
  const std::pair<const char*, double> city3d_rmse[] = {
      {"00295", 0.0391}, {"04160", 0.3173}, {"06773", 0.0735}, {"07827", 0.1834}, {"08439", 0.0562},
      {"08541", 0.0748}, {"09696", 0.0185}, {"13071", 0.3247}, {"13639", 0.3681}, {"19960", 0.3476}};
  std::vector<double> ours, theirs;
  for (const auto& [name, reference] : city3d_rmse) {
    SCOPED_TRACE(name);
    const PointCloud cloud = read_point_cloud(folder + name + ".ply", kFieldXyz);
    const BuildingResult r = reconstruct_building(building_from_cloud(name, cloud.points), {});
    EXPECT_EQ(r.report.status, BuildingStatus::ok) << r.report.reason;
    EXPECT_EQ(r.report.level, ModelLevel::lod22);
    ASSERT_TRUE(r.model.has_value());
    EXPECT_TRUE(check_mesh(r.model->mesh).valid());
    // Per building: never far worse than City3D (chimneys and trees make some RMSEs large for both).
    EXPECT_LT(r.report.rmse, reference + 0.15);
    EXPECT_LE(r.report.faces, 40u);
    ours.push_back(r.report.rmse);
    theirs.push_back(reference);
  }
  std::sort(ours.begin(), ours.end());
  std::sort(theirs.begin(), theirs.end());
  const double our_median = (ours[4] + ours[5]) / 2, their_median = (theirs[4] + theirs[5]) / 2;
  EXPECT_LE(our_median, their_median * 1.1) << "median RMSE " << our_median << " vs City3D " << their_median;
}

TEST(Smoke, tiny_buildings_get_lod2_from_smaller_planes_and_the_convex_hull) {
  const std::string folder = std::string(CITY3D_SHARED_DATA) + "/city3d_dev/AHN3/";
  if (!fs::exists(folder)) GTEST_SKIP() << "../shared/data is not beside the repository";
  // 02576: 22 points, too small for the heightmap to hold an outline (the convex hull serves);
  // 04992: 133 points, no plane of City3D's 40 points (planes of 20 points are tried). City3D's
  // RMSEs, measured as in the test above: 0.0113 and 0.1306.
  const std::tuple<const char*, const char*, double> cases[] = {
      {"02576", "outline: convex hull of the points", 0.06}, {"04992", "planes of at least 20 points", 0.15}};
  // City3D's 40 points, grown at 20 degrees as before issue 10 (at 30 degrees 04992 has a plane of
  // 40 points and the retry is not needed).
  ReconstructionParams params;
  params.planes.min_points = 40;
  params.planes.max_angle = 20.0;
  for (const auto& [name, note, bound] : cases) {
    SCOPED_TRACE(name);
    const PointCloud cloud = read_point_cloud(folder + name + ".ply", kFieldXyz);
    const BuildingResult r = reconstruct_building(building_from_cloud(name, cloud.points), params);
    EXPECT_EQ(r.report.status, BuildingStatus::ok) << r.report.reason;
    EXPECT_EQ(r.report.level, ModelLevel::lod22);
    EXPECT_NE(r.report.note.find(note), std::string::npos) << r.report.note;
    ASSERT_TRUE(r.model.has_value());
    EXPECT_TRUE(check_mesh(r.model->mesh).valid());
    EXPECT_LT(r.report.rmse, bound);
  }
}

// Issue 10, "every point explained": three clouds of city3d_dev_large whose first model left more
// than 5% of the points farther than 1 m (City3D's own models: 0.0%, 0.0%, 0.9%), each fixed by a
// different rebuild: 00731's ground points form a plane whose face prior put a third of a flat roof
// at ground level; 08171's flat roof has a band without returns that cut the outline; 09083 has a crown of scattered returns 1-2.5 m above a
// shed, in no plane (a roof level of its own); 19772 has a 0.35 m strip of returns 1.05 m above its
// eave, a plane whose lines the regularisation merged into the eave's (a cell of its own). With the rebuilds off (retry_unexplained_share 1)
// each leaves more than 5%. (05389, a roof part of fewer points than a plane needs, was one until
// issue 23: its first model now explains its points, RMSE 0.16 m against 0.44 m before.)
TEST(Smoke, poorly_explained_models_are_rebuilt_until_their_points_are_explained) {
  const std::string folder = std::string(CITY3D_SHARED_DATA) + "/city3d_dev_large/AHN3/";
  if (!fs::exists(folder)) GTEST_SKIP() << "../shared/data is not beside the repository";
  // The variant each keeps: of the hypothesis (smaller planes, wide outline, left-out roofs), and for
  // 00731 of the selection too (without the face prior; the others' selection variant is free).
  struct Case {
    const char* name;
    RebuildOutcome::Variant variant;
    bool selection_checked;
  };
  const Case cases[] = {{"00731", {false, false, false, true, false}, true},
                        {"08171", {false, true, false, false, false}, false},
                        {"09083", {false, false, true, false, false}, false},
                        {"19772", {false, false, true, false, false}, false}};
  for (const auto& [name, variant, selection_checked] : cases) {
    SCOPED_TRACE(name);
    const PointCloud cloud = read_point_cloud(folder + name + ".ply", kFieldXyz);
    const BuildingInput input = building_from_cloud(name, cloud.points);
    ReconstructionParams off;
    off.retry_unexplained_share = 1.0;
    const BuildingResult before = reconstruct_building(input, off);
    EXPECT_GT(before.report.unexplained_share, 0.05);
    EXPECT_NE(before.report.rebuild.result, RebuildOutcome::Result::rebuilt) << before.report.note;

    const BuildingResult r = reconstruct_building(input, {});
    EXPECT_EQ(r.report.status, BuildingStatus::ok) << r.report.reason;
    EXPECT_EQ(r.report.level, ModelLevel::lod22);
    ASSERT_TRUE(r.model.has_value());
    EXPECT_TRUE(check_mesh(r.model->mesh).valid());
    const RebuildOutcome& rebuild = r.report.rebuild;
    EXPECT_EQ(rebuild.result, RebuildOutcome::Result::rebuilt) << r.report.note;
    EXPECT_TRUE(rebuild.unexplained);
    EXPECT_EQ(rebuild.variant.smaller_planes, variant.smaller_planes) << r.report.note;
    EXPECT_EQ(rebuild.variant.wide_outline, variant.wide_outline) << r.report.note;
    EXPECT_EQ(rebuild.variant.left_out, variant.left_out) << r.report.note;
    if (selection_checked) {
      EXPECT_EQ(rebuild.variant.without_prior, variant.without_prior) << r.report.note;
      EXPECT_EQ(rebuild.variant.half_complexity, variant.half_complexity) << r.report.note;
    }
    EXPECT_LT(rebuild.far_after, rebuild.far_before);
    EXPECT_DOUBLE_EQ(static_cast<double>(rebuild.far_after), r.report.unexplained_points);
    EXPECT_LT(r.report.unexplained_share, 0.05);
    EXPECT_LT(r.report.rmse, before.report.rmse);
    // The share the report gives is the written model's.
    std::size_t far = 0;
    for (const double d : point_distances(r.model->mesh, input.points)) far += d > kUnexplainedDistance;
    EXPECT_DOUBLE_EQ(r.report.unexplained_points, static_cast<double>(far));
  }
}

// Issue 23: two Delft buildings whose first model carries surface no point supports, each a low part whose
// few points (16 at 2.5 m; 17 at 3.4 m) form no plane of 20 under a roof plane extended over it. The
// points beneath that surface count as left out, and a rebuild gives them a roof: smaller planes for
// b31bbff4a, a roof level for the points left out for b31bc4dbd.
TEST(Smoke, models_with_unsupported_surface_are_rebuilt_until_the_points_support_them) {
  require_delft();
  FootprintReadOptions by_id;
  by_id.id_field = "gml_id";
  const FootprintSet set = read_footprints(kDelft + "/footprints/bgt_pand_laz_area.gpkg", by_id);
  // The variant of the hypothesis each keeps: smaller planes, roofs for the points left out.
  const std::pair<const char*, RebuildOutcome::Variant> cases[] = {{"b31bbff4a", {true, false, false, false, false}},
                                                                   {"b31bc4dbd", {false, false, true, false, false}}};
  std::vector<Footprint> chosen;
  for (const Footprint& f : set.footprints)
    for (const auto& c : cases)
      if (f.id.rfind(c.first, 0) == 0) chosen.push_back(f);
  ASSERT_EQ(chosen.size(), 2u);
  Cropper cropper(chosen, {});
  for (const char* tile : {"/ahn3_cropped_1.las", "/ahn3_cropped_2.las"})
    cropper.add(read_point_cloud(kDelft + tile, kFieldClassification));
  const std::vector<BuildingInput> inputs = cropper.finish();
  ASSERT_EQ(inputs.size(), 2u);
  for (const BuildingInput& input : inputs) {
    SCOPED_TRACE(input.id);
    const auto c = std::find_if(std::begin(cases), std::end(cases),
                                [&](const auto& k) { return input.id.rfind(k.first, 0) == 0; });
    ASSERT_NE(c, std::end(cases));
    ReconstructionParams off;
    off.retry_unsupported_area = 1e9;
    const BuildingResult before = reconstruct_building(input, off);
    EXPECT_GT(before.report.unsupported_area, 10.0);
    EXPECT_LT(before.report.unexplained_share, 0.05);  // the points alone see nothing wrong
    const BuildingResult r = reconstruct_building(input, {});
    EXPECT_EQ(r.report.status, BuildingStatus::ok) << r.report.reason;
    ASSERT_TRUE(r.model.has_value());
    const RebuildOutcome& rebuild = r.report.rebuild;
    EXPECT_EQ(rebuild.result, RebuildOutcome::Result::rebuilt) << r.report.note;
    EXPECT_TRUE(rebuild.unsupported);
    EXPECT_EQ(rebuild.variant.smaller_planes, c->second.smaller_planes) << r.report.note;
    EXPECT_EQ(rebuild.variant.left_out, c->second.left_out) << r.report.note;
    EXPECT_FALSE(rebuild.variant.wide_outline);
    EXPECT_GT(rebuild.unsupported_before, 10.0);
    EXPECT_DOUBLE_EQ(rebuild.unsupported_after, r.report.unsupported_area);
    EXPECT_LT(r.report.unsupported_area, 1.0);
    EXPECT_LT(r.report.rmse, before.report.rmse);
  }
}

// The inputs of the Delft footprints whose ids begin with `houses`, from every `k`th point record of
// both tiles.
std::vector<BuildingInput> thinned_delft_inputs(const std::vector<std::string>& houses, std::size_t k) {
  FootprintReadOptions by_id;
  by_id.id_field = "gml_id";
  const FootprintSet set = read_footprints(kDelft + "/footprints/bgt_pand_laz_area.gpkg", by_id);
  std::vector<Footprint> chosen;
  for (const Footprint& f : set.footprints)
    if (std::any_of(houses.begin(), houses.end(), [&](const std::string& h) { return f.id.rfind(h, 0) == 0; }))
      chosen.push_back(f);
  EXPECT_EQ(chosen.size(), houses.size());
  Cropper cropper(chosen, {});
  for (const char* tile : {"/ahn3_cropped_1.las", "/ahn3_cropped_2.las"}) {
    const PointCloud full = read_point_cloud(kDelft + tile, kFieldClassification);
    PointCloud thinned;
    for (std::size_t i = 0; i < full.size(); i += k) {
      thinned.points.push_back(full.points[i]);
      thinned.classification.push_back(full.classification[i]);
    }
    cropper.add(thinned);
  }
  return cropper.finish();
}

// Issue 23: the Delft tiles at every 4th point record (about 2 points per m2, as older or non-Dutch surveys
// have them). Six houses then hold 7 to 28 points, too few or too sparse for region growing: each still
// gets a LoD2.2 model, its planes fitted through triples of its points, closer to its points than the
// LoD1.2 block it fell back to before.
TEST(Smoke, sparse_small_houses_get_lod22_from_planes_through_triples_of_their_points) {
  require_delft();
  const std::vector<std::string> houses = {"b31be22b0", "b31e18918", "b31e18912",
                                           "b31bdd43a", "b31e1d770", "b31e1feb7"};
  const std::vector<BuildingInput> inputs = thinned_delft_inputs(houses, 4);
  ASSERT_EQ(inputs.size(), houses.size());
  int several = 0;
  for (const BuildingInput& input : inputs) {
    SCOPED_TRACE(input.id);
    EXPECT_LE(input.points.size(), 30u);
    const BuildingResult r = reconstruct_building(input, {});
    EXPECT_EQ(r.report.status, BuildingStatus::ok) << r.report.reason;
    EXPECT_EQ(r.report.level, ModelLevel::lod22) << r.report.reason;
    EXPECT_NE(r.report.note.find("few points: planes fitted"), std::string::npos) << r.report.note;
    ASSERT_TRUE(r.model.has_value());
    EXPECT_TRUE(check_mesh(r.model->mesh).valid());
    EXPECT_LT(r.report.rmse, r.report.rmse_lod12);
    EXPECT_LT(r.report.unsupported_area, 1.5);
    // planes.few_points_divisor: planes through triples that must each hold every point, not a quarter
    // of them, are one plane at most.
    ReconstructionParams whole;
    whole.planes.few_points_divisor = 1;
    const BuildingResult one = reconstruct_building(input, whole);
    EXPECT_LE(one.report.planes, 1u) << one.report.note;
    several += r.report.planes > 1;
  }
  EXPECT_GE(several, 1) << "a house of more than one plane at the default quarter";
}

// At every 8th point record a house of 62 points has no plane from region growing, and more points
// than the triples of all of them could be searched: the triples of 60 of them, spread over the house,
// give it a LoD2.2 model (it was a LoD1.2 block, 0.93 m from the full-density points).
TEST(Smoke, a_sparse_house_of_more_points_than_the_candidates_gets_lod22_from_triples) {
  require_delft();
  const std::vector<BuildingInput> inputs = thinned_delft_inputs({"b31bc4dcc"}, 8);
  ASSERT_EQ(inputs.size(), 1u);
  EXPECT_GT(inputs[0].points.size(), 60u);
  const BuildingResult r = reconstruct_building(inputs[0], {});
  EXPECT_EQ(r.report.status, BuildingStatus::ok) << r.report.reason;
  EXPECT_EQ(r.report.level, ModelLevel::lod22) << r.report.reason;
  EXPECT_NE(r.report.note.find("few points: planes fitted through triples of its"), std::string::npos)
      << r.report.note;
  ASSERT_TRUE(r.model.has_value());
  EXPECT_TRUE(check_mesh(r.model->mesh).valid());
  EXPECT_LT(r.report.rmse, r.report.rmse_lod12);
}

// At every 8th point record b31bc9c58's steep south-east slope is the only plane with points near a
// cell along its north-east side (that side's returns made no plane), and over it the slope rose to
// 25.3 m, 10.6 m above the building's highest point (68.6 m2 no point supports). The planes whose
// points come nearest and are no blade there are now offered beside it, and one of them is chosen.
TEST(Smoke, a_cell_whose_one_plane_is_a_blade_gets_the_nearest_plane_that_is_not) {
  require_delft();
  const std::vector<BuildingInput> inputs = thinned_delft_inputs({"b31bc9c58"}, 8);
  ASSERT_EQ(inputs.size(), 1u);
  const BuildingResult r = reconstruct_building(inputs[0], {});
  EXPECT_EQ(r.report.level, ModelLevel::lod22) << r.report.reason;
  ASSERT_TRUE(r.model.has_value());
  EXPECT_TRUE(check_mesh(r.model->mesh).valid());
  EXPECT_LT(r.report.unsupported_area, 5.0) << r.report.note;
  double top_point = -std::numeric_limits<double>::infinity(), top_model = top_point;
  for (const Point3& p : inputs[0].points) top_point = std::max(top_point, p.z);
  for (const Point3& v : r.model->mesh.vertices) top_model = std::max(top_model, v.z);
  EXPECT_LT(top_model, top_point + 1.0);
}

// A building the rebuilds cannot help says so in its report, with the share it leaves (AHN3 large/02574:
// 10 of its 52 points farther than 1 m from its flat roof. AHN3 large/06023, this test's building before,
// 40% of its 75 points left out, is now rebuilt to none).
TEST(Smoke, a_model_no_rebuild_improves_is_kept_and_reported) {
  const std::string file = std::string(CITY3D_SHARED_DATA) + "/city3d_dev_large/AHN3/02574.ply";
  if (!fs::exists(file)) GTEST_SKIP() << "../shared/data is not beside the repository";
  const PointCloud cloud = read_point_cloud(file, kFieldXyz);
  const BuildingInput input = building_from_cloud("02574", cloud.points);
  ReconstructionParams off;
  off.retry_unexplained_share = 1.0;
  const BuildingResult before = reconstruct_building(input, off);
  const BuildingResult r = reconstruct_building(input, {});
  ASSERT_TRUE(r.model.has_value());
  EXPECT_GT(r.report.unexplained_share, 0.05);
  EXPECT_EQ(r.report.rebuild.result, RebuildOutcome::Result::no_better) << r.report.note;
  EXPECT_TRUE(r.report.rebuild.unexplained);
  EXPECT_EQ(r.report.rebuild.far_after, r.report.rebuild.far_before);
  EXPECT_EQ(r.model->mesh.faces, before.model->mesh.faces);
}

// LoD1.2 and LoD1.3 of models whose roof faces meet off by a few millimetres (18356: a step wall in
// two pieces 0.5 degrees apart, its vertex 1.1 mm off the taller roof's edge), whose height clusters
// meet at a vertex across another cluster (06209), or with a roof part that is itself a sliver along a
// neighbour's edge, which joining folds (13825): the blocks as first made are no valid solid, and were
// left out; with no more than two walls over each other on a vertex's column, of the parts joined
// within lod1.join_distance or else of the parts as they are, they are made at the 3 m step.
TEST(Smoke, blocks_of_roof_parts_that_meet_off_by_a_millimetre_or_at_a_vertex_are_made) {
  const struct {
    const char* set;
    const char* id;
  } cases[] = {{"city3d_dev", "18356"}, {"city3d_dev", "06209"}, {"city3d_dev_large", "13825"}};
  for (const auto& c : cases) {
    const std::string file = std::string(CITY3D_SHARED_DATA) + "/" + c.set + "/AHN3/" + c.id + ".ply";
    if (!fs::exists(file)) GTEST_SKIP() << "../shared/data is not beside the repository";
    const PointCloud cloud = read_point_cloud(file, kFieldXyz);
    const BuildingResult r = reconstruct_building(building_from_cloud(c.id, cloud.points), {});
    ASSERT_TRUE(r.model.has_value()) << c.id;
    EXPECT_EQ(r.report.lods, "1.2,1.3,2.2") << c.id << ": " << r.report.note;
    EXPECT_EQ(r.report.note.find("LoD1."), std::string::npos) << c.id << ": " << r.report.note;
    ASSERT_EQ(r.lods.size(), 3u) << c.id;
    for (const LodModel& m : r.lods) EXPECT_TRUE(check_mesh(m.model.mesh).valid()) << c.id << " LoD" << m.lod;
    // LoD1.3 lies between the block of one height and the LoD2 model.
    EXPECT_LT(r.report.volume_lod13, r.report.volume_lod12) << c.id;
    EXPECT_LT(r.report.rmse_lod13, r.report.rmse_lod12) << c.id;
  }
}

namespace {

// The area in plan of a model's ground faces.
double floor_area(const BuildingModel& m) {
  const std::vector<SurfaceType> types = surface_types(m);
  double area = 0.0;
  for (std::size_t f = 0; f < m.mesh.faces.size(); ++f) {
    if (types[f] != SurfaceType::ground) continue;
    const auto& face = m.mesh.faces[f];
    for (std::size_t k = 0; k < face.size(); ++k) {
      const Point3& a = m.mesh.vertices[face[k]];
      const Point3& b = m.mesh.vertices[face[(k + 1) % face.size()]];
      area += (a.x * b.y - b.x * a.y) / 2;
    }
  }
  return std::fabs(area);
}

}  // namespace

// AHN3 large/13511's roof parts touch the outline at a single vertex, and 19589's make a ring that
// crosses itself: no blocks of them are a valid solid, at any step. LoD1.2 and LoD1.3 are the block of
// the LoD2.2 model's floor, the outline every level then shares (the cloud's convex hull, which the
// LoD1 rung takes, adds ground the building does not stand on), and the note says so.
TEST(Smoke, blocks_that_cannot_be_valid_fall_to_the_block_of_the_lod22_floor_and_the_note_says_so) {
  const struct {
    const char* id;
    const char* code;
  } cases[] = {{"13511", "304"}, {"19589", "104"}};
  for (const auto& c : cases) {
    const std::string file = std::string(CITY3D_SHARED_DATA) + "/city3d_dev_large/AHN3/" + c.id + ".ply";
    if (!fs::exists(file)) GTEST_SKIP() << "../shared/data is not beside the repository";
    const PointCloud cloud = read_point_cloud(file, kFieldXyz);
    const BuildingResult r = reconstruct_building(building_from_cloud(c.id, cloud.points), {});
    ASSERT_TRUE(r.model.has_value()) << c.id;
    EXPECT_EQ(r.report.lods, "1.2,1.3,2.2") << c.id << ": " << r.report.note;
    for (const std::string note :
         {std::string(
              "LoD1.2 as the block of the LoD2.2 model's floor: its blocks are not valid as written: ") +
              c.code,
          std::string("LoD1.3 as the block of the LoD2.2 model's floor: at 3 m its blocks are not valid as "
                      "written: ") +
              c.code})
      EXPECT_NE(r.report.note.find(note), std::string::npos) << c.id << ": " << r.report.note;
    ASSERT_EQ(r.lods.size(), 3u) << c.id;
    for (const LodModel& m : r.lods) EXPECT_TRUE(check_mesh(m.model.mesh).valid()) << c.id << " LoD" << m.lod;
    // The LoD2.2 model's floor, at the LoD1 rung's height: smaller than the hull's block, and closer.
    EXPECT_NEAR(floor_area(r.lods[0].model), floor_area(r.lods[2].model), 1e-3) << c.id;
    const BuildingModel hull = make_lod1_block(building_from_cloud(c.id, cloud.points));
    EXPECT_LT(floor_area(r.lods[0].model), floor_area(hull) - 1.0) << c.id;
    EXPECT_GT(r.report.volume_lod12, r.report.volume_lod22) << c.id;
    EXPECT_LT(r.report.rmse_lod12, rmse(hull.mesh, building_from_cloud(c.id, cloud.points).points)) << c.id;
  }
}

// AHN3/06050: 219 points of a tree-like cluster 2-13 m high, whose returns form no plane, and 21
// ground-level returns scattered 5-15 m away, which do. The outline is the cluster's; a roof of the
// ground returns' plane clipped to it made a 12 cm slab at ground level (RMSE 6.50 m, 99.6% of the
// points farther than 1 m). A plane without a quarter of its points inside an inferred part is not
// the part's roof, so the building falls to a block at its roof height, and the report says why.
TEST(Smoke, a_roof_plane_outside_the_inferred_outline_is_not_its_roof) {
  const std::string file = std::string(CITY3D_SHARED_DATA) + "/city3d_dev_large/AHN3/06050.ply";
  if (!fs::exists(file)) GTEST_SKIP() << "../shared/data is not beside the repository";
  const PointCloud cloud = read_point_cloud(file, kFieldXyz);
  const BuildingResult r = reconstruct_building(building_from_cloud("06050", cloud.points), {});
  ASSERT_TRUE(r.model.has_value());
  EXPECT_EQ(r.report.status, BuildingStatus::fallback);
  EXPECT_EQ(r.report.level, ModelLevel::lod12);
  EXPECT_NE(r.report.reason.find("none of the 1 roof planes lies inside the inferred outline"), std::string::npos)
      << r.report.reason;
  EXPECT_TRUE(check_mesh(r.model->mesh).valid());
  EXPECT_LT(r.report.rmse, 2.0);
  EXPECT_LT(r.report.unexplained_share, 0.3);
}

// The rebuilds are bounded by work, not time: AHN3/13894 (6,628 points) leaves 5.0% unexplained, and
// its smaller planes make 5,852 candidate faces (a 37 s selection); variants over the limit are not
// selected, and the note names them with their size. A variant within it is (roofs for the points
// left out: 0.7%).
TEST(Smoke, rebuild_variants_over_the_work_limit_are_not_selected_and_said) {
  const std::string file = std::string(CITY3D_SHARED_DATA) + "/city3d_dev/AHN3/13894.ply";
  if (!fs::exists(file)) GTEST_SKIP() << "../shared/data is not beside the repository";
  const PointCloud cloud = read_point_cloud(file, kFieldXyz);
  const BuildingResult r = reconstruct_building(building_from_cloud("13894", cloud.points), {});
  ASSERT_TRUE(r.model.has_value());
  EXPECT_EQ(r.report.level, ModelLevel::lod22);
  EXPECT_LE(r.report.candidate_faces, 3000u);
  EXPECT_LT(r.report.unexplained_share, 0.05);
  const RebuildOutcome& rebuild = r.report.rebuild;
  EXPECT_EQ(rebuild.result, RebuildOutcome::Result::rebuilt) << r.report.note;
  EXPECT_TRUE(rebuild.variant.left_out) << r.report.note;
  // The smaller planes' hypothesis is over the limit, and not selected over.
  ASSERT_FALSE(rebuild.over_limit.empty()) << r.report.note;
  EXPECT_TRUE(rebuild.over_limit.front().first.smaller_planes);
  EXPECT_GT(rebuild.over_limit.front().second, 3000u);

  // The work limit is a parameter (RebuildParams::max_candidate_faces): under it, no rebuild at all.
  ReconstructionParams small_limit;
  small_limit.rebuild.max_candidate_faces = 100;
  const BuildingResult limited = reconstruct_building(building_from_cloud("13894", cloud.points), small_limit);
  EXPECT_EQ(limited.report.rebuild.result, RebuildOutcome::Result::too_large) << limited.report.note;
  EXPECT_NE(limited.report.note.find("more than 100)"), std::string::npos) << limited.report.note;
}

// Left-out points in no plane, grouped by plan and height, become horizontal roof levels.
TEST(LeftOut, points_in_no_plane_become_a_roof_level_per_group) {
  std::vector<Point3> points;
  std::vector<bool> unexplained;
  const auto add = [&](double x, double y, double z, bool left_out) {
    points.push_back({x, y, z});
    unexplained.push_back(left_out);
  };
  PlanarSegment plane;  // a segmented roof: its points are never a level, left out or not
  for (int i = 0; i < 30; ++i) {
    plane.points.push_back(static_cast<std::uint32_t>(points.size()));
    add(3.9 + 0.2 * (i % 6), 0.2 * (i / 6), 3.0, i % 2 == 0);  // beside group A
  }
  // Group A: 15 points at z = 3.0 + 0.01 k (median 3.07) on a 0.2 m grid. Group B: 12 points 2 m
  // above it, over the same area: another level. Their points interleave (A 30, B 31, A 32, ...,
  // B 53, then A 54-56), so A comes first by its smallest point but B's largest point is smaller.
  for (int k = 0; k < 15; ++k) {
    add(5.0 + 0.2 * (k % 5), 0.2 * (k / 5), 3.0 + 0.01 * k, true);
    if (k < 12) add(5.0 + 0.2 * (k % 4), 0.2 * (k / 4), 5.0 + 0.01 * k, true);
  }
  // 6 points far away in plan: too few for a level. 12 explained points: no level either.
  for (int k = 0; k < 6; ++k) add(20.0 + 0.2 * k, 0.0, 3.0, true);
  for (int k = 0; k < 12; ++k) add(10.0 + 0.2 * (k % 4), 0.2 * (k / 4), 3.0, false);

  const std::vector<PlanarSegment> levels = detail::left_out_levels(points, {plane}, unexplained, 0.2, 10,
                                                                     RebuildParams{});
  ASSERT_EQ(levels.size(), 2u);
  EXPECT_EQ(levels[0].points.size(), 15u);
  EXPECT_EQ(levels[0].points.front(), 30u);
  EXPECT_EQ(levels[1].points.size(), 12u);
  EXPECT_EQ(levels[1].points.front(), 31u);
  EXPECT_EQ(levels[0].points.back(), 56u);
  EXPECT_EQ(levels[1].points.back(), 53u);
  for (const PlanarSegment& level : levels) {
    EXPECT_EQ(level.kind, PlanarSegment::Kind::roof);
    EXPECT_DOUBLE_EQ(level.plane.a, 0.0);
    EXPECT_DOUBLE_EQ(level.plane.b, 0.0);
    EXPECT_DOUBLE_EQ(level.plane.c, 1.0);
    EXPECT_TRUE(std::is_sorted(level.points.begin(), level.points.end()));
  }
  EXPECT_NEAR(-levels[0].plane.d, 3.07, 1e-12);
  EXPECT_NEAR(-levels[1].plane.d, 5.06, 1e-12);
  // Linked in plan only within 3 spacings: at a spacing of 0.05 m (radius 0.15 m) the 0.2 m grid
  // falls apart into single points, none a level.
  EXPECT_TRUE(detail::left_out_levels(points, {plane}, unexplained, 0.05, 10, RebuildParams{}).empty());
}

// A gable at 1 point per m2 whose one slope became a plane extended over the whole house: the other
// slope's points, left out, are a plane of their own; a group holding no plane of half its points,
// and a group of more than max_left_out_plane_points, are none.
TEST(LeftOut, the_left_out_slope_of_a_sparse_gable_is_a_plane_of_its_own) {
  std::vector<Point3> points;
  std::vector<bool> unexplained;
  PlanarSegment found;  // the slope region growing found (y < 4): never searched again
  const double t = std::tan(40.0 * kPi / 180.0);
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 4; ++j) {
      const double x = 1.0 * i + 0.1 * j, y = 0.5 + 1.0 * j + 0.05 * i;
      found.points.push_back(static_cast<std::uint32_t>(points.size()));
      points.push_back({x, y, 5.0 + t * y});
      unexplained.push_back(false);
      points.push_back({x, 8.0 - y, 5.0 + t * y});  // the other slope, mirrored: left out
      unexplained.push_back(true);
    }
  // 12 scattered points 20 m away at random heights: a group, but no plane holds half of them.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> height(0.0, 6.0);
  for (int k = 0; k < 12; ++k) {
    points.push_back({20.0 + 0.7 * (k % 4), 0.7 * (k / 4), height(rng)});
    unexplained.push_back(true);
  }
  RebuildParams params;
  const auto planes = detail::left_out_planes(points, {found}, unexplained, 1.0, 4, PlaneParams{}, params);
  ASSERT_EQ(planes.size(), 1u);
  EXPECT_EQ(planes[0].kind, PlanarSegment::Kind::roof);
  EXPECT_EQ(planes[0].points.size(), 32u);
  for (std::uint32_t i : planes[0].points) EXPECT_EQ(i % 2, 1u) << "a point of the left-out slope";
  EXPECT_TRUE(std::is_sorted(planes[0].points.begin(), planes[0].points.end()));
  EXPECT_GT(planes[0].plane.b, 0.0);  // it faces the other way (+y) from the slope found
  EXPECT_NEAR(std::acos(planes[0].plane.c) * 180.0 / kPi, 40.0, 1.0);
  // A plane needs half its group, not the group's least count (min_points, the points of a level): with
  // 8 returns of clutter 3 m over the slope the group holds 40 points, and the slope's 32 are a plane
  // when a group needs 36.
  for (int k = 0; k < 8; ++k) {
    const double x = 0.9 * k + 0.3, y = 5.0 + 0.3 * (k % 3);
    points.push_back({x, y, 8.0 + t * (8.0 - y) + 0.1 * k});
    unexplained.push_back(true);
  }
  const auto with_clutter =
      detail::left_out_planes(points, {found}, unexplained, 1.0, 36, PlaneParams{}, params);
  ASSERT_EQ(with_clutter.size(), 1u);
  EXPECT_EQ(with_clutter[0].points, planes[0].points);
  // rebuild.left_out_plane_divisor: a plane that must hold the whole group (1), not half (2), is not the
  // slope's 32 of 40.
  RebuildParams whole = params;
  whole.left_out_plane_divisor = 1;
  EXPECT_TRUE(detail::left_out_planes(points, {found}, unexplained, 1.0, 4, PlaneParams{}, whole).empty());
  // More points than the triples are searched for: no plane.
  params.max_left_out_plane_points = 31;
  EXPECT_TRUE(detail::left_out_planes(points, {found}, unexplained, 1.0, 4, PlaneParams{}, params).empty());
}

// A plane whose points are mostly left out gets the rectangle around them, parallel to the outline.
TEST(LeftOut, a_plane_mostly_left_out_gets_a_rectangle_parallel_to_the_outline) {
  const double c = std::cos(0.5), s = std::sin(0.5);  // the outline is a square turned by 0.5 rad
  const auto turn = [&](double u, double v) { return Point2{u * c - v * s, u * s + v * c}; };
  Polygon2 square;
  for (const auto& [u, v] : {std::pair{0.0, 0.0}, {10.0, 0.0}, {10.0, 10.0}, {0.0, 10.0}}) square.outer.push_back(turn(u, v));
  std::vector<Point3> points;
  std::vector<bool> unexplained;
  // A strip 4 m x 0.3 m along the outline's first edge, 1 m in; 3 of its 4 points per row left out.
  PlanarSegment strip, roof, row;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 4; ++j) {
      const Point2 p = turn(2.0 + 0.2 * i, 1.0 + 0.1 * j);
      strip.points.push_back(static_cast<std::uint32_t>(points.size()));
      points.push_back({p.x, p.y, 5.0});
      unexplained.push_back(j != 0);
    }
  // A roof with 4 of its 10 points left out (an area: less than half), and a row of left-out points
  // (no width): no rectangle.
  for (int i = 0; i < 10; ++i) {
    const Point2 p = turn(5.0 + i % 5, 5.0 + i / 5);
    roof.points.push_back(static_cast<std::uint32_t>(points.size()));
    points.push_back({p.x, p.y, 4.0});
    unexplained.push_back(i == 0 || i == 1 || i == 5 || i == 6);
  }
  for (int i = 0; i < 5; ++i) {
    const Point2 p = turn(5.0 + i, 8.0);
    row.points.push_back(static_cast<std::uint32_t>(points.size()));
    points.push_back({p.x, p.y, 4.0});
    unexplained.push_back(true);
  }
  const std::vector<Segment2> lines = detail::left_out_plane_lines(points, {strip, roof, row}, unexplained, {square},
                                                                   RebuildParams{});
  ASSERT_EQ(lines.size(), 4u);
  // In the outline's frame the rectangle is [2, 5.8] x [1.1, 1.3]: the left-out rows only.
  double u0 = 1e9, u1 = -1e9, v0 = 1e9, v1 = -1e9;
  for (const Segment2& l : lines) {
    for (const Point2& p : {l.a, l.b}) {
      const double u = p.x * c + p.y * s, v = -p.x * s + p.y * c;
      u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
    }
    // Every side runs along u or along v.
    const double du = (l.b.x - l.a.x) * c + (l.b.y - l.a.y) * s, dv = -(l.b.x - l.a.x) * s + (l.b.y - l.a.y) * c;
    EXPECT_LT(std::min(std::fabs(du), std::fabs(dv)), 1e-9);
  }
  EXPECT_NEAR(u0, 2.0, 1e-9);
  EXPECT_NEAR(u1, 5.8, 1e-9);
  EXPECT_NEAR(v0, 1.1, 1e-9);
  EXPECT_NEAR(v1, 1.3, 1e-9);
  // Where 40% of a plane left out is enough (rebuild.left_out_cell_share), the roof gets its cell too.
  RebuildParams smaller_share;
  smaller_share.left_out_cell_share = 0.4;
  EXPECT_EQ(
      detail::left_out_plane_lines(points, {strip, roof, row}, unexplained, {square}, smaller_share).size(),
      8u);
}

// An inferred part's roofs are the planes of which at least outline.part_roof_share of the points lie
// inside it.
TEST(Outline, a_part_holds_the_roof_planes_of_which_its_share_of_points_lie_inside_it) {
  const Polygon2 part{{{0, 0}, {10, 0}, {10, 10}, {0, 10}}, {}};
  std::vector<Point3> points;
  PlanarSegment plane;
  for (int i = 0; i < 10; ++i) {
    plane.points.push_back(static_cast<std::uint32_t>(points.size()));
    points.push_back({i < 3 ? 5.0 : 15.0 + i, 5.0, 4.0});  // 3 of its 10 points inside the part
  }
  EXPECT_EQ(detail::roofs_of_part({plane}, part, points, 0.25).size(), 1u);
  EXPECT_EQ(detail::roofs_of_part({plane}, part, points, 0.3).size(), 1u);
  EXPECT_TRUE(detail::roofs_of_part({plane}, part, points, 0.5).empty());
}

// A cloud of a house and a 3 x 3 m shed 4 m from it: the shed is a part of the inferred outline when
// more than outline.extra_part_plane_share of some roof plane's points lie in it. Its one plane here
// holds 60% of its points in the shed (and 40% on the house).
TEST(Outline, a_further_part_needs_its_share_of_a_roof_planes_points) {
  std::vector<Point3> world;
  PlanarSegment house, shed;
  for (double x = 0.15; x < 10; x += 0.3)
    for (double y = 0.15; y < 8; y += 0.3) {
      house.points.push_back(static_cast<std::uint32_t>(world.size()));
      world.push_back({85000 + x, 446000 + y, 6.0});
    }
  for (double x = 14.15; x < 17; x += 0.3)
    for (double y = 0.15; y < 3; y += 0.3) {
      shed.points.push_back(static_cast<std::uint32_t>(world.size()));
      world.push_back({85000 + x, 446000 + y, 3.0});
    }
  const std::size_t in_shed = shed.points.size();
  for (std::size_t k = 0; k < in_shed * 2 / 3; ++k) shed.points.push_back(house.points[k]);
  ASSERT_NEAR(static_cast<double>(in_shed) / static_cast<double>(shed.points.size()), 0.6, 0.01);
  const BuildingInput input = building_from_cloud("house_and_shed", world);
  ReconstructionParams params;
  const Heightmap heightmap = rasterise_tin(input.points, params.heightmap);
  BuildingReport report;
  EXPECT_EQ(detail::building_outline(input, heightmap, {house, shed}, params, false, report).size(), 2u)
      << report.note;
  params.outline.extra_part_plane_share = 0.7;
  EXPECT_EQ(detail::building_outline(input, heightmap, {house, shed}, params, false, report).size(), 1u)
      << report.note;
}

namespace {

// A synthetic building for the whole per-building pipeline: roof points on a jittered 0.3 m grid
// (about 11 points per m2, AHN3's density) with 3 cm of Gaussian noise, the footprint given, the
// ground measured at z = 0.
BuildingInput synthetic_input(const Ring2& outline, const std::function<double(double, double)>& roof,
                              std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.1, 0.1);
  std::normal_distribution<double> noise(0.0, 0.03);
  BuildingInput in;
  in.id = "synthetic";
  in.footprint.id = in.id;
  in.footprint.polygons.push_back({outline, {}});
  Box2 box;
  for (const Point2& p : outline) box.add(p);
  for (double y = box.min.y + 0.15; y < box.max.y; y += 0.3)
    for (double x = box.min.x + 0.15; x < box.max.x; x += 0.3) {
      const double px = x + jitter(rng), py = y + jitter(rng);
      bool inside = false;  // even-odd rule
      for (std::size_t i = 0, j = outline.size() - 1; i < outline.size(); j = i++)
        if ((outline[i].y > py) != (outline[j].y > py) &&
            px < (outline[j].x - outline[i].x) * (py - outline[i].y) / (outline[j].y - outline[i].y) + outline[i].x)
          inside = !inside;
      if (inside) in.points.push_back({px, py, roof(px, py) + noise(rng)});
    }
  in.ground_z = 0.0;
  in.ground_method = "given";
  in.ground_measured = true;
  return in;
}

}  // namespace

TEST(EndToEnd, synthetic_box_gable_l_and_step_buildings_reconstruct_to_their_shapes) {
  struct Case {
    const char* name;
    Ring2 outline;
    std::function<double(double, double)> roof;
    std::size_t faces;
    double volume;
  };
  const Case cases[] = {
      {"box 10 x 6, flat at 5 m", {{0, 0}, {10, 0}, {10, 6}, {0, 6}}, [](double, double) { return 5.0; }, 6, 300.0},
      {"gable 10 x 8, eaves 4 m, ridge 6 m",
       {{0, 0}, {10, 0}, {10, 8}, {0, 8}},
       [](double, double y) { return y < 4 ? 4.0 + 0.5 * y : 8.0 - 0.5 * y; },
       7,
       400.0},
      {"L, flat at 3 m",
       {{0, 0}, {10, 0}, {10, 4}, {4, 4}, {4, 10}, {0, 10}},
       [](double, double) { return 3.0; },
       8,
       192.0},
      {"step 12 x 6, 7 m and 4 m",
       {{0, 0}, {12, 0}, {12, 6}, {0, 6}},
       [](double x, double) { return x < 6 ? 7.0 : 4.0; },
       8,
       396.0},
  };
  std::uint32_t seed = 1;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const BuildingResult r = reconstruct_building(synthetic_input(c.outline, c.roof, seed++), {});
    EXPECT_EQ(r.report.status, BuildingStatus::ok) << r.report.reason;
    EXPECT_EQ(r.report.level, ModelLevel::lod22);
    ASSERT_TRUE(r.model.has_value());
    const MeshCheck check = check_mesh(r.model->mesh);
    EXPECT_TRUE(check.valid());
    EXPECT_EQ(r.model->mesh.faces.size(), c.faces);
    EXPECT_NEAR(check.signed_volume, c.volume, 0.03 * c.volume);
    EXPECT_LT(r.report.rmse, 0.05);
  }
}

// With a footprint, its walls are the outline: the heightmap's edges along the rim of the data (the drop
// from the roof to no data) are not made into polylines, only the step between the two roofs is. Walls
// inferred from the lines (--walls inferred) still get the outline's.
TEST(EndToEnd, with_a_footprint_the_polylines_follow_the_step_and_not_the_outline) {
  const fs::path debug = fs::temp_directory_path() / "city3d_test_rim_edges";
  const BuildingInput input = synthetic_input(
      {{0, 0}, {12, 0}, {12, 6}, {0, 6}}, [](double x, double) { return x < 6 ? 7.0 : 4.0; }, 4);
  const auto polylines_box = [&](WallMode mode, std::size_t& vertices) {
    fs::remove_all(debug);
    ReconstructionParams params;
    params.debug_dir = debug.string();
    params.walls.mode = mode;
    const BuildingResult r = reconstruct_building(input, params);
    EXPECT_EQ(r.report.level, ModelLevel::lod22) << r.report.reason;
    EXPECT_TRUE(r.model && r.model->mesh.faces.size() == 8u);
    std::ifstream obj(debug / "synthetic" / "polylines.obj");
    EXPECT_TRUE(obj) << "no polylines.obj in " << debug;
    Box2 box;
    vertices = 0;
    for (std::string line; std::getline(obj, line);) {
      std::istringstream in(line);
      std::string tag;
      double x = 0, y = 0;
      if (in >> tag >> x >> y && tag == "v") {
        box.add({x, y});
        ++vertices;
      }
    }
    fs::remove_all(debug);
    return box;
  };
  // The step runs across the 6 m width at one x; the outline spans the 12 m length too.
  std::size_t vertices = 0;
  for (WallMode mode : {WallMode::automatic, WallMode::footprint}) {
    const Box2 box = polylines_box(mode, vertices);
    ASSERT_GE(vertices, 2u);
    EXPECT_LT(box.max.x - box.min.x, 1.0);
    EXPECT_GT(box.max.y - box.min.y, 4.0);
  }
  const Box2 inferred = polylines_box(WallMode::inferred, vertices);
  ASSERT_GE(vertices, 2u);
  EXPECT_GT(inferred.max.x - inferred.min.x, 11.0);
}

// The roof type (3DBAG's b3_dak_type) takes a roof within RoofTypeParams::flat_angle of horizontal as
// flat: a shed roof of 5 degrees is slanted at the default 3, horizontal at 10.
TEST(EndToEnd, the_roof_type_follows_its_flat_angle) {
  const Ring2 outline{{0, 0}, {10, 0}, {10, 6}, {0, 6}};
  const double rise = std::tan(5.0 * kPi / 180.0);
  const BuildingInput input = synthetic_input(outline, [rise](double x, double) { return 4.0 + rise * x; }, 7);
  const BuildingResult slanted = reconstruct_building(input, {});
  ASSERT_EQ(slanted.report.level, ModelLevel::lod22) << slanted.report.reason;
  EXPECT_EQ(slanted.report.roof_type, "slanted");
  ReconstructionParams params;
  params.roof_type.flat_angle = 10.0;
  const BuildingResult flat = reconstruct_building(input, params);
  ASSERT_EQ(flat.report.level, ModelLevel::lod22) << flat.report.reason;
  EXPECT_EQ(flat.report.roof_type, "horizontal");
}

// 2 million points on one roof (13,000 per m2) split it into 6,786 planes and the run ran out of
// memory: a building denser than max_point_density is thinned first, one point per cell in plan.
TEST(EndToEnd, a_building_denser_than_max_point_density_is_thinned_first_and_says_so) {
  const Ring2 outline{{0, 0}, {10, 0}, {10, 6}, {0, 6}};
  const auto gable = [](double, double y) { return 4.0 + 0.5 * std::min(y, 6.0 - y); };
  const BuildingInput sparse = synthetic_input(outline, gable, 11);  // about 11 points per m2
  const BuildingResult as_given = reconstruct_building(sparse, {});
  ASSERT_EQ(as_given.report.level, ModelLevel::lod22) << as_given.report.reason;
  EXPECT_EQ(as_given.report.note.find("thinned"), std::string::npos) << as_given.report.note;
  // Each point 60 times, within a centimetre: about 650 per m2.
  BuildingInput dense = sparse;
  dense.points.clear();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> cm(-0.01, 0.01);
  for (const Point3& p : sparse.points)
    for (int k = 0; k < 60; ++k) dense.points.push_back({p.x + cm(rng), p.y + cm(rng), p.z + cm(rng)});
  const BuildingResult thinned = reconstruct_building(dense, {});
  ASSERT_EQ(thinned.report.level, ModelLevel::lod22) << thinned.report.reason;
  EXPECT_NE(thinned.report.note.find("points thinned from " + std::to_string(dense.points.size())),
            std::string::npos)
      << thinned.report.note;
  EXPECT_LT(thinned.report.points, dense.points.size() / 10);
  EXPECT_EQ(thinned.report.planes, as_given.report.planes);
  // Below the limit nothing is thinned, whatever the density.
  ReconstructionParams high;
  high.max_point_density = 1000.0;
  EXPECT_EQ(reconstruct_building(dense, high).report.note.find("thinned"), std::string::npos);
  // A wall's column of points, one every centimetre up 4 m: thinned cells 5 cm tall keep ten times as
  // many of them as the default 50 cm.
  BuildingInput column = dense;
  for (int k = 0; k < 400; ++k) column.points.push_back({0.2, 3.0, 0.01 * k});
  ReconstructionParams short_cells;
  short_cells.thinning_height_cells = 1.0;
  const std::size_t tall = reconstruct_building(column, {}).report.points;
  const std::size_t fine = reconstruct_building(column, short_cells).report.points;
  EXPECT_GE(fine, tall + 60) << tall << " against " << fine;
}

// Footprints whose rings touch, valid in OGC's rules: a courtyard whose corner meets the outer wall, two
// parts meeting at a corner. Every block extruded from them had an edge of four faces there, and the
// building failed with no model at all. The rings are opened by footprint_clearance first, and the
// model keeps the courtyard: its volume is the flat roof's height over the footprint less the hole.
TEST(EndToEnd, a_footprint_whose_rings_touch_is_opened_and_modelled) {
  const Ring2 outline{{0, 0}, {12, 0}, {12, 10}, {0, 10}};
  const auto flat = [](double, double) { return 5.0; };
  BuildingInput courtyard = synthetic_input(outline, flat, 21);
  const Ring2 hole{{6, 0}, {4, 4}, {8, 4}};  // 8 m2, its first vertex on the outer ring
  courtyard.footprint.polygons[0].holes.push_back(hole);
  BuildingInput parts = synthetic_input(outline, flat, 22);
  parts.footprint.polygons = {{{{0, 0}, {6, 0}, {6, 5}, {0, 5}}, {}},
                              {{{6, 5}, {12, 5}, {12, 10}, {6, 10}}, {}}};
  for (BuildingInput* input : {&courtyard, &parts}) {
    std::vector<Point3> kept;
    for (const Point3& p : input->points) {
      bool in = false;
      for (const Polygon2& polygon : input->footprint.polygons)
        in = in || (inside_ring(polygon.outer, {p.x, p.y}) &&
                    std::none_of(polygon.holes.begin(), polygon.holes.end(), [&](const Ring2& h) {
                      return inside_ring(h, {p.x, p.y});
                    }));
      if (in) kept.push_back(p);
    }
    input->points = std::move(kept);
  }
  const double volumes[] = {5.0 * (120.0 - 8.0), 5.0 * 60.0};
  int k = 0;
  for (const BuildingInput* input : {&courtyard, &parts}) {
    const BuildingResult r = reconstruct_building(*input, {});
    ASSERT_TRUE(r.model) << r.report.reason;
    EXPECT_EQ(r.report.status, BuildingStatus::ok) << r.report.reason;
    EXPECT_EQ(r.report.level, ModelLevel::lod22) << r.report.reason;
    EXPECT_NE(r.report.note.find("footprint: its rings touched at 1 place"), std::string::npos)
        << r.report.note;
    EXPECT_NEAR(r.report.volume_lod22, volumes[k], 0.03 * volumes[k]);
    EXPECT_NEAR(r.report.volume_lod12, volumes[k], 0.03 * volumes[k]);
    ++k;
  }
}

// A footprint with a vertex 0.5 mm from the one before it and a spike 1 mm wide (digitising slips; both
// valid polygons) gave a LoD1 block that no validator takes (102 CONSECUTIVE_POINTS_SAME, 104
// RING_SELF_INTERSECTION): `--lod 1.2` left the building with no model. The vertex and the spike's tip
// are dropped first, and the note says so.
TEST(EndToEnd, a_footprint_with_a_doubled_vertex_and_a_hairline_spike_gets_its_lod1_block) {
  const Ring2 outline{{0, 0}, {12, 0}, {12, 8}, {0, 8}};
  BuildingInput input = synthetic_input(
      outline, [](double, double) { return 6.0; }, 31);
  input.footprint.polygons[0].outer = {{0, 0}, {12, 0}, {12.0004, 0.0003}, {12, 8}, {6.001, 8}, {6.0005, 10},
                                       {6, 8}, {0, 8}};
  ReconstructionParams lod12;
  lod12.max_level = ModelLevel::lod12;
  lod12.lods = parse_lod_set("1.2");
  for (const ReconstructionParams& params : {lod12, ReconstructionParams{}}) {
    const BuildingResult r = reconstruct_building(input, params);
    ASSERT_TRUE(r.model) << r.report.reason;
    EXPECT_EQ(r.report.status, BuildingStatus::ok) << r.report.reason;
    EXPECT_NE(
        r.report.note.find("footprint: 2 vertices within 0.002 m of the one before dropped, 1 spike narrower "
                           "than 0.01 m cut off"),
        std::string::npos)
        << r.report.note;
    EXPECT_NEAR(r.report.volume_lod12, 6.0 * 96.0, 0.03 * 6.0 * 96.0);
  }
}

// 200 random star-shaped footprints of 4 to 23 corners, with digitising slips at random corners: a vertex
// doubled within 0.3 mm, a spike 1 mm wide and a third of the radius long, a midpoint on an edge. Without
// tidy_footprint, 151 of these 200 get no LoD1 block at all (`--lod 1.2`); each now gets one.
TEST(EndToEnd, footprints_with_digitising_slips_all_get_a_valid_lod1_block) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  ReconstructionParams lod12;
  lod12.max_level = ModelLevel::lod12;
  lod12.lods = parse_lod_set("1.2");
  int without_model = 0, tidied = 0;
  for (int it = 0; it < 200; ++it) {
    const int corners = 4 + static_cast<int>(rng() % 20);
    Ring2 ring;
    for (int i = 0; i < corners; ++i) {
      const double a = 2 * M_PI * i / corners, r = 4 + 6 * unit(rng);
      ring.push_back({r * std::cos(a), r * std::sin(a)});
      const unsigned slip = rng() % 8;
      const Point2 p = ring.back();
      if (slip == 0) ring.push_back({p.x + 0.0003 * unit(rng), p.y + 0.0003 * unit(rng)});
      if (slip == 1) {
        ring.push_back({p.x * 1.3, p.y * 1.3});
        ring.push_back({p.x + 0.001 * std::sin(a), p.y - 0.001 * std::cos(a)});
      }
      if (slip == 2 && ring.size() >= 2) {
        const Point2 q = ring[ring.size() - 2];
        ring.insert(ring.end() - 1, {(p.x + q.x) / 2, (p.y + q.y) / 2});
      }
    }
    const BuildingInput input = synthetic_input(
        ring, [](double x, double y) { return 5.0 + 0.2 * x + 0.1 * y; }, 300 + it);
    const BuildingResult r = reconstruct_building(input, lod12);
    without_model += !r.model;
    tidied += r.report.note.find("footprint: ") != std::string::npos;
    if (!r.model) ADD_FAILURE() << "footprint " << it << ": " << r.report.reason;
  }
  EXPECT_EQ(without_model, 0);
  EXPECT_GT(tidied, 150);  // most have a slip to tidy
}

// Every tuning number of the pipeline's own steps is a parameter: checked, and in the parameters'
// text that a resume compares.
TEST(Parameters, the_pipelines_own_numbers_are_checked_and_written) {
  const std::string text = parameters_text({});
  for (const char* line : {"outline.gap_spacings = 1.5\n",
                           "outline.wide_gap_spacings = 4\n",
                           "rebuild.max_candidate_faces = 3000\n",
                           "roof_type.flat_angle = 3\n",
                           "planes.small_min_points = 10\n",
                           "max_point_density = 400\n",
                           "full_rung_time_share = 0.59999999999999998\n",
                           "walls.min_escaping_rays = 3\n",
                           "heightmap.resolution_per_spacing = 0.775",
                           "hypothesis.support_cut_mixed = 0.050000000000000003\n",
                           "hypothesis.surface_support.refine = 5\n",
                           "planes.small_divisor = 2\n",
                           "planes.small_points_divisor = 3\n",
                           "planes.few_points_divisor = 4\n",
                           "outline.snap.dominant_window = 10\n",
                           "outline.snap.min_corner_angle = 5\n",
                           "outline.snap.max_shift = 1.5\n",
                           "outline.snap.max_area_change = 0.10000000000000001\n",
                           "selection.gomory_min_columns = 1500\n",
                           "hypothesis.support_cut_min_edge = 0.050000000000000003\n",
                           "hypothesis.support_cut_same_direction = 0.017000000000000001\n",
                           "hypothesis.start_descent_passes = 50\n",
                           "polylines.relocate_pull = 0.001\n",
                           "polylines.corner_min_sine = 0.17000000000000001\n",
                           "polylines.relocate_rounds = 4\n",
                           "rebuild.left_out_plane_divisor = 2\n",
                           "rebuild.left_out_plane_min_points = 4\n",
                           "walls.ray_fan_step = 30\n",
                           "walls.side_probe = 0.050000000000000003\n",
                           "thinning_height_cells = 10\n",
                           "selection.glpk_time_share = 0.5\n",
                           "selection.min_time_limit = 0.10000000000000001\n",
                           "outline.extra_part_plane_share = 0.5\n",
                           "outline.part_roof_share = 0.25\n",
                           "rebuild.left_out_cell_share = 0.5\n",
                           "assemble.planarity_tolerance = 0.002\n"})
    EXPECT_NE(text.find(line), std::string::npos) << line;
  const std::vector<std::pair<std::string, std::function<void(ReconstructionParams&)>>> wrong = {
      {"outline.min_region_area", [](ReconstructionParams& p) { p.outline.min_region_area = 0; }},
      {"outline.gap_spacings", [](ReconstructionParams& p) { p.outline.gap_spacings = NAN; }},
      {"outline.part_gap", [](ReconstructionParams& p) { p.outline.part_gap = -1; }},
      {"rebuild.level_link_height", [](ReconstructionParams& p) { p.rebuild.level_link_height = -0.5; }},
      {"roof_type.flat_angle", [](ReconstructionParams& p) { p.roof_type.flat_angle = 91; }},
      {"full_rung_time_share", [](ReconstructionParams& p) { p.full_rung_time_share = 0; }},
      {"small_min_points", [](ReconstructionParams& p) { p.planes.small_min_points = 2; }},
      {"min_escaping_rays", [](ReconstructionParams& p) { p.walls.min_escaping_rays = 16; }},
      {"support_cut_mixed", [](ReconstructionParams& p) { p.hypothesis.support_cut_mixed = 1; }},
      {"refine must be odd", [](ReconstructionParams& p) { p.hypothesis.surface_support.refine = 4; }},
      {"small_divisor = 0", [](ReconstructionParams& p) { p.planes.small_divisor = 0; }},
      {"small_points_divisor = -1", [](ReconstructionParams& p) { p.planes.small_points_divisor = -1; }},
      {"few_points_divisor = 0", [](ReconstructionParams& p) { p.planes.few_points_divisor = 0; }},
      {"dominant_window must be in (0, 45]",
       [](ReconstructionParams& p) { p.outline.snap.dominant_window = 50; }},
      {"support_cut_min_edge must be >= 0",
       [](ReconstructionParams& p) { p.hypothesis.support_cut_min_edge = -1; }},
      {"support_cut_same_direction must be in [0, 1)",
       [](ReconstructionParams& p) { p.hypothesis.support_cut_same_direction = 1; }},
      {"start_descent_passes must be >= 1",
       [](ReconstructionParams& p) { p.hypothesis.start_descent_passes = 0; }},
      {"rebuild.left_out_plane_divisor must be >= 1",
       [](ReconstructionParams& p) { p.rebuild.left_out_plane_divisor = 0; }},
      {"rebuild.left_out_plane_min_points must be >= 3",
       [](ReconstructionParams& p) { p.rebuild.left_out_plane_min_points = 2; }},
      {"ray_fan_step must be in (0, 45]", [](ReconstructionParams& p) { p.walls.ray_fan_step = 46; }},
      {"side_probe must be > 0", [](ReconstructionParams& p) { p.walls.side_probe = 0; }},
      {"thinning_height_cells must be >= 1", [](ReconstructionParams& p) { p.thinning_height_cells = 0.5; }},
      {"glpk_time_share", [](ReconstructionParams& p) { p.selection.glpk_time_share = 0; }},
      {"min_time_limit", [](ReconstructionParams& p) { p.selection.min_time_limit = -1; }},
      {"outline.extra_part_plane_share must be in [0, 1)",
       [](ReconstructionParams& p) { p.outline.extra_part_plane_share = 1; }},
      {"outline.part_roof_share must be in (0, 1]",
       [](ReconstructionParams& p) { p.outline.part_roof_share = 0; }},
      {"rebuild.left_out_cell_share must be in (0, 1]",
       [](ReconstructionParams& p) { p.rebuild.left_out_cell_share = 1.5; }},
  };
  for (const auto& [name, spoil] : wrong) {
    ReconstructionParams p;
    spoil(p);
    try {
      p.validate();
      ADD_FAILURE() << name << " was not rejected";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}
