// Tests of the batch run's bookkeeping through the `city3d` executable: shards and their merge
// (byte-identical to one process), the journal (kill -9, damaged records), and the output folder
// (temporary files of killed runs, outputs of earlier runs). Also the CityJSON assembly from features.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "city3d/footprint_io.hpp"
#include "city3d/error.hpp"
#include "city3d/model_io.hpp"
#include "city3d/options.hpp"

extern char** environ;

namespace fs = std::filesystem;

namespace {

struct Result {
  int exit_code = -1;
  std::string output;
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

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void write_file(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream ss(text);
  for (std::string line; std::getline(ss, line);) lines.push_back(line);
  return lines;
}

// The report without what is measured rather than computed: each building's CPU and wall seconds (the
// CSV's last two columns, the JSON's "cpu_seconds" and "seconds") and the run's.
std::string without_timings(const std::string& report) {
  static const std::regex csv_seconds(R"(,[0-9]+\.[0-9]{4},[0-9]+\.[0-9]{4}\n)");
  static const std::regex json_seconds(R"("(cpu_)?seconds": [0-9.]+)");
  return std::regex_replace(std::regex_replace(report, csv_seconds, ",S,S\n"), json_seconds, "\"$1seconds\": S");
}

std::set<std::string> files_in(const fs::path& dir) {
  std::set<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) names.insert(e.path().filename().string());
  return names;
}

// Every output of two folders equal: CityJSON, CityJSONSeq, models.obj and every model byte for
// byte; the reports up to their timings.
void expect_same_outputs(const fs::path& a, const fs::path& b) {
  for (const char* f : {"buildings.city.json", "buildings.city.jsonl", "models.obj"}) {
    ASSERT_TRUE(fs::exists(a / f)) << a / f;
    EXPECT_EQ(read_file(a / f), read_file(b / f)) << f;
  }
  for (const char* f : {"report.csv", "report.json"}) {
    const std::string ra = read_file(a / f), rb = read_file(b / f);
    EXPECT_FALSE(ra.empty()) << a / f;
    EXPECT_EQ(without_timings(ra), without_timings(rb)) << f;
  }
  EXPECT_EQ(files_in(a / "models"), files_in(b / "models"));
  for (const std::string& name : files_in(a / "models"))
    EXPECT_EQ(read_file(a / "models" / name), read_file(b / "models" / name)) << name;
}

// Starts the executable in the background (no shell in between), returning its pid.
pid_t spawn(const std::vector<std::string>& arguments, const fs::path& log) {
  std::vector<std::string> args = {CITY3D_EXE};
  args.insert(args.end(), arguments.begin(), arguments.end());
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = -1;
  posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  return pid;
}

class Shards : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("city3d_shards_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  // The sample block (15 footprints) in blocks of 10 m, so that it splits into many blocks.
  std::vector<std::string> sample(const fs::path& out) const {
    const std::string d = CITY3D_SAMPLE_DATA;
    return {"reconstruct", d + "/delft_sample_1.las", d + "/delft_sample_2.las", "-f", d + "/delft_sample_footprints.gpkg",
            "--id-field", "gml_id", "--cityjsonseq", "--merged", "--block-size", "10", "--no-progress", "-o",
            out.string()};
  }
  static std::string join(const std::vector<std::string>& args) {
    std::string s;
    for (const std::string& a : args) s += (s.empty() ? "" : " ") + a;
    return s;
  }
  Result reconstruct(const fs::path& out, const std::string& more = "") const { return run(join(sample(out)) + " " + more); }
  fs::path dir_;
};

}  // namespace

