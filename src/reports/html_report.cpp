// report.html: the run overview, one self-contained file (inline CSS, SVG and script, nothing
// fetched): summary, a map of the footprints coloured by status or RMSE, histograms, the worst
// buildings with their reason, and a 3D view of a chosen building. The data is embedded as JSON;
// the page draws itself with plain DOM/SVG/canvas code. The page itself (HTML, CSS, script) is the
// template src/reports/report_page.html, compiled in (report_page.hpp); this file writes the data into it.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/run_outputs.hpp"
#include "core/in_order.hpp"
#include "files/atomic_file.hpp"
#include "reports/report_page.hpp"

namespace city3d {
namespace {

using ordered_json = nlohmann::ordered_json;

// A number of the page's data: v rounded to `decimals` decimals as printf rounds it, held as the
// double nearest that decimal, which nlohmann writes in its shortest round-trip form (12.5, not
// 12.50: a smaller page); a whole number as an integer (8, not 8.0; -0 as 0), null when not finite.
ordered_json page_number(double v, int decimals) {
  if (!std::isfinite(v)) return nullptr;
  char buf[48];
  const int n = std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  double r = v;
  std::from_chars(buf, buf + n, r);
  if (r == std::trunc(r) && std::fabs(r) < 9e15) return static_cast<std::int64_t>(r);
  return r;
}

// The page's text of a value: nlohmann's compact form, then '<', '>' and '&' as \u003c, \u003e and
// \u0026, so that the data cannot close its <script> element ("</script>") or open a comment. They
// can only be inside JSON strings, where the escapes stand for the same characters. A byte that is
// not UTF-8 becomes U+FFFD.
std::string page_json(const ordered_json& value) {
  const std::string text = value.dump(-1, ' ', false, ordered_json::error_handler_t::replace);
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    if (c == '<') out += "\\u003c";
    else if (c == '>') out += "\\u003e";
    else if (c == '&') out += "\\u0026";
    else out += c;
  }
  return out;
}

// One of the run's descriptions (inputs, parameters), a JSON object made by nlohmann in the
// pipeline; an empty object when there is none.
ordered_json run_object(const std::string& text) {
  ordered_json j = ordered_json::parse(text, nullptr, false);
  return j.is_discarded() ? ordered_json::object() : j;
}

// The outline a model stands on, in plan (world coordinates): its ground faces' rings. For a
// single-building cloud, the outline city3d inferred from its points.
std::vector<Ring2> ground_rings(const BuildingModel& m) {
  std::vector<Ring2> rings;
  const std::vector<SurfaceType> types = surface_types(m);
  for (std::size_t f = 0; f < m.mesh.faces.size(); ++f) {
    if (types[f] != SurfaceType::ground) continue;
    Ring2 ring;
    for (std::uint32_t v : m.mesh.faces[f]) ring.push_back({m.mesh.vertices[v].x + m.origin.x, m.mesh.vertices[v].y + m.origin.y});
    rings.push_back(std::move(ring));
  }
  return rings;
}

// Vertex coordinates of models embedded for the 3D view, at most (keeps a 10,000-building page light).
constexpr std::size_t kModelVertexBudget = 150000;

// The records of the first pass kept for the two passes after it instead of being read (and their
// CityJSONFeature parsed) again: up to this many records and vertices of models and footprints in
// all (a kept record of the Delft block holds about 15 KB: at most a few MB whatever the size of
// the run), every record of a city block, the first ones of a large run.
constexpr std::size_t kKeptRecords = 200;
constexpr std::size_t kKeptVertexBudget = 50000;

// Records read together, on several threads (parsing them is most of the page's work): the passes
// below take them in order, a batch at a time.
constexpr std::size_t kReadBatch = 64;

}  // namespace

