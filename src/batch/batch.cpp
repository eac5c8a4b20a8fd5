// The batch job (run_batch) and the merge of shards (merge_shards). A run is planned before any
// building is reconstructed, from what every shard can compute alike: the footprints are scanned once
// (no geometry kept) and grouped into square blocks, and the blocks, in the order of their home tiles, are
// cut into consecutive runs, one per shard. Consecutive blocks are cropped together (one stream of their tiles). Each
// block's footprints are then read through an OGR spatial filter, its tiles cropped, its buildings
// reconstructed in parallel (reconstruct_building, pipeline.cpp), and each finished building's
// outputs (model file, CityJSONFeature, report rows) recorded in the journal. The run-level files are
// assembled from the journal records alone (finalise.cpp), by a single run and a merge alike.
#include "city3d/batch.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <numeric>
#include <set>
#include <sstream>
#include <system_error>
#include <thread>

#include "batch/advice.hpp"
#include "batch/crop_tiles.hpp"
#include "batch/finalise.hpp"
#include "batch/input_check.hpp"
#include "batch/journal.hpp"
#include "batch/progress.hpp"
#include "city3d/error.hpp"
#include "city3d/log.hpp"
#include "city3d/model_io.hpp"
#include "city3d/point_cloud_io.hpp"
#include "city3d/rings.hpp"
#include "files/atomic_file.hpp"
#include "files/output_folder.hpp"
#include "reports/report.hpp"