TEST_F(Shards, merge_of_1_2_4_and_7_shards_is_byte_identical_to_one_process) {
  // One block per cropping pass here; the shards crop several blocks of a tile at a time.
  ASSERT_EQ(reconstruct(dir_ / "single", "-j 2 --group-area 0").exit_code, 0);
  for (int n : {1, 2, 4, 7}) {
    SCOPED_TRACE(std::to_string(n) + " shards");
    std::string folders;
    std::size_t buildings = 0;
    for (int k = 1; k <= n; ++k) {
      const fs::path shard = dir_ / ("s" + std::to_string(n) + "_" + std::to_string(k));
      const Result r = reconstruct(shard, "--shard " + std::to_string(k) + "/" + std::to_string(n));
      ASSERT_EQ(r.exit_code, 0) << r.output;
      ASSERT_TRUE(fs::exists(shard / "run.json"));
      buildings += lines_of(read_file(shard / "report.csv")).size() - 1;
      folders += " " + shard.string();
    }
    EXPECT_EQ(buildings, 15u);  // every footprint in exactly one shard
    const fs::path merged = dir_ / ("merged" + std::to_string(n));
    const Result m = run("merge" + folders + " -o " + merged.string());
    ASSERT_EQ(m.exit_code, 0) << m.output;
    expect_same_outputs(dir_ / "single", merged);
  }
  // The merged folder is what one process leaves: a run of the same job into it resumes everything.
  const Result again = reconstruct(dir_ / "merged4", "-v");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_TRUE(contains(again.output, "resume: 15 finished buildings")) << again.output;
  expect_same_outputs(dir_ / "single", dir_ / "merged4");
}

TEST_F(Shards, merge_refuses_a_missing_an_incomplete_and_a_foreign_shard_and_names_it) {
  for (int k = 1; k <= 3; ++k)
    ASSERT_EQ(reconstruct(dir_ / ("s" + std::to_string(k)), "--shard " + std::to_string(k) + "/3").exit_code, 0);
  const std::string s1 = (dir_ / "s1").string(), s2 = (dir_ / "s2").string(), s3 = (dir_ / "s3").string();
  const std::string out = " -o " + (dir_ / "out").string();

  Result r = run("merge " + s1 + " " + s2 + out);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_TRUE(contains(r.output, "shard 3/3 is missing")) << r.output;

  // A shard that has not finished (killed, or still running): no run.json.
  fs::rename(dir_ / "s2" / "run.json", dir_ / "run.json.saved");
  r = run("merge " + s1 + " " + s2 + " " + s3 + out);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(contains(r.output, "shard 2/3 (" + s2 + ") is incomplete")) << r.output;
  fs::rename(dir_ / "run.json.saved", dir_ / "s2" / "run.json");

  // A shard of the same job with other parameters.
  ASSERT_EQ(reconstruct(dir_ / "other", "--shard 3/3 --roof-percentile 50").exit_code, 0);
  r = run("merge " + s1 + " " + s2 + " " + (dir_ / "other").string() + out);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_TRUE(contains(r.output, "shards of different runs")) << r.output;

  // A model file changed after its shard wrote it.
  const std::string name = *files_in(dir_ / "s1" / "models").begin();
  write_file(dir_ / "s1" / "models" / name, read_file(dir_ / "s1" / "models" / name) + "# edited\n");
  r = run("merge " + s1 + " " + s2 + " " + s3 + out);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(contains(r.output, name + " is missing or changed")) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "out" / "run.json"));

  // Rerunning the shard repairs it (the changed model is recomputed), and the merge goes through.
  r = reconstruct(dir_ / "s1", "--shard 1/3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "missing or changed since it was written")) << r.output;
  r = run("merge " + s1 + " " + s2 + " " + s3 + out);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(dir_ / "out" / "run.json"));
}

