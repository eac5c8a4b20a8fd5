// The batch job (run_batch): footprints, tiles, cropping block by block, buildings reconstructed in
// parallel (reconstruct_building, pipeline.cpp), output written in input order, resume, report.
#include "city3d/batch.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <numeric>
#include <sstream>
#include <thread>

#include "city3d/error.hpp"
#include "city3d/log.hpp"
#include "city3d/model_io.hpp"
#include "city3d/point_cloud_io.hpp"
#include "city3d/run_outputs.hpp"
#include "pipeline/journal.hpp"
#include "pipeline/report.hpp"

namespace city3d {
namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

bool is_point_cloud_file(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".las" || ext == ".laz" || ext == ".ply";
}

// Files as given, folders expanded to their LAS/LAZ/PLY files sorted by name (deterministic).
std::vector<std::string> expand_inputs(const std::vector<std::string>& inputs) {
  std::vector<std::string> files;
  for (const std::string& in : inputs) {
    std::error_code ec;
    if (fs::is_directory(in, ec)) {
      std::vector<std::string> found;
      for (const auto& entry : fs::directory_iterator(in, ec))
        if (entry.is_regular_file() && is_point_cloud_file(entry.path())) found.push_back(entry.path().string());
      if (ec) throw IoError("input: cannot list folder " + in + ": " + ec.message());
      if (found.empty()) throw IoError("input: folder " + in + " holds no .las, .laz or .ply file");
      std::sort(found.begin(), found.end());
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

std::vector<Point3> read_all_points(const std::string& path) {
  PointCloud cloud = read_point_cloud(path, kFieldXyz);
  return std::move(cloud.points);
}

// Streams every tile that overlaps the footprints into the cropper.
void crop_tiles(const std::vector<std::string>& files, const std::vector<Footprint>& footprints,
                const CropParams& params, unsigned threads, Cropper& cropper) {
  Box2 extent;
  for (const Footprint& f : footprints)
    for (const Polygon2& p : f.polygons)
      for (const Point2& v : p.outer) extent.add(v);
  // The cropper's wide ground buffer, and a metre to spare.
  const double margin = params.ground_buffer * params.wide_buffer_factor + 1.0;
  extent.min = {extent.min.x - margin, extent.min.y - margin};
  extent.max = {extent.max.x + margin, extent.max.y + margin};
  for (const std::string& file : files) {
    // Cropping runs between reconstructions, so every thread can decode LAZ chunks meanwhile.
    auto reader = open_point_cloud(file, kFieldClassification, threads);
    const PointCloudInfo& info = reader->info();
    if (!info.bounds.empty()) {
      Box2 tile;
      tile.add({info.bounds.min.x, info.bounds.min.y});
      tile.add({info.bounds.max.x, info.bounds.max.y});
      if (!tile.intersects(extent)) {
        log_info("crop: " + file + " does not overlap the footprints, skipped");
        continue;
      }
    }
    PointCloud chunk;
    std::uint64_t n = 0;
    for (;;) {
      chunk.clear();
      const std::size_t got = reader->read(chunk, 1 << 20);
      if (got == 0) break;
      n += got;
      cropper.add(chunk);
    }
    log_info("crop: " + file + ": " + std::to_string(n) + " points streamed");
  }
}

// Writes each building's outputs as soon as it and every building before it are done, so output
// order (and bytes) never depend on the thread count, and finished work is on disk early.
class OrderedWriter {
 public:
  OrderedWriter(const BatchOptions& options, std::size_t total, const CityJsonOptions& cityjson,
                const std::vector<Footprint>* footprints)
      : options_(options), cityjson_(cityjson), footprints_(footprints), results_(total), ready_(total, false) {
    if (options.per_building_files) fs::create_directories(fs::path(options.output_dir) / "models");
    if (options.cityjson_seq)
      seq_ = std::make_unique<CityJsonSeqWriter>((fs::path(options.output_dir) / "buildings.city.jsonl").string(),
                                                 cityjson_);
  }

  void submit(std::size_t index, BuildingResult result) {
    std::lock_guard<std::mutex> lock(mutex_);
    results_[index] = std::move(result);
    ready_[index] = true;
    while (next_ < results_.size() && ready_[next_]) write(next_, results_[next_]), ++next_;
  }

  void finish() {
    if (seq_) seq_->close();
    const fs::path out(options_.output_dir);
    if (options_.cityjson) write_cityjson((out / "buildings.city.json").string(), objects_, cityjson_);
    if (options_.merged_file) {
      std::vector<BuildingModel> models;
      for (CityObject& o : objects_) models.push_back(o.geometries.back().model);
      write_models((out / ("models" + mesh_extension(options_.format))).string(), models,
                   {options_.format, options_.local_coordinates});
    }
  }

  std::vector<BuildingReport> reports() const {
    std::vector<BuildingReport> rows;
    for (const BuildingResult& r : results_) rows.push_back(r.report);
    return rows;
  }

  /// The written buildings' city objects, in input order (kept when a run-level output needs them).
  const std::vector<CityObject>& objects() const { return objects_; }

 private:
  void write(std::size_t index, BuildingResult& result) {
    if (!result.model) return;
    if (options_.per_building_files) {
      const fs::path file = fs::path(options_.output_dir) / "models" / model_file_name(result.model->id, options_.format);
      write_model(file.string(), *result.model, {options_.format, options_.local_coordinates});
    }
    CityObject object{result.model->id, {},
                      detail::output_attributes(result.report, footprints_ && index < footprints_->size()
                                                                   ? (*footprints_)[index].attributes
                                                                   : Attributes{},
                                                options_.timings_in_cityjson)};
    for (LodModel& lod : result.lods) object.geometries.push_back({lod.lod, std::move(lod.model)});
    if (object.geometries.empty()) object.geometries.push_back({cityjson_lod(result.report.level), *result.model});
    result.model.reset();
    result.lods.clear();
    if (seq_) seq_->add(object);
    if (options_.cityjson || options_.merged_file || options_.gpkg || options_.html) objects_.push_back(std::move(object));
  }

  const BatchOptions& options_;
  CityJsonOptions cityjson_;
  const std::vector<Footprint>* footprints_;
  std::mutex mutex_;
  std::vector<BuildingResult> results_;
  std::vector<bool> ready_;
  std::size_t next_ = 0;
  std::unique_ptr<CityJsonSeqWriter> seq_;
  std::vector<CityObject> objects_;
};

void print_progress(std::size_t done, std::size_t total, Clock::time_point start) {
  const double elapsed = seconds_since(start);
  const double rate = elapsed > 0 ? done / elapsed : 0.0;
  const double left = rate > 0 ? (total - done) / rate : 0.0;
  std::fprintf(stderr, "\rbuildings %zu/%zu  %.1f/s  %.0f s left   ", done, total, rate, left);
  if (done == total) std::fputc('\n', stderr);
  std::fflush(stderr);
}

}  // namespace

namespace {

// Footprints grouped into square blocks of `extent` metres by their bounding-box centres, blocks in
// row-major order, footprints in input order within a block. extent <= 0: one block.
std::vector<std::vector<std::size_t>> spatial_blocks(const std::vector<Footprint>& footprints, double extent) {
  std::map<std::pair<long long, long long>, std::vector<std::size_t>> cells;
  for (std::size_t i = 0; i < footprints.size(); ++i) {
    Box2 box;
    for (const Polygon2& p : footprints[i].polygons)
      for (const Point2& v : p.outer) box.add(v);
    std::pair<long long, long long> key{0, 0};
    if (extent > 0 && !box.empty())
      key = {static_cast<long long>(std::floor((box.min.y + box.max.y) / 2 / extent)),
             static_cast<long long>(std::floor((box.min.x + box.max.x) / 2 / extent))};
    cells[key].push_back(i);
  }
  std::vector<std::vector<std::size_t>> blocks;
  for (auto& [key, indices] : cells) blocks.push_back(std::move(indices));
  return blocks;
}

// The footprints a block must crop with: its own, and every other footprint that can reach into
// their ground buffers (ground points inside any footprint never count as ground), so that a
// building's input does not depend on how footprints are blocked.
std::vector<std::size_t> with_neighbours(const std::vector<Footprint>& footprints, const std::vector<std::size_t>& block,
                                         double reach) {
  Box2 extent;
  for (std::size_t i : block)
    for (const Polygon2& p : footprints[i].polygons)
      for (const Point2& v : p.outer) extent.add(v);
  extent.min = {extent.min.x - reach, extent.min.y - reach};
  extent.max = {extent.max.x + reach, extent.max.y + reach};
  std::vector<bool> in_block(footprints.size(), false);
  for (std::size_t i : block) in_block[i] = true;
  std::vector<std::size_t> result = block;
  for (std::size_t i = 0; i < footprints.size(); ++i) {
    if (in_block[i]) continue;
    Box2 box;
    for (const Polygon2& p : footprints[i].polygons)
      for (const Point2& v : p.outer) box.add(v);
    if (!box.empty() && box.intersects(extent)) result.push_back(i);
  }
  return result;
}

}  // namespace

BatchSummary run_batch(const BatchOptions& options) {
  const auto start = Clock::now();
  options.reconstruction.validate();
  options.crop.validate();
  if (options.threads < 1) throw ConfigError("batch: threads must be at least 1");
  const std::vector<std::string> files = expand_inputs(options.point_clouds);
  log_info("parameters:\n" + parameters_text(options.reconstruction));
  fs::create_directories(options.output_dir);
  detail::Journal journal((fs::path(options.output_dir) / "resume.journal").string(),
                          detail::batch_fingerprint(options, files), options.resume);

  // What to reconstruct: the footprints (cropped from the tiles block by block), or one building
  // per single-building cloud (read when its turn comes).
  FootprintSet set;
  std::vector<BuildingReport> skipped_rows;
  std::string crs;
  Box2 extent;
  if (!options.footprints.empty()) {
    set = read_footprints(options.footprints, options.footprint);
    crs = set.srs.rfind("EPSG:", 0) == 0 ? set.srs : "";
    for (const SkippedFootprint& s : set.skipped) {
      BuildingReport row;
      row.id = s.id;
      row.status = BuildingStatus::skipped;
      row.stage = "footprints";
      row.reason = s.reason;
      skipped_rows.push_back(row);
    }
    for (const Footprint& f : set.footprints)
      for (const Polygon2& p : f.polygons)
        for (const Point2& v : p.outer) extent.add(v);
  }
  const std::size_t total = options.footprints.empty() ? files.size() : set.footprints.size();
  // One transform for the run, known before the first building (CityJSONSeq streams): the
  // footprints' corner, or for clouds their first header's corner, in whole metres; both CityJSON
  // files use it.
  CityJsonOptions cityjson{crs, options.reconstruction.output_grid, {0, 0, 0}, ""};
  if (options.footprints.empty() && !files.empty()) {
    const PointCloudInfo info = read_point_cloud_info(files.front());
    if (!info.bounds.empty()) extent.add({info.bounds.min.x, info.bounds.min.y});
  }
  if (!extent.empty()) cityjson.translate = {std::floor(extent.min.x), std::floor(extent.min.y), 0.0};
  OrderedWriter writer(options, total, cityjson, options.footprints.empty() ? nullptr : &set.footprints);

  // Reconstructs buildings `indices` (global, input order) in parallel; make_input(k) gives the
  // input of indices[k] and is called by the worker that reconstructs it.
  std::atomic<std::size_t> done{0};
  auto reconstruct_all = [&](const std::vector<std::size_t>& indices,
                             const std::function<BuildingInput(std::size_t)>& make_input) {
    std::atomic<std::size_t> next{0};
    std::exception_ptr failure;
    std::mutex failure_mutex;
    auto worker = [&]() {
      for (;;) {
        const std::size_t k = next++;
        if (k >= indices.size()) return;
        {
          std::lock_guard<std::mutex> lock(failure_mutex);
          if (failure) return;
        }
        try {
          BuildingResult result;
          const BuildingId& id = options.footprints.empty() ? fs::path(files[indices[k]]).stem().string()
                                                            : set.footprints[indices[k]].id;
          if (const BuildingResult* finished = journal.find(id)) {
            result = *finished;
          } else {
            result = reconstruct_building(make_input(k), options.reconstruction);
            journal.append(result);
          }
          writer.submit(indices[k], std::move(result));
        } catch (...) {
          // Only input and output errors reach here (reconstruct_building never throws for a bad
          // building): the run cannot go on.
          std::lock_guard<std::mutex> lock(failure_mutex);
          if (!failure) failure = std::current_exception();
          return;
        }
        const std::size_t d = ++done;
        if (options.progress) print_progress(d, total, start);
      }
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < options.threads; ++t) pool.emplace_back(worker);
    worker();
    for (std::thread& t : pool) t.join();
    if (failure) std::rethrow_exception(failure);
  };

  if (options.footprints.empty()) {
    std::vector<std::size_t> indices(files.size());
    std::iota(indices.begin(), indices.end(), 0);
    reconstruct_all(indices, [&](std::size_t k) {
      return building_from_cloud(fs::path(files[k]).stem().string(), read_all_points(files[k]), options.ground_z);
    });
  } else {
    const double reach = options.crop.ground_buffer * options.crop.wide_buffer_factor + 1.0;
    for (const std::vector<std::size_t>& block : spatial_blocks(set.footprints, options.block_size)) {
      const bool all_done = std::all_of(block.begin(), block.end(),
                                        [&](std::size_t i) { return journal.find(set.footprints[i].id) != nullptr; });
      std::vector<BuildingInput> inputs;
      if (!all_done) {
        // Crop with the neighbours too; keep the block's own inputs (the first block.size()).
        const std::vector<std::size_t> members = with_neighbours(set.footprints, block, reach);
        std::vector<Footprint> footprints;
        for (std::size_t i : members) footprints.push_back(set.footprints[i]);
        Cropper cropper(footprints, options.crop);
        crop_tiles(files, footprints, options.crop, static_cast<unsigned>(options.threads), cropper);
        inputs = cropper.finish();
        inputs.resize(block.size());
        for (BuildingInput& in : inputs)
          if (in.footprint.ground_z) {
            // The footprint source knows the floor: it overrides the ground points.
            in.ground_z = *in.footprint.ground_z - in.origin.z;
            in.ground_method = "footprint attribute";
            in.ground_measured = true;
          }
      }
      reconstruct_all(block, [&](std::size_t k) { return std::move(inputs[k]); });
    }
  }
  writer.finish();

  std::vector<BuildingReport> rows = writer.reports();
  rows.insert(rows.end(), skipped_rows.begin(), skipped_rows.end());
  BatchSummary summary;
  summary.buildings = rows.size();
  for (const BuildingReport& r : rows) {
    summary.ok += r.status == BuildingStatus::ok;
    summary.fallback += r.status == BuildingStatus::fallback;
    summary.skipped += r.status == BuildingStatus::skipped;
    summary.failed += r.status == BuildingStatus::failed;
  }
  summary.seconds = seconds_since(start);
  summary.report_path = (fs::path(options.output_dir) / "report.csv").string();
  detail::write_report_csv(summary.report_path, rows);
  detail::write_report_json((fs::path(options.output_dir) / "report.json").string(), rows, summary);
  if (options.gpkg || options.html) {
    const std::vector<BuildingRecord> records =
        building_records(rows, options.footprints.empty() ? nullptr : &set.footprints, writer.objects());
    if (options.gpkg) write_gpkg((fs::path(options.output_dir) / "buildings.gpkg").string(), records, crs);
    if (options.html) write_report_html((fs::path(options.output_dir) / "report.html").string(), records, crs);
  }
  return summary;
}

}  // namespace city3d