namespace city3d {
namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

// Adds a note to a report row (after the pipeline's own, "; "-separated), even when the row has it
// already (add_note, of the pipeline, adds a note only once).
void append_note(BuildingReport& report, const std::string& note) {
  report.note += (report.note.empty() ? "" : "; ") + note;
}

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Files as given, folders expanded to their LAS/LAZ/PLY files sorted by name (deterministic).
std::vector<std::string> expand_inputs(const std::vector<std::string>& inputs) {
  std::vector<std::string> files;
  for (const std::string& in : inputs) {
    std::error_code ec;
    if (fs::is_directory(in, ec)) {
      const std::vector<std::string> found = point_cloud_files_in(in);
      if (found.empty()) throw IoError("input: folder " + in + " holds no .las, .laz or .ply file");
      // Subfolders with point clouds of their own: not read. A city3d output folder (its PLY models
      // are meshes, not points) is not named.
      std::vector<std::string> below;
      const auto city3d_output = [&ec](const fs::path& dir) {
        return fs::exists(dir / "run.json", ec) || fs::exists(dir / "resume.journal", ec);
      };
      for (const auto& entry : fs::directory_iterator(in, ec))
        if (entry.is_directory(ec) && !city3d_output(entry.path()) &&
            !point_cloud_files_in(entry.path().string()).empty() &&
            std::none_of(inputs.begin(), inputs.end(),
                         [&](const std::string& given) { return fs::equivalent(given, entry.path(), ec); }))
          below.push_back(entry.path().filename().string());
      std::sort(below.begin(), below.end());
      std::string names;
      for (const std::string& b : below) names += (names.empty() ? "" : ", ") + b;
      if (!names.empty())
        log_warning("input: the point clouds in subfolders of " + in + " are not read (" + names +
                    "): give them too");
      files.insert(files.end(), found.begin(), found.end());
    } else if (fs::exists(in, ec)) {
      files.push_back(in);
    } else {
      throw IoError("input: cannot open " + in + ": no such file or folder");
    }
  }
  if (files.empty()) throw ConfigError("input: no point-cloud file given");
  return files;
}

/// A single-building cloud's id and, when it is not the file name, how it was made.
struct CloudId {
  BuildingId id;
  std::string note;
};

// Each cloud's id: its file name without extension; when several files share that name, each of
// them gets its path below their common folder, without extension (with it when that is still
// shared: x.las and x.laz side by side). Ids are unique in every output, whatever the files' names.
std::vector<CloudId> cloud_ids(const std::vector<std::string>& files) {
  std::vector<CloudId> ids(files.size());
  std::map<std::string, std::vector<std::size_t>> by_name;
  for (std::size_t i = 0; i < files.size(); ++i) {
    ids[i].id = fs::path(files[i]).stem().string();
    by_name[ids[i].id].push_back(i);
  }
  for (const auto& [name, group] : by_name) {
    if (group.size() < 2) continue;
    std::vector<fs::path> paths;
    for (std::size_t i : group) paths.push_back(fs::absolute(files[i]).lexically_normal());
    fs::path common = paths.front().parent_path();
    for (const fs::path& p : paths)
      while (!common.empty() && p.parent_path().lexically_relative(common).string().rfind("..", 0) == 0)
        common = common.parent_path();
    std::map<std::string, std::size_t> uses;
    for (const fs::path& p : paths) ++uses[p.lexically_relative(common).replace_extension().generic_string()];
    for (std::size_t k = 0; k < group.size(); ++k) {
      fs::path below = paths[k].lexically_relative(common);
      if (uses[fs::path(below).replace_extension().generic_string()] == 1) below.replace_extension();
      ids[group[k]].id = below.generic_string();
      ids[group[k]].note = "id: the path below " + common.string() + ", since " + std::to_string(group.size()) +
                           " files are named " + name;
    }
  }
  // Names that still meet (a path that is another file's name, say): numbered in input order.
  std::map<std::string, std::size_t> seen;
  for (CloudId& c : ids)
    if (const std::size_t n = ++seen[c.id]; n > 1) {
      c.note = (c.note.empty() ? "" : c.note + "; ") + "id: " + c.id + " numbered " + std::to_string(n) +
               ", since another input has that id";
      c.id += "~" + std::to_string(n);
    }
  return ids;
}

Box2 bounds(const Footprint& f) {
  Box2 box;
  for (const Polygon2& p : f.polygons)
    for (const Point2& v : p.outer) box.add(v);
  return box;
}

double ring_area_world(const Ring2& ring) { return std::abs(twice_signed_area(ring)) / 2; }

double area(const Footprint& f) {
  double a = 0.0;
  for (const Polygon2& p : f.polygons) {
    a += ring_area_world(p.outer);
    for (const Ring2& h : p.holes) a -= ring_area_world(h);
  }
  return std::max(a, 0.0);
}

// What the coverage of a footprint (FootprintCoverage) says about its building, in its report row.
// Below `min_coverage` of its area inside the tiles' extents, a building reconstructed from what
// points there are is `partial` (a tile left out: its model is wrong); a skipped or failed one keeps
// its status, with a note. So is one whose own points lie in less than `min_building_coverage` of
// the cells where the tiles have points: the rest of its footprint holds other classes only. Cells
// without any point inside the extents are the data's own gaps (glass roofs, water: 2 of Delft's 160
// footprints have none over half their area), and cells of other classes over less than
// `min_coverage` of it ordinary (trees over a roof, a low part classified otherwise): notes say so.
void apply_coverage(const FootprintCoverage& c, double min_coverage, double min_building_coverage,
                    BuildingReport& r) {
  r.coverage = c.area;
  r.point_coverage = c.cells;
  r.building_coverage = c.building;
  char buf[300];
  const bool area_short = c.area < min_coverage;
  // A footprint without building points says so in its reason already.
  const bool building_short = r.points > 0 && c.building < min_building_coverage;
  if (area_short || building_short) {
    if (!area_short)
      std::snprintf(
          buf, sizeof buf,
          "building points in only %.1f%% of the footprint's cells with points (building_coverage %.3f): "
          "the rest hold other classes only (a tile whose buildings are not classified, or a footprint "
          "larger than the building in the points)",
          100.0 * c.building, c.building);
    else if (c.area > 0)
      std::snprintf(buf, sizeof buf, "partly covered: %.1f%% of the footprint lies outside every tile given (coverage %.3f)",
                    100.0 * (1.0 - c.area), c.area);
    else
      std::snprintf(buf, sizeof buf, "the footprint lies outside every tile given (coverage 0)");
    if (r.status == BuildingStatus::ok || r.status == BuildingStatus::fallback) {
      r.status = BuildingStatus::partial;
      r.reason = buf + (r.reason.empty() ? "" : "; " + r.reason);
      if (r.stage.empty()) r.stage = "coverage";
    } else {
      append_note(r, buf);
    }
    return;
  }
  if (c.cells < min_coverage) {
    std::snprintf(buf, sizeof buf, "no point at all over %.1f%% of the footprint (point_coverage %.3f)",
                  100.0 * (1.0 - c.cells), c.cells);
    append_note(r, buf);
  }
  if (r.points > 0 && c.building < min_coverage) {
    std::snprintf(buf, sizeof buf,
                  "no building point in %.1f%% of the footprint's cells with points (building_coverage %.3f)",
                  100.0 * (1.0 - c.building), c.building);
    append_note(r, buf);
  }
}

// A finished building's record: its model file is written now (and hashed as written), its
// CityJSONFeature and report rows made now, so that the run-level files need nothing but records.
// What a building's CityJSON holds is decided here (and in cityjson_writer.cpp).
// `outline` is the footprint's polygons in world coordinates as read (nullptr for single-building
// clouds), recorded with its attributes when the overview outputs need them.
detail::BuildingRecord make_record(std::uint64_t index, BuildingResult result, const BatchOptions& o,
                                   const detail::RunLayout& layout, const Attributes& footprint_attributes,
                                   const std::vector<Polygon2>* outline) {
  detail::BuildingRecord record;
  record.index = index;
  record.id = result.report.id;
  record.status = result.report.status;
  record.report_csv = detail::report_csv_row(result.report);
  record.report_json = detail::report_json_row(result.report);
  if (outline && (layout.gpkg || layout.html)) {
    record.footprint.emplace();
    record.footprint->id = record.id;
    record.footprint->polygons = *outline;
    record.footprint->attributes = footprint_attributes;
  }
  if (!result.model) return record;
  if (o.per_building_files) {
    record.model_file = model_file_name(result.model->id, o.format);
    const std::string path = (fs::path(o.output_dir) / "models" / record.model_file).string();
    write_model(path, *result.model, {o.format, o.local_coordinates});
    record.model_hash = detail::file_hash(path);
    if (record.model_hash.empty()) throw IoError("write: cannot read back " + path);
  }
  // Every level of detail made, with the footprint's attributes and the report's (report.cpp).
  CityObject object{result.model->id, {},
                    detail::output_attributes(result.report, footprint_attributes, o.timings_in_cityjson)};
  for (const LodModel& lod : result.lods) object.geometries.push_back({lod.lod, lod.model});
  if (object.geometries.empty()) object.geometries.push_back({cityjson_lod(result.report.level), *result.model});
  record.feature = cityjson_feature(object, {layout.crs, layout.scale, "", ""}, layout.translate);
  if (o.merged_file) record.mesh = std::move(*result.model);
  return record;
}

detail::BuildingRecord skipped_record(std::uint64_t index, const SkippedFootprint& s) {
  BuildingReport row;
  row.id = s.id;
  row.status = BuildingStatus::skipped;
  row.stage = "footprints";
  row.reason = s.reason;
  detail::BuildingRecord record;
  record.index = index;
  record.id = s.id;
  record.status = row.status;
  record.report_csv = detail::report_csv_row(row);
  record.report_json = detail::report_json_row(row);
  return record;
}

// What a run does, known before any building is reconstructed and the same in every shard: the
// buildings (in output order), their blocks, and the footprints that were not kept.
struct Plan {
  detail::RunLayout layout;
  std::uint64_t buildings = 0;
  std::vector<Box2> boxes;                          ///< per building (footprints): bounding box
  std::vector<std::vector<std::uint64_t>> blocks;   ///< building indices per block, row-major
  std::vector<double> weights;                      ///< per block: footprint area, or cloud file size
  std::vector<SkippedFootprint> skipped;            ///< indices buildings, buildings + 1, ...
  std::vector<CloudId> cloud_ids;                   ///< single-building clouds: per file
  std::string crs;
};

// Throws IoError when --where or --bbox leave no footprint of a layer that has some: a run of no
// building is a mistake to say before anything is written, not a report without rows.
void check_selection(const FootprintSet& set, const BatchOptions& o) {
  if (set.feature_count > 0 || (o.footprint.attribute_filter.empty() && !o.footprint.bbox)) return;
  std::string filters;
  if (!o.footprint.attribute_filter.empty()) filters = "--where \"" + o.footprint.attribute_filter + "\"";
  if (o.footprint.bbox) {
    const Box2& b = *o.footprint.bbox;
    char box[160];
    std::snprintf(box, sizeof box, "--bbox %.3f,%.3f,%.3f,%.3f", b.min.x, b.min.y, b.max.x, b.max.y);
    filters += (filters.empty() ? "" : " and ") + std::string(box);
    // Reprojected footprints are filtered in the points' CRS, not in their own.
    if (!set.reprojected_from.empty())
      filters += " (in " + set.srs.substr(0, 60) +
                 ", the point clouds' CRS: the footprints are reprojected from " +
                 set.reprojected_from.substr(0, 60) + ")";
  }
  throw IoError("footprints: " + filters + " leave" + (o.footprint.attribute_filter.empty() || !o.footprint.bbox ? "s" : "") +
                " no footprint of the " + std::to_string(set.unfiltered_count) + " features of " + set.path +
                " layer '" + set.layer + "': nothing to reconstruct");
}

// Footprints grouped into square blocks of `extent` metres by their bounding-box centres, blocks in
// row-major order, footprints in input order within a block. extent <= 0: one block.
void make_blocks(Plan& plan, const std::vector<double>& areas, double extent) {
  std::map<std::pair<long long, long long>, std::vector<std::uint64_t>> cells;
  for (std::uint64_t i = 0; i < plan.boxes.size(); ++i) {
    const Box2& box = plan.boxes[i];
    std::pair<long long, long long> key{0, 0};
    if (extent > 0 && !box.empty())
      key = {static_cast<long long>(std::floor((box.min.y + box.max.y) / 2 / extent)),
             static_cast<long long>(std::floor((box.min.x + box.max.x) / 2 / extent))};
    cells[key].push_back(i);
  }
  for (auto& [key, indices] : cells) {
    double weight = 0.0;
    for (std::uint64_t i : indices) weight += areas[i];
    plan.blocks.push_back(std::move(indices));
    plan.weights.push_back(weight);
  }
}

// Blocks in the order of their home tiles (`home`: the tile holding a block's centre), row-major
// within a tile, so that the blocks of one tile are neighbours in this order; the order is cut into
// `shards` consecutive runs of about equal weight (a block goes to the shard its weight's midpoint
// falls in). Every shard computes the same split from the inputs alone, and a shard's blocks share
// few tiles, which its cropping passes read once for several blocks.
std::vector<std::size_t> tile_order(const std::vector<std::size_t>& home) {
  std::vector<std::size_t> order(home.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return home[a] < home[b]; });
  return order;
}