TEST_F(Shards, run_killed_with_kill_9_resumes_to_the_same_output_from_a_damaged_journal) {
  ASSERT_EQ(reconstruct(dir_ / "whole", "-j 1").exit_code, 0);
  const fs::path resumed = dir_ / "resumed";
  // Kill -9 once the journal holds a few finished buildings.
  std::vector<std::string> args = sample(resumed);
  args.push_back("-j");
  args.push_back("1");
  const pid_t pid = spawn(args, dir_ / "killed.log");
  ASSERT_GT(pid, 0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (lines_of(read_file(resumed / "resume.journal")).size() < 7 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the run finished before it could be killed";
  EXPECT_FALSE(fs::exists(resumed / "run.json"));

  // Damage it: one changed digit in the middle of the first finished building's record (issue 14:
  // it moved a vertex 0.6 m, silently), and one changed byte in the model file of another.
  std::string journal = read_file(resumed / "resume.journal");
  const std::size_t record = journal.find('\n') + 1;
  std::size_t digit = journal.find_first_of("0123456789", record + journal.substr(record).find("vertices"));
  for (int skip = 0; skip < 40; ++skip) digit = journal.find_first_of("0123456789", digit + 1);
  ASSERT_LT(digit, journal.find('\n', record));
  journal[digit] = journal[digit] == '7' ? '3' : '7';
  write_file(resumed / "resume.journal", journal);
  // The model of a building the journal holds (other than the damaged one): models are written
  // before their records, so the folder may hold one more without a record yet.
  std::vector<std::string> models;
  for (const std::string& name : files_in(resumed / "models"))
    if (name.size() > 4 && name.substr(name.size() - 4) == ".obj" &&
        journal.find("\"" + name + "\"", journal.find('\n', record)) != std::string::npos)
      models.push_back(name);
  EXPECT_GE(models.size(), 3u);
  if (models.empty()) models.push_back("none");
  std::string model = read_file(resumed / "models" / models.back());
  if (!model.empty()) model[model.size() / 2] = model[model.size() / 2] == '1' ? '2' : '1';
  if (!model.empty()) write_file(resumed / "models" / models.back(), model);

  const Result r = run(join(sample(resumed)) + " -j 1 -v");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "line 2 of " + (resumed / "resume.journal").string())) << r.output;
  EXPECT_TRUE(contains(r.output, "is damaged (checksum mismatch); its building is recomputed")) << r.output;
  EXPECT_TRUE(contains(r.output, models.back() + " is missing or changed since it was written")) << r.output;
  expect_same_outputs(dir_ / "whole", resumed);
  EXPECT_EQ(lines_of(read_file(resumed / "resume.journal")).size(), 16u);  // header + 15 buildings
}

