// The footprint readers' entry points (an OBJ file or any OGR source), and FootprintSource: footprints read
// block by block through OGR spatial filters, so that a country's footprint layer is never held in memory;
// the scan keeps only (FID, number) pairs.
#include <algorithm>
#include <filesystem>

#include "city3d/error.hpp"
#include "city3d/footprint_io.hpp"
#include "city3d/log.hpp"
#include "footprints/footprint_readers.hpp"

namespace city3d {

struct FootprintSource::Impl {
  std::string path;
  FootprintReadOptions options;
  bool scanned = false;
  /// Held in memory (OBJ files, sources without unique FIDs): every kept footprint, by number.
  bool in_memory = false;
  std::vector<Footprint> footprints;
  /// Read by spatial filter: (FID, number) of every kept footprint, sorted by FID.
  std::vector<std::pair<std::int64_t, std::size_t>> number_of_fid;
};

namespace {
bool is_obj(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".obj";
}

Box2 bounds(const Footprint& f) {
  Box2 box;
  for (const Polygon2& p : f.polygons)
    for (const Point2& v : p.outer) box.add(v);
  return box;
}
}  // namespace

// OBJ by extension (case-insensitive); every other path goes to OGR, which sniffs the format.
FootprintSet read_footprints(const std::string& path, const FootprintReadOptions& options) {
  return is_obj(path) ? detail::read_obj_footprints(path, options)
                      : detail::read_ogr_footprints(path, options);
}

std::vector<FieldSummary> summarise_fields(const std::string& path, const FootprintReadOptions& options,
                                           std::size_t max_features, std::size_t& features) {
  features = 0;
  if (is_obj(path)) return {};
  return detail::summarise_ogr_fields(path, options, max_features, features);
}

std::vector<std::string> list_footprint_layers(const std::string& path) {
  if (is_obj(path)) {
    detail::read_obj_footprints(path, {});  // validates the file like the OGR branch does
    return {"obj"};
  }
  return detail::list_ogr_layers(path);
}

FootprintSource::FootprintSource(std::string path, FootprintReadOptions options) : impl_(new Impl) {
  impl_->path = std::move(path);
  impl_->options = std::move(options);
}

FootprintSource::~FootprintSource() = default;

FootprintSet FootprintSource::scan(const std::function<void(std::size_t, const Footprint&)>& kept) {
  Impl& d = *impl_;
  if (d.scanned) throw Error("footprints: " + d.path + " scanned twice");
  d.scanned = true;
  if (is_obj(d.path)) {
    FootprintSet set = read_footprints(d.path, d.options);
    d.in_memory = true;
    d.footprints = std::move(set.footprints);
    set.footprints.clear();
    for (std::size_t i = 0; i < d.footprints.size(); ++i) kept(i, d.footprints[i]);
    return set;
  }
  std::size_t number = 0;
  bool unique_fids = true;
  const std::function<void(Footprint&&)> sink = [&](Footprint&& f) {
    if (f.fid < 0) unique_fids = false;
    d.number_of_fid.emplace_back(f.fid, number);
    kept(number++, f);
  };
  FootprintSet set = detail::read_ogr_footprints(d.path, d.options, {&sink, false});
  std::sort(d.number_of_fid.begin(), d.number_of_fid.end());
  for (std::size_t i = 1; i < d.number_of_fid.size() && unique_fids; ++i)
    unique_fids = d.number_of_fid[i].first != d.number_of_fid[i - 1].first;
  if (!unique_fids) {
    // Without unique FIDs a footprint read again cannot be told from another: hold them all.
    log_info("footprints: " + d.path + " has no unique feature ids; its footprints are held in memory");
    d.number_of_fid.clear();
    d.in_memory = true;
    d.footprints = detail::read_ogr_footprints(d.path, d.options, {nullptr, true}).footprints;
  }
  return set;
}

std::vector<std::pair<std::size_t, Footprint>> FootprintSource::read_box(const Box2& box) const {
  const Impl& d = *impl_;
  if (!d.scanned) throw Error("footprints: " + d.path + " read before its scan");
  std::vector<std::pair<std::size_t, Footprint>> result;
  if (d.in_memory) {
    for (std::size_t i = 0; i < d.footprints.size(); ++i) {
      const Box2 b = bounds(d.footprints[i]);
      if (!b.empty() && b.intersects(box)) result.emplace_back(i, d.footprints[i]);
    }
    return result;
  }
  // The same filters as the scan, with the region as the spatial filter: a footprint comes back
  // when its bounding box meets the region (read_ogr_footprints checks envelopes) and OGR's own
  // filter lets it through (it may test the polygon itself). Features the scan skipped (duplicated
  // ids whose first holder lies outside the region, invalid polygons) are left out by their FIDs.
  FootprintReadOptions options = d.options;
  options.bbox = box;
  const std::function<void(Footprint&&)> sink = [&](Footprint&& f) {
    const auto it = std::lower_bound(d.number_of_fid.begin(), d.number_of_fid.end(),
                                     std::make_pair(f.fid, std::size_t{0}));
    if (it == d.number_of_fid.end() || it->first != f.fid) return;
    result.emplace_back(it->second, std::move(f));
  };
  detail::read_ogr_footprints(d.path, options, {&sink, true, true});
  std::sort(result.begin(), result.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return result;
}

}  // namespace city3d