std::vector<int> assign_shards(const std::vector<std::size_t>& order, const std::vector<double>& weights, int shards) {
  double total = 0.0;
  for (double w : weights) total += w;
  std::vector<int> owner(weights.size(), 0);
  double before = 0.0;
  for (std::size_t p = 0; p < order.size(); ++p) {
    // Without weights (no footprint area at all), by position.
    const double w = total > 0 ? weights[order[p]] : 1.0;
    const double sum = total > 0 ? total : static_cast<double>(order.size());
    owner[order[p]] = std::min(shards - 1, static_cast<int>(std::floor(shards * (before + w / 2) / sum)));
    before += w;
  }
  return owner;
}

// "name = value" lines with each number in its shortest form that reads back the same (0.2, not
// parameters_text()'s 0.20000000000000001), for the log.
std::string readable_numbers(const std::string& lines) {
  std::stringstream in(lines);
  std::string out;
  for (std::string line; std::getline(in, line);) {
    const std::size_t eq = line.find(" = ");
    if (eq != std::string::npos) {
      const std::string value = line.substr(eq + 3);
      char* end = nullptr;
      const double v = std::strtod(value.c_str(), &end);
      if (!value.empty() && end && *end == '\0') {
        char buf[32];
        const auto [last, error] = std::to_chars(buf, buf + sizeof buf, v);
        if (error == std::errc()) line = line.substr(0, eq + 3) + std::string(buf, last);
      }
    }
    out += line + "\n";
  }
  return out;
}