TEST_F(Shards, temporary_files_of_a_killed_run_are_removed_when_the_rerun_succeeds) {
  const fs::path out = dir_ / "out";
  std::vector<std::string> args = sample(out);
  const pid_t pid = spawn(args, dir_ / "killed.log");
  ASSERT_GT(pid, 0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (lines_of(read_file(out / "resume.journal")).size() < 4 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ::kill(pid, SIGKILL);
  ::waitpid(pid, nullptr, 0);
  // What a run killed in the middle of writing leaves (issue 14: buildings.city.jsonl.tmp-<pid>-0),
  // whether or not this kill happened to land in a write; and files of the user's own.
  const std::string tmp = ".tmp-" + std::to_string(pid) + "-";
  write_file(out / ("buildings.city.jsonl" + tmp + "0"), "{\"type\":\"CityJSON\"");
  write_file(out / ("report.csv" + tmp + "3"), "id,status");
  write_file(out / "models" / ("b1.obj" + tmp + "2"), "# city3d\nv 1");
  write_file(out / "notes.tmp", "mine");
  write_file(out / "models" / "sketch.obj.tmp-draft", "mine");
  const Result r = reconstruct(out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const fs::path& folder : {out, out / "models"})
    for (const std::string& name : files_in(folder))
      EXPECT_FALSE(std::regex_match(name, std::regex(R"(.*\.tmp-[0-9]+-[0-9]+)"))) << folder / name;
  EXPECT_TRUE(fs::exists(out / "notes.tmp"));
  EXPECT_TRUE(fs::exists(out / "models" / "sketch.obj.tmp-draft"));
}

TEST_F(Shards, rerun_with_fewer_buildings_removes_the_models_and_files_the_earlier_run_wrote) {
  const fs::path out = dir_ / "out";
  ASSERT_EQ(reconstruct(out).exit_code, 0);
  ASSERT_EQ(files_in(out / "models").size(), 15u);
  write_file(out / "models" / "my_own.obj", "# not city3d's\n");
  write_file(out / "notes.txt", "mine");
  // The same folder, the footprints of a smaller box, and no CityJSONSeq or merged file this time.
  const std::string d = CITY3D_SAMPLE_DATA;
  const Result r = run("reconstruct " + d + "/delft_sample_1.las " + d + "/delft_sample_2.las -f " + d +
                       "/delft_sample_footprints.gpkg --id-field gml_id --bbox 84990,447530,85030,447580 "
                       "--no-progress -o " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::vector<std::string> rows = lines_of(read_file(out / "report.csv"));
  ASSERT_GT(rows.size(), 2u);
  ASSERT_LT(rows.size(), 16u);
  std::set<std::string> expected = {"my_own.obj"};
  for (std::size_t i = 1; i < rows.size(); ++i) expected.insert(rows[i].substr(0, rows[i].find(',')) + ".obj");
  EXPECT_EQ(files_in(out / "models"), expected);
  EXPECT_TRUE(fs::exists(out / "notes.txt"));
  EXPECT_FALSE(fs::exists(out / "buildings.city.jsonl"));
  EXPECT_FALSE(fs::exists(out / "models.obj"));
  EXPECT_TRUE(fs::exists(out / "buildings.city.json"));
}

TEST(CityJsonAssembly, features_spliced_into_one_file_equal_write_cityjson_of_the_same_objects) {
  using namespace city3d;
  // Two buildings, the second of two shells (BuildingParts), quantised against the same transform.
  auto box = [](const std::string& id, double x, double z0, double z1, int shells) {
    BuildingModel m;
    m.id = id;
    m.origin = {85000.0 + x, 447500.0, 0.0};
    for (int s = 0; s < shells; ++s) {
      const std::uint32_t b = static_cast<std::uint32_t>(m.mesh.vertices.size());
      const double o = 20.0 * s;
      for (double zz : {z0, z1})
        for (auto [px, py] : {std::pair{0.0, 0.0}, {10.0, 0.0}, {10.0, 6.0}, {0.0, 6.0}})
          m.mesh.vertices.push_back({px + o, py, zz});
      m.mesh.faces.push_back({b + 0, b + 3, b + 2, b + 1});
      m.mesh.faces.push_back({b + 4, b + 5, b + 6, b + 7});
      for (std::uint32_t k = 0; k < 4; ++k) m.mesh.faces.push_back({b + k, b + (k + 1) % 4, b + 4 + (k + 1) % 4, b + 4 + k});
    }
    return CityObject{m.id, {{"2.2", m}}, {{"name", std::string("a \"quoted\" id, with [brackets]")}, {"rmse", 0.0005}}};
  };
  const std::vector<CityObject> objects = {box("one", 0.0, 1.25, 7.5, 1), box("two", 40.0, 0.5, 4.0, 2)};
  const fs::path dir = fs::temp_directory_path() / "city3d_assembly";
  fs::create_directories(dir);
  const CityJsonOptions options{"EPSG:28992", 0.001, ""};
  write_cityjson((dir / "direct.city.json").string(), objects, options);
  // write_cityjson's translate: the floor of the minimum corner.
  const Point3 translate{85000.0, 447500.0, 0.0};
  CityJsonAssembler assembler((dir / "spliced.city.json").string(), options, translate);
  for (const CityObject& o : objects) assembler.add(cityjson_feature(o, options, translate));
  assembler.close();
  const std::string direct = read_file(dir / "direct.city.json");
  EXPECT_TRUE(contains(direct, "\"translate\":[85000,447500,0]")) << direct.substr(0, 200);
  EXPECT_EQ(direct, read_file(dir / "spliced.city.json"));
  // A text that is not a CityJSONFeature is refused with its position.
  CityJsonAssembler bad((dir / "bad.city.json").string(), options, translate);
  try {
    bad.add("{\"type\":\"CityJSONFeature\",\"CityObjects\":{\"x\":{\"geometry\":[{\"boundaries\":[[1,2,]]}]}},\"vertices\":[]}");
    ADD_FAILURE() << "no error";
  } catch (const std::exception& e) {
    EXPECT_TRUE(contains(e.what(), "feature 1 is not a CityJSONFeature")) << e.what();
  }
  fs::remove_all(dir);
}

TEST(FootprintSource, regions_read_through_the_spatial_filter_hold_the_scans_footprints_with_its_numbers) {
  using namespace city3d;
  for (const std::string& path : {std::string(CITY3D_SAMPLE_DATA) + "/delft_sample_footprints.gpkg",
                                  std::string(CITY3D_TEST_DATA) + "/footprints/sample_broken.geojson"}) {
    SCOPED_TRACE(path);
    FootprintReadOptions options;
    options.id_field = "gml_id";
    const FootprintSet all = read_footprints(path, options);
    FootprintSource source(path, options);
    std::vector<std::string> scanned;
    const FootprintSet scan = source.scan([&](std::size_t n, const Footprint& f) {
      EXPECT_EQ(n, scanned.size());
      scanned.push_back(f.id);
    });
    // The same footprints in the same order as read_footprints, and the same skipped ones (the
    // broken source has a duplicated id, which only a read of every feature can tell).
    ASSERT_EQ(scanned.size(), all.footprints.size());
    for (std::size_t i = 0; i < scanned.size(); ++i) EXPECT_EQ(scanned[i], all.footprints[i].id);
    ASSERT_EQ(scan.skipped.size(), all.skipped.size());
    EXPECT_TRUE(scan.footprints.empty());
    // A region around everything: every kept footprint, geometry and all, and nothing else.
    Box2 everything;
    everything.add({-1e7, -1e7});
    everything.add({1e7, 1e7});
    const auto found = source.read_box(everything);
    ASSERT_EQ(found.size(), all.footprints.size());
    for (std::size_t i = 0; i < found.size(); ++i) {
      EXPECT_EQ(found[i].first, i);
      EXPECT_EQ(found[i].second.id, all.footprints[i].id);
      ASSERT_EQ(found[i].second.polygons.size(), all.footprints[i].polygons.size());
      EXPECT_EQ(found[i].second.polygons[0].outer.size(), all.footprints[i].polygons[0].outer.size());
    }
    // A small region at a vertex of the first footprint: that footprint, and only footprints whose
    // bounding box meets the region (OGR may also leave out those whose polygon does not).
    const Polygon2& first = all.footprints.front().polygons.front();
    Box2 small;
    small.add(first.outer[0]);
    small.add({first.outer[0].x + 0.5, first.outer[0].y + 0.5});
    std::set<std::size_t> expected;
    for (std::size_t i = 0; i < all.footprints.size(); ++i) {
      Box2 b;
      for (const Polygon2& p : all.footprints[i].polygons)
        for (const Point2& v : p.outer) b.add(v);
      if (b.intersects(small)) expected.insert(i);
    }
    std::set<std::size_t> got;
    for (const auto& [n, f] : source.read_box(small)) got.insert(n);
    EXPECT_LT(expected.size(), all.footprints.size());
    EXPECT_TRUE(got.count(0));
    EXPECT_TRUE(std::includes(expected.begin(), expected.end(), got.begin(), got.end()));
  }
}

TEST(ShardOption, parses_k_of_n_and_rejects_what_is_not_a_shard) {
  using city3d::parse_command_line;
  const char* good[] = {"city3d", "reconstruct", "x.las", "--shard", "2/4"};
  const city3d::RunOptions o = parse_command_line(5, good);
  EXPECT_EQ(o.batch.shard, 2);
  EXPECT_EQ(o.batch.shards, 4);
  for (const char* bad : {"0/4", "5/4", "2", "a/b", "2/0", "-1/3", "1.5/3"}) {
    const char* argv[] = {"city3d", "reconstruct", "x.las", "--shard", bad};
    try {
      parse_command_line(5, argv);
      ADD_FAILURE() << bad;
    } catch (const city3d::ConfigError& e) {
      EXPECT_TRUE(contains(e.what(), "option --shard: expected K/N")) << e.what();
    }
  }
  const char* merge_without_folders[] = {"city3d", "merge", "-o", "out"};
  EXPECT_THROW(parse_command_line(4, merge_without_folders), city3d::ConfigError);
  const char* shard_on_info[] = {"city3d", "info", "x.las", "--shard", "1/2"};
  EXPECT_THROW(parse_command_line(5, shard_on_info), city3d::ConfigError);
  const char* merge[] = {"city3d", "merge", "a", "b", "-o", "out"};
  EXPECT_EQ(parse_command_line(6, merge).inputs.size(), 2u);
}
