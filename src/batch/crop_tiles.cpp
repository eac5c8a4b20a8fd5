// A cropping pass: each tile that meets the pass's regions streamed into the cropper (crop_tiles.hpp).
#include "batch/crop_tiles.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <future>

#include "batch/input_check.hpp"
#include "city3d/log.hpp"

namespace city3d::detail {

void crop_tiles(const std::vector<std::string>& files, const std::vector<Box2>& regions, unsigned threads,
                Cropper& cropper, std::vector<Box3>& bounds, ClassCounts& classes,
                std::vector<ChunkExtents>& extents) {
  // Small chunks kept from tile to tile: their pages are faulted in once. With threads the next chunk is
  // read while this one is cropped. The crop does not depend on the chunking.
  constexpr std::size_t chunk_points = std::size_t{1} << 16;
  PointCloud chunk, next;
  for (std::size_t t = 0; t < files.size(); ++t) {
    const std::string& file = files[t];
    // Cropping runs between reconstructions, so every thread can decode LAZ chunks meanwhile.
    // A read that learns where the chunks lie reads every point (so its bounds and classes hold for
    // the whole tile); once they are known, only the chunks that meet the regions are decoded.
    const bool whole = extents[t].boxes.empty();
    auto reader = open_point_cloud(file, kFieldClassification, threads, extents[t], regions);
    const PointCloudInfo& info = reader->info();
    if (!info.bounds.empty()) {
      Box2 tile;
      tile.add({info.bounds.min.x, info.bounds.min.y});
      tile.add({info.bounds.max.x, info.bounds.max.y});
      if (std::none_of(regions.begin(), regions.end(), [&](const Box2& r) { return tile.intersects(r); })) {
        log_debug("crop: " + file + " does not overlap the block, skipped");
        continue;
      }
    }
    Box3 seen;
    std::uint64_t n = 0;
    const auto read = [&reader](PointCloud& into) {
      into.clear();
      return reader->read(into, chunk_points);
    };
    for (std::size_t got = read(chunk); got > 0;) {
      std::future<std::size_t> ahead;
      if (threads > 1) ahead = std::async(std::launch::async, read, std::ref(next));
      n += got;
      if (info.bounds.empty() || whole)
        for (const Point3& p : chunk.points) seen.add(p);
      if (!classes.counted[t]) {
        classes.any = classes.any || !chunk.classification.empty();
        for (std::uint8_t c : chunk.classification) ++classes.n[c];
      }
      cropper.add(chunk);
      got = ahead.valid() ? ahead.get() : read(next);
      std::swap(chunk, next);
    }
    if (whole) classes.counted[t] = true;
    if (whole && reader->withheld_points() > 0)
      log_warning(
          "crop: " + file + ": " + std::to_string(reader->withheld_points()) +
          " points flagged withheld are left out (the LAS specification has them treated as deleted)");
    if (info.bounds.empty() && whole) bounds[t] = seen;
    // A header whose bounds leave out some of its points (a file written by a tool that did not update
    // them): the coverage of its footprints is measured from the points, and the user told.
    const double step = std::max({info.scale[0], info.scale[1], info.scale[2]});
    if (!info.bounds.empty() && whole && n > 0 &&
        (seen.min.x < info.bounds.min.x - step || seen.min.y < info.bounds.min.y - step ||
         seen.max.x > info.bounds.max.x + step || seen.max.y > info.bounds.max.y + step)) {
      log_warning("crop: " + file + ": its points span x " + fixed(seen.min.x) + " .. " + fixed(seen.max.x) +
                  ", y " + fixed(seen.min.y) + " .. " + fixed(seen.max.y) +
                  ", beyond its header's bounds x " + fixed(info.bounds.min.x) + " .. " +
                  fixed(info.bounds.max.x) + ", y " + fixed(info.bounds.min.y) + " .. " +
                  fixed(info.bounds.max.y) + ": coverage is measured from the points; a tile whose header " +
                  "misses a block is not read for it (rewrite the header's bounds)");
      bounds[t].add(seen.min);
      bounds[t].add(seen.max);
    }
    // Heights beyond the header's: a z scale or offset changed without the bounds (heights in
    // centimetres read as millimetres are ten times too high, and every model with them).
    if (!info.bounds.empty() && whole && n > 0 &&
        (seen.min.z < info.bounds.min.z - step || seen.max.z > info.bounds.max.z + step)) {
      char text[256];
      std::snprintf(
          text, sizeof text,
          ": its points' heights span z %.3f .. %.3f, beyond its header's bounds z %.3f .. %.3f: check "
          "its z scale and offset (%g, %g) before trusting the models' heights",
          seen.min.z, seen.max.z, info.bounds.min.z, info.bounds.max.z, info.scale[2], info.offset[2] + 0.0);
      log_warning("crop: " + file + text);
    }
    log_info("crop: " + file + ": " + std::to_string(n) + " points streamed");
  }
}

}  // namespace city3d::detail