detail::RunLayout layout_of(const BatchOptions& o) {
  detail::RunLayout l;
  l.cityjson = o.cityjson;
  l.cityjson_seq = o.cityjson_seq;
  l.merged_file = o.merged_file;
  l.per_building_files = o.per_building_files;
  l.local_coordinates = o.local_coordinates;
  l.format = o.format;
  l.scale = o.reconstruction.output_grid;  // the grid every model was rounded to and checked on
  l.gpkg = o.gpkg;
  l.html = o.html;
  l.tiles3d = o.tiles3d;
  // One text for the same parameters, whoever wrote them (nlohmann's compact form, keys sorted).
  if (!o.parameters.empty()) {
    const nlohmann::json parameters = nlohmann::json::parse(o.parameters, nullptr, false);
    if (parameters.is_discarded() || !parameters.is_object())
      throw ConfigError("batch: the run's parameters are not a JSON object: " + o.parameters.substr(0, 80));
    l.parameters = parameters.dump();
  }
  return l;
}

// The inputs of a run as its outputs' metadata records them: the point clouds (canonical paths, as
// the journal's fingerprint knows them), the footprint source, its layer, id field and filters.
std::string inputs_json(const BatchOptions& o, const std::vector<std::string>& files, const std::string& layer) {
  nlohmann::json clouds = nlohmann::json::array();
  for (const std::string& f : files) {
    std::error_code ec;
    const fs::path canonical = fs::weakly_canonical(f, ec);
    clouds.push_back(ec ? f : canonical.string());
  }
  nlohmann::json inputs = {{"point_clouds", clouds}};
  if (!o.footprints.empty()) {
    std::error_code ec;
    const fs::path canonical = fs::weakly_canonical(o.footprints, ec);
    inputs["footprints"] = ec ? o.footprints : canonical.string();
    inputs["layer"] = layer;
    inputs["id_field"] = o.footprint.id_field.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.footprint.id_field);
  }
  return inputs.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace

namespace {

BatchSummary run_batch_in_folder(const BatchOptions& options) {
  const auto start = Clock::now();
  options.reconstruction.validate();
  options.crop.validate();
  if (options.threads < 1) throw ConfigError("batch: threads must be at least 1");
  if (options.ground_z && !options.footprints.empty())
    throw ConfigError(
        "option --ground-z: the floor height of single-building clouds; with footprints (-f) each "
        "building's ground is measured from the ground points around it, or read with --ground-field");
  const bool sharded = options.shards > 0 || options.shard > 0;
  if (sharded && !(options.shards >= 1 && options.shard >= 1 && options.shard <= options.shards))
    throw ConfigError("batch: shard " + std::to_string(options.shard) + "/" + std::to_string(options.shards) +
                      " does not exist (K/N with 1 <= K <= N)");
  detail::check_output_folder(options.point_clouds, options.footprints, options.output_dir);
  // Tiles given twice are read once; single-building clouds are buildings, each file its own.
  const std::vector<std::string> files = detail::distinct_inputs(
      expand_inputs(options.point_clouds),
      options.footprints.empty() ? detail::Repeats::clouds : detail::Repeats::tiles);
  // Every header is checked before anything is written, and gives the CRS and extents.
  std::vector<PointCloudInfo> infos;
  for (const std::string& f : files) infos.push_back(read_point_cloud_info(f));
  detail::warn_of_meshes(infos);
  detail::warn_of_uncounted_records(infos);
  // Each tile's bounds (a PLY's once its points are streamed), for the footprints' coverage.
  std::vector<Box3> tile_bounds;
  for (const PointCloudInfo& info : infos) tile_bounds.push_back(info.bounds);
  detail::ClassCounts classes;
  classes.counted.assign(files.size(), false);
  // Where each LAZ tile's chunks lie, once a cropping pass has read it (crop_tiles).
  std::vector<ChunkExtents> chunk_extents(files.size());
  log_info("parameters:\n" + readable_numbers(parameters_text(options.reconstruction)));

  // The plan: every building of the run, in output order, and its block.
  Plan plan;
  plan.layout = layout_of(options);
  std::unique_ptr<FootprintSource> source;
  Box2 extent;
  if (!options.footprints.empty()) {
    // Footprints in another CRS than the points are reprojected into theirs (or into the one --crs
    // states, when the points record none).
    FootprintReadOptions read_options = options.footprint;
    const std::string points_crs = detail::common_point_cloud_crs(files, infos);
    read_options.target_srs = points_crs;
    if (points_crs.empty() && !options.crs.empty()) read_options.target_srs = detail::crs_facts(options.crs).horizontal;
    source = std::make_unique<FootprintSource>(options.footprints, read_options);
    std::vector<double> areas;
    const FootprintSet set = source->scan([&](std::size_t, const Footprint& f) {
      plan.boxes.push_back(bounds(f));
      areas.push_back(area(f));
      extent.add(plan.boxes.back().min);
      extent.add(plan.boxes.back().max);
    });
    check_selection(set, options);
    detail::check_footprints_meet_points(plan.boxes, set, infos, points_crs);
    const detail::RunCrs crs = detail::resolve_run_crs(options.crs, points_crs, set.srs, options.footprints);
    plan.layout.crs = crs.name;
    plan.layout.crs_source = crs.source;
    plan.layout.inputs = inputs_json(options, files, set.layer);
    plan.skipped = set.skipped;
    plan.buildings = plan.boxes.size();
    make_blocks(plan, areas, options.block_size);
  } else {
    // Single-building clouds: each cloud is its own block.
    plan.buildings = files.size();
    plan.cloud_ids = cloud_ids(files);
    for (std::uint64_t i = 0; i < files.size(); ++i) {
      std::error_code ec;
      const auto size = fs::file_size(files[i], ec);
      plan.blocks.push_back({i});
      plan.weights.push_back(ec ? 0.0 : static_cast<double>(size));
    }
    const PointCloudInfo& info = infos.front();
    if (!info.bounds.empty()) extent.add({info.bounds.min.x, info.bounds.min.y});
    const detail::RunCrs crs =
        detail::resolve_run_crs(options.crs, detail::common_point_cloud_crs(files, infos), "", "");
    plan.layout.crs = crs.name;
    plan.layout.crs_source = crs.source;
    plan.layout.inputs = inputs_json(options, files, "");
  }
  // A tileset is placed on the globe: it needs to know where the coordinates are.
  if (options.tiles3d && plan.layout.crs.empty())
    throw IoError("3dtiles: the run has no CRS (" +
                  std::string(options.footprints.empty() ? "the point clouds record none"
                                                         : "neither the point clouds nor the footprints record one") +
                  "), so its tileset cannot be placed on the globe: give --crs (AHN: --crs EPSG:7415)");
  // One transform for every building of the run, in the CityJSON file and the CityJSONSeq alike,
  // from what every shard knows: the footprints' corner (or the first cloud's), z = 0.
  if (!extent.empty()) plan.layout.translate = {std::floor(extent.min.x), std::floor(extent.min.y), 0.0};
  plan.layout.records = plan.buildings + plan.skipped.size();

  // Each block's home tile: the first tile whose header bounds hold the centre of the block's
  // footprints (single-building clouds: each cloud its own).
  std::vector<std::size_t> home(plan.blocks.size());
  std::iota(home.begin(), home.end(), 0);
  if (source) {
    std::vector<Box2> tiles;
    for (const std::string& file : files) {
      const PointCloudInfo info = read_point_cloud_info(file);
      Box2 box;
      if (!info.bounds.empty()) box.add({info.bounds.min.x, info.bounds.min.y}), box.add({info.bounds.max.x, info.bounds.max.y});
      tiles.push_back(box);
    }
    for (std::size_t b = 0; b < plan.blocks.size(); ++b) {
      Box2 extent;
      for (std::uint64_t i : plan.blocks[b]) extent.add(plan.boxes[i].min), extent.add(plan.boxes[i].max);
      const Point2 centre{(extent.min.x + extent.max.x) / 2, (extent.min.y + extent.max.y) / 2};
      home[b] = files.size();
      for (std::size_t t = 0; t < tiles.size() && home[b] == files.size(); ++t)
        if (!tiles[t].empty() && centre.x >= tiles[t].min.x && centre.x <= tiles[t].max.x &&
            centre.y >= tiles[t].min.y && centre.y <= tiles[t].max.y)
          home[b] = t;
    }
  }
  // This process's part: every block, or the blocks of its shard, in tile order.
  const std::vector<std::size_t> order = tile_order(home);
  const std::vector<int> owner =
      sharded ? assign_shards(order, plan.weights, options.shards) : std::vector<int>(plan.blocks.size(), 0);
  std::vector<std::size_t> my_blocks;
  for (std::size_t b : order)
    if (owner[b] == (sharded ? options.shard - 1 : 0)) my_blocks.push_back(b);
  // Cropping passes: consecutive blocks in tile order, up to group_area of footprints, so that a tile
  // is streamed once for as many blocks as memory allows. (A pass is not cut where the home tile
  // changes: tiles with fewer footprints than group_area, and the neighbours every block's ground
  // buffer reaches into, would be streamed once per home tile.) Single-building clouds are one pass
  // that the threads share, each thread reading the clouds it takes, the largest files first.
  std::vector<std::vector<std::size_t>> groups;
  double group_weight = 0.0;
  for (std::size_t b : my_blocks) {
    if (groups.empty() || (source && group_weight + plan.weights[b] > options.group_area)) {
      groups.emplace_back();
      group_weight = 0.0;
    }
    groups.back().push_back(b);
    group_weight += plan.weights[b];
  }
  const bool owns_skipped = !sharded || options.shard == 1;
  detail::JournalHeader header;
  header.fingerprint = detail::batch_fingerprint(options, files);
  header.shard = sharded ? options.shard : 0;
  header.shards = sharded ? options.shards : 0;
  header.block_size = sharded ? options.block_size : 0.0;
  header.layout = plan.layout;
  for (std::size_t b : my_blocks) header.expected += plan.blocks[b].size();
  if (owns_skipped) header.expected += plan.skipped.size();
  if (sharded)
    log_info("shard " + std::to_string(options.shard) + "/" + std::to_string(options.shards) + ": " +
             std::to_string(my_blocks.size()) + " of " + std::to_string(plan.blocks.size()) + " blocks, " +
             std::to_string(header.expected) + " of " + std::to_string(plan.layout.records) + " buildings");

  // The output folders only now, when the inputs are known to be usable: a run that fails on its
  // inputs leaves nothing behind.
  detail::prepare_output_folder(options.output_dir, "output");
  if (!options.reconstruction.debug_dir.empty()) detail::prepare_output_folder(options.reconstruction.debug_dir, "debug");
  if (options.per_building_files)
    detail::prepare_output_folder((fs::path(options.output_dir) / "models").string(), "output");
  detail::OutputFolder folder(options.output_dir,
                             detail::run_level_files(plan.layout, sharded ? detail::FinaliseScope::shard
                                                                          : detail::FinaliseScope::whole_run));
  detail::Journal journal(options.output_dir, header, options.resume);
  folder.remove_earlier_models(journal.earlier_models(), journal.earlier_of_the_same_run());

  if (owns_skipped)
    for (std::size_t j = 0; j < plan.skipped.size(); ++j)
      if (!journal.find(plan.buildings + j)) journal.append(skipped_record(plan.buildings + j, plan.skipped[j]));

  // Reconstructs buildings `indices` (global, output order) in parallel; id_of(k) and make_input(k)
  // give the id and input of indices[k], the input made by the worker that reconstructs it.
  const std::size_t total = header.expected;
  detail::Progress progress(options.progress, total, journal.restored());
  // outline_of(k) gives its footprint's polygons in world coordinates (nullptr for clouds).
  // amend(k, result) adds what the run knows about the building beyond its input (coverage, how
  // its id was made). `work` (empty, or one figure per building) orders the buildings for the
  // threads: the most work first, so that no thread is left with a large building while the others
  // have finished (longest processing time first). The outputs do not depend on it: the journal's
  // records are written out in output order.
  auto reconstruct_all = [&](const std::vector<std::uint64_t>& indices,
                             const std::function<BuildingId(std::size_t)>& id_of,
                             const std::function<BuildingInput(std::size_t)>& make_input,
                             const std::function<const std::vector<Polygon2>*(std::size_t)>& outline_of,
                             const std::function<void(std::size_t, BuildingResult&)>& amend,
                             const std::vector<std::size_t>& work) {
    std::vector<std::size_t> order(indices.size());
    std::iota(order.begin(), order.end(), 0);
    if (!work.empty())
      std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return work[a] > work[b]; });
    std::atomic<std::size_t> next{0};
    std::exception_ptr failure;
    std::mutex failure_mutex;
    auto worker = [&]() {
      for (;;) {
        const std::size_t taken = next++;
        if (taken >= order.size()) return;
        const std::size_t k = order[taken];
        {
          std::lock_guard<std::mutex> lock(failure_mutex);
          if (failure) return;
        }
        try {
          if (const detail::RecordRef* finished = journal.find(indices[k])) {
            if (finished->id == id_of(k)) continue;
            log_warning("resume: record " + std::to_string(indices[k]) + " of " + journal.path() + " is for " +
                        finished->id + ", not " + id_of(k) + "; recomputed");
          }
          const BuildingInput input = make_input(k);
          BuildingResult result = reconstruct_building(input, options.reconstruction);
          amend(k, result);
          journal.append(make_record(indices[k], std::move(result), options, plan.layout, input.footprint.attributes,
                                     outline_of(k)));
        } catch (...) {
          // Only input and output errors reach here (reconstruct_building never throws for a bad
          // building): the run cannot go on.
          std::lock_guard<std::mutex> lock(failure_mutex);
          if (!failure) failure = std::current_exception();
          return;
        }
        progress.building_done();
      }
    };
    progress.start_reconstructing();
    std::vector<std::thread> pool;
    try {
      for (std::size_t t = 1; t < static_cast<std::size_t>(options.threads) && t < order.size(); ++t)
        pool.emplace_back(worker);
    } catch (const std::system_error&) {
      // No more threads to be had (a -j beyond the system's limit): the ones started and this one do the
      // work.
    }
    worker();
    for (std::thread& t : pool) t.join();
    progress.stop_reconstructing();
    if (failure) std::rethrow_exception(failure);
  };

  const double reach = options.crop.ground_buffer * options.crop.wide_buffer_factor + 1.0;
  bool ground_class_missing_told = false;
  for (const std::vector<std::size_t>& group : groups) {
    std::vector<std::uint64_t> indices;
    for (std::size_t b : group) indices.insert(indices.end(), plan.blocks[b].begin(), plan.blocks[b].end());
    const bool all_done =
        std::all_of(indices.begin(), indices.end(), [&](std::uint64_t i) { return journal.find(i) != nullptr; });
    if (all_done) continue;
    if (!source) {
      std::vector<std::size_t> work;
      for (std::uint64_t i : indices) work.push_back(static_cast<std::size_t>(plan.weights[i]));
      reconstruct_all(
          indices, [&](std::size_t k) { return plan.cloud_ids[indices[k]].id; },
          [&](std::size_t k) {
            detail::CloudPoints cloud =
                detail::read_building_cloud(files[indices[k]], options.footprint.max_extent);
            BuildingInput input =
                building_from_cloud(plan.cloud_ids[indices[k]].id, cloud.points, options.ground_z);
            if (!cloud.note.empty()) {
              log_warning("input: " + files[indices[k]] + ": " + cloud.note);
              input.footprint.note += (input.footprint.note.empty() ? "" : "; ") + cloud.note;
            }
            return input;
          },
          [](std::size_t) { return nullptr; },
          [&](std::size_t k, BuildingResult& result) {
            const std::string& note = plan.cloud_ids[indices[k]].note;
            if (!note.empty()) append_note(result.report, note);
          },
          work);
      continue;
    }
    // The group's footprints and every other footprint that can reach into their ground buffers
    // (ground points inside any footprint never count as ground), read block by block through a
    // spatial filter, so that a building's input does not depend on how footprints are blocked.
    std::vector<std::pair<std::size_t, Footprint>> found;
    std::vector<Box2> regions;
    for (std::size_t b : group) {
      Box2 region;
      for (std::uint64_t i : plan.blocks[b]) region.add(plan.boxes[i].min), region.add(plan.boxes[i].max);
      region.min = {region.min.x - reach, region.min.y - reach};
      region.max = {region.max.x + reach, region.max.y + reach};
      regions.push_back(region);
      std::vector<std::pair<std::size_t, Footprint>> more = source->read_box(region);
      std::vector<std::pair<std::size_t, Footprint>> merged;
      std::merge(std::make_move_iterator(found.begin()), std::make_move_iterator(found.end()),
                 std::make_move_iterator(more.begin()), std::make_move_iterator(more.end()), std::back_inserter(merged),
                 [](const auto& a, const auto& c) { return a.first < c.first; });
      merged.erase(std::unique(merged.begin(), merged.end(), [](const auto& a, const auto& c) { return a.first == c.first; }),
                   merged.end());
      found = std::move(merged);
    }
    std::vector<Footprint> footprints;
    std::vector<bool> taken(found.size(), false);
    for (std::uint64_t i : indices) {
      const auto it = std::lower_bound(found.begin(), found.end(), i,
                                       [](const auto& entry, std::uint64_t n) { return entry.first < n; });
      if (it == found.end() || it->first != i || taken[static_cast<std::size_t>(it - found.begin())])
        throw IoError("footprints: footprint " + std::to_string(i) + " of " + options.footprints +
                      " was not found again when its block was read (has the source changed?)");
      taken[static_cast<std::size_t>(it - found.begin())] = true;
      footprints.push_back(std::move(it->second));
    }
    for (std::size_t k = 0; k < found.size(); ++k)
      if (!taken[k]) footprints.push_back(std::move(found[k].second));
    // The group's own footprints as read (world coordinates), for the overview outputs' records: the
    // cropper moves them into each building's local frame.
    std::vector<std::vector<Polygon2>> outlines;
    if (plan.layout.gpkg || plan.layout.html)
      for (std::size_t k = 0; k < indices.size(); ++k) outlines.push_back(footprints[k].polygons);
    Cropper cropper(std::move(footprints), options.crop);
    progress.reading(files.size(), indices.size());
    crop_tiles(files, regions, static_cast<unsigned>(options.threads), cropper, tile_bounds, classes,
               chunk_extents);
    // Tiles classified without the ground class (another class number, or none): every floor would be
    // a roof's lowest point, metres above the street, each building's ground_method alone saying so.
    if (!ground_class_missing_told && options.crop.use_classes != ClassUse::never && classes.any &&
        classes.n[options.crop.ground_class] == 0) {
      ground_class_missing_told = true;
      log_warning(
          "crop: the tiles hold no point of the ground class " + std::to_string(options.crop.ground_class) +
          " (--ground-class) but of classes " + detail::classes_present(classes) +
          ": every floor is its building's lowest point, the eaves where only the roof has points; give "
          "the ground class with --ground-class, or --ignore-classes to take the ground from every point "
          "around the footprints");
    }
    // Keep only the group's own inputs (the first indices.size()).
    std::vector<BuildingInput> inputs = cropper.finish();
    inputs.resize(indices.size());
    detail::take_ground_fields(inputs, options.footprint.ground_field, options.ground_field_max_below,
                               options.ground_field_note_distance);
    // The tiles' extents, for the coverage each worker measures before it reconstructs.
    std::vector<Box2> extents;
    std::vector<double> spacings;
    for (std::size_t t = 0; t < files.size(); ++t) {
      extents.push_back(tile_extent(tile_bounds[t], infos[t].point_count));
      spacings.push_back(point_spacing(tile_bounds[t], infos[t].point_count));
    }
    std::vector<FootprintCoverage> coverage(indices.size());
    std::vector<std::size_t> points(indices.size());
    for (std::size_t k = 0; k < indices.size(); ++k) points[k] = inputs[k].points.size();
    reconstruct_all(
        indices, [&](std::size_t k) { return inputs[k].id; },
        [&](std::size_t k) {
          // In the building's local frame, where its footprint and points are.
          const Point3& origin = inputs[k].origin;
          std::vector<Box2> local;
          double spacing = 0.0;
          for (std::size_t t = 0; t < extents.size(); ++t) {
            if (extents[t].empty() || !extents[t].intersects(plan.boxes[indices[k]])) continue;
            Box2 e;
            e.add({extents[t].min.x - origin.x, extents[t].min.y - origin.y});
            e.add({extents[t].max.x - origin.x, extents[t].max.y - origin.y});
            local.push_back(e);
            spacing = std::max(spacing, spacings[t]);
          }
          coverage[k] = footprint_coverage(inputs[k], local, spacing);
          return std::move(inputs[k]);
        },
        [&](std::size_t k) { return outlines.empty() ? nullptr : &outlines[k]; },
        [&](std::size_t k, BuildingResult& result) {
          apply_coverage(coverage[k], options.min_coverage, options.min_building_coverage, result.report);
        },
        points);
  }
  journal.close();
  progress.finish();

  // The run-level files, from the journal's records (as this run wrote them: not parsed again).
  const detail::JournalReader reader(journal.path(), header, journal.take_written());
  std::vector<detail::RecordInJournal> sources;
  for (const detail::RecordRef& ref : reader.records()) sources.push_back({&reader, &ref});
  std::sort(sources.begin(), sources.end(),
            [](const detail::RecordInJournal& a, const detail::RecordInJournal& b) {
              return a.ref->index < b.ref->index;
            });
  if (sources.size() != header.expected)
    throw Error("batch: " + journal.path() + " holds " + std::to_string(sources.size()) + " records, " +
                std::to_string(header.expected) + " expected");
  detail::RunManifest manifest;
  manifest.header = header;
  manifest.records = sources.size();
  BatchSummary summary =
      detail::finalise_run(options.output_dir, plan.layout, sources, seconds_since(start), journal.restored(),
                           sharded ? detail::FinaliseScope::shard : detail::FinaliseScope::whole_run,
                           manifest.outputs, static_cast<unsigned>(options.threads));
  manifest.seconds = seconds_since(start);
  folder.write_manifest(manifest);
  std::string building_classes;  // empty when classes are not used
  if (options.crop.use_classes != ClassUse::never)
    for (std::uint8_t c : options.crop.building_classes)
      building_classes += (building_classes.empty() ? "" : ",") + std::to_string(c);
  summary.advice = detail::advice_for(summary, classes.any ? &classes : nullptr, building_classes);
  return summary;
}

}  // namespace

BatchSummary run_batch(const BatchOptions& options) {
  std::error_code ec;
  const bool existed = fs::exists(options.output_dir, ec);
  try {
    return run_batch_in_folder(options);
  } catch (...) {
    // A run that stops before finishing a building leaves no folder it created (nothing in it but
    // a journal without buildings).
    if (!existed) detail::remove_output_without_results(options.output_dir);
    throw;
  }
}

}  // namespace city3d