void write_report_html(const std::string& path, const OverviewSource& records, const RunDescription& run,
                       unsigned threads) {
  const std::string& crs = run.crs;
  // A first pass over the records: the footprints' extent (the map is drawn relative to the run's
  // corner, in centimetres), what orders the models (status, faithfulness both ways, RMSE) and each highest level's size.
  struct Key {
    bool fallback = false;
    double unfaithful = 0.0;  // as the page's worst buildings: both ways, then RMSE
    double rmse = 0.0;
    std::size_t vertices = 0;
    bool model = false;
  };
  std::vector<Key> keys(records.size());
  // Slots for the first kKeptRecords only: an empty slot still takes the size of a record's report
  // (about 0.7 KB), which a run or merge of many buildings would pay for each of them.
  std::vector<std::optional<OverviewRecord>> kept(std::min(records.size(), kKeptRecords));
  const auto kept_record = [&](std::size_t k) { return k < kept.size() && kept[k] ? &*kept[k] : nullptr; };
  std::size_t kept_vertices = 0;
  Box2 extent;
  double outline_size = 0;  // the widest inferred outline (single-building clouds)
  std::size_t outlines = 0;
  const auto read_all = [&](std::size_t k) { return records.at(k, true); };
  detail::for_each_in_order(
      records.size(), threads, kReadBatch, read_all, [&](std::size_t k, OverviewRecord r) {
        for (const Polygon2& p : r.footprint)
          for (const Point2& v : p.outer) extent.add(v);
        if (r.footprint.empty() && !r.lods.empty()) {
          Box2 box;
          for (const Ring2& ring : ground_rings(r.lods.back().model))
            for (const Point2& v : ring) box.add(v);
          if (!box.empty()) {
            outline_size = std::max({outline_size, box.max.x - box.min.x, box.max.y - box.min.y});
            ++outlines;
          }
        }
        const BuildingReport& b = r.report;
        const double unfaithful =
            (std::isfinite(b.unexplained_share) ? b.unexplained_share : 0.0) +
            (std::isfinite(b.unsupported_area) && b.footprint_area > 0 ? b.unsupported_area / b.footprint_area
                                                                       : 0.0);
        keys[k] = {b.status == BuildingStatus::fallback || b.status == BuildingStatus::partial, unfaithful,
                   b.rmse, r.lods.empty() ? 0 : r.lods.back().model.mesh.vertices.size(), !r.lods.empty()};
        std::size_t vertices = 0;
        for (const Polygon2& p : r.footprint) {
          vertices += p.outer.size();
          for (const Ring2& h : p.holes) vertices += h.size();
        }
        for (const CityGeometry& level : r.lods) vertices += level.model.mesh.vertices.size();
        if (k < kKeptRecords && kept_vertices + vertices <= kKeptVertexBudget) {
          kept_vertices += vertices;
          kept[k] = std::move(r);
        }
      });
  const bool have_footprints = !extent.empty();
  const Point2 corner = have_footprints ? Point2{std::floor(extent.min.x), std::floor(extent.min.y)} : Point2{0, 0};
  // Without footprints (single-building clouds, each in a frame of its own) the map shows the
  // outlines inferred from the points side by side: each centred in a cell of a grid, all at one
  // scale, in output order, row by row from the top.
  const bool inferred = !have_footprints && outlines > 0;
  const double cell = std::ceil(outline_size * 1.25 + 1.0);
  const std::size_t columns = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(std::sqrt(double(outlines)))));
  const std::size_t rows = (outlines + columns - 1) / std::max<std::size_t>(1, columns);

  std::string models = "[";
  std::size_t model_count = 0, vertex_budget = kModelVertexBudget;
  // Models of the worst buildings first (failed ones have none), then in order, within the budget.
  std::vector<std::size_t> order(records.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (keys[a].fallback != keys[b].fallback) return keys[a].fallback;
    if (keys[a].unfaithful != keys[b].unfaithful) return keys[a].unfaithful > keys[b].unfaithful;
    return keys[a].rmse > keys[b].rmse;
  });
  std::vector<long> model_of(records.size(), -1);
  // The models shown, chosen from the first pass's sizes.
  std::vector<std::size_t> shown;
  for (std::size_t i : order) {
    if (!keys[i].model || keys[i].vertices > vertex_budget) continue;
    vertex_budget -= keys[i].vertices;
    shown.push_back(i);
  }
  // Only the models shown are read again (those the first pass did not keep).
  const auto read_shown = [&](std::size_t n) {
    return kept_record(shown[n]) ? std::optional<OverviewRecord>() : records.at(shown[n], true);
  };
  detail::for_each_in_order(
      shown.size(), threads, kReadBatch, read_shown, [&](std::size_t n, std::optional<OverviewRecord> read) {
        const std::size_t i = shown[n];
        const OverviewRecord& r = read ? *read : *kept_record(i);
        const BuildingModel& m = r.lods.back().model;
        // Centred on the model's plan-view centre, floor at z = 0.
        Box3 box;
        for (const Point3& p : m.mesh.vertices) box.add(p);
        const Point3 c{(box.min.x + box.max.x) / 2, (box.min.y + box.max.y) / 2, box.min.z};
        ordered_json vertices = ordered_json::array();
        for (const Point3& p : m.mesh.vertices)
          vertices.push_back(
              {page_number(p.x - c.x, 2), page_number(p.y - c.y, 2), page_number(p.z - c.z, 2)});
        ordered_json surfaces = ordered_json::array();
        for (SurfaceType t : surface_types(m)) surfaces.push_back(static_cast<int>(t));
        const ordered_json model = {{"lod", r.lods.back().lod},
                                    {"v", std::move(vertices)},
                                    {"f", m.mesh.faces},
                                    {"s", std::move(surfaces)}};
        models += (model_count ? "," : "") + page_json(model);
        model_of[i] = static_cast<long>(model_count++);
      });
  models += ']';

  // The page, written as it is made: a row per record, one record at a time, then the models.
  detail::AtomicFile file(path);
  std::FILE* out = file.file();
  std::fputs(detail::kReportPageHead, out);
  const ordered_json head = {{"crs", crs},
                             {"crs_source", run.crs_source},
                             {"inputs", run_object(run.inputs)},
                             {"parameters", run_object(run.parameters)},
                             {"inferred", inferred},
                             {"version", CITY3D_VERSION}};
  std::string data = page_json(head);
  data.pop_back();  // its '}': the buildings and the models follow, each building as it is read
  data += ",\"buildings\":[";
  std::fputs(data.c_str(), out);
  std::size_t placed = 0;  // inferred outlines laid out so far
  const auto read_row = [&](std::size_t i) {
    return kept_record(i) ? std::optional<OverviewRecord>() : records.at(i, inferred);
  };
  detail::for_each_in_order(
      records.size(), threads, kReadBatch, read_row, [&](std::size_t i, std::optional<OverviewRecord> read) {
        const OverviewRecord& r = read ? *read : *kept_record(i);
        const BuildingReport& b = r.report;
        ordered_json row = {{"id", b.id},
                            {"s", status_name(b.status)},
                            {"l", level_name(b.level)},
                            {"r", b.reason},
                            {"n", b.note},
                            {"lods", b.lods},
                            {"rt", b.roof_type},
                            {"rmse", page_number(b.rmse >= 0 ? b.rmse : NAN, 4)},
                            {"us", page_number(b.unexplained_share, 4)},
                            {"ua", page_number(b.unsupported_area, 2)},
                            {"he", page_number(b.height_excess, 2)},
                            {"fa", page_number(b.footprint_area, 2)},
                            {"f", b.faces},
                            {"p", b.points},
                            {"t", page_number(b.seconds, 3)},
                            {"h", page_number(b.h_roof_70p, 2)},
                            {"m", model_of[i]}};
        ordered_json rings = ordered_json::array();
        const auto add_ring = [&](const Ring2& ring) {
          ordered_json points = ordered_json::array();
          for (const Point2& v : ring)
            points.push_back({page_number(v.x - corner.x, 2), page_number(v.y - corner.y, 2)});
          rings.push_back(std::move(points));
        };
        for (const Polygon2& p : r.footprint) {
          add_ring(p.outer);
          for (const Ring2& h : p.holes) add_ring(h);
        }
        if (inferred && !r.lods.empty()) {
          std::vector<Ring2> rings = ground_rings(r.lods.back().model);
          Box2 box;
          for (const Ring2& ring : rings)
            for (const Point2& v : ring) box.add(v);
          if (!box.empty()) {
            // The centre of its cell, the grid's top row first (y grows upwards on the map).
            const double cx = (static_cast<double>(placed % columns) + 0.5) * cell;
            const double cy = (static_cast<double>(rows - 1 - placed / columns) + 0.5) * cell;
            const Point2 shift{cx - (box.min.x + box.max.x) / 2, cy - (box.min.y + box.max.y) / 2};
            for (Ring2& ring : rings) {
              for (Point2& v : ring) v = {v.x + shift.x, v.y + shift.y};
              add_ring(ring);
            }
            ++placed;
          }
        }
        row["fp"] = std::move(rings);
        std::fputs(((i ? ",\n" : "\n") + page_json(row)).c_str(), out);
      });
  std::fputs("],\"models\":", out);
  std::fputs(models.c_str(), out);
  std::fputs("}", out);
  std::fputs(detail::kReportPageTail, out);
  file.commit();
}

}  // namespace city3d
