// The overview outputs' records (GeoPackage, report.html) read back from a run's journal records: the
// report.json object of each building and its CityJSONFeature (levels of detail, attributes), so
// that those outputs are, like every run-level file, a function of the records.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/run_outputs.hpp"

namespace city3d {
namespace {

using json = nlohmann::json;

double number_or_nan(const json& o, const char* key) {
  const auto it = o.find(key);
  return it != o.end() && it->is_number() ? it->get<double>() : std::numeric_limits<double>::quiet_NaN();
}

std::string text_of(const json& o, const char* key) {
  const auto it = o.find(key);
  return it != o.end() && it->is_string() ? it->get<std::string>() : std::string();
}

std::size_t count_of(const json& o, const char* key) {
  const auto it = o.find(key);
  return it != o.end() && it->is_number_unsigned() ? it->get<std::size_t>() : 0;
}

BuildingStatus status_of(const std::string& s) { return status_from_name(s).value_or(BuildingStatus::failed); }

ModelLevel level_of(const std::string& s) { return level_from_name(s).value_or(ModelLevel::none); }

// A report row as report_json_row() wrote it (report.cpp).
BuildingReport parse_report(const std::string& text, std::size_t position) {
  json o;
  try {
    o = json::parse(text);
  } catch (const json::exception& e) {
    throw IoError("overview: report row " + std::to_string(position) + " is not JSON: " + e.what());
  }
  BuildingReport r;
  r.id = text_of(o, "id");
  r.status = status_of(text_of(o, "status"));
  r.level = level_of(text_of(o, "level"));
  r.stage = text_of(o, "stage");
  r.reason = text_of(o, "reason");
  r.note = text_of(o, "note");
  r.points = count_of(o, "points");
  r.ground_points = count_of(o, "ground_points");
  r.ground_z = number_or_nan(o, "ground_z");
  r.ground_method = text_of(o, "ground_method");
  r.roof_z = number_or_nan(o, "roof_z");
  r.planes = count_of(o, "planes");
  r.walls = count_of(o, "walls");
  r.candidate_faces = count_of(o, "candidate_faces");
  r.faces = count_of(o, "faces");
  const double rmse = number_or_nan(o, "rmse");
  r.rmse = std::isfinite(rmse) ? rmse : -1.0;
  r.valid = o.value("valid", false);
  r.seconds = number_or_nan(o, "seconds");
  r.lods = text_of(o, "lods");
  r.lods_reconstructed = text_of(o, "lods_reconstructed");
  r.footprint_area = number_or_nan(o, "footprint_area");
  r.point_density = number_or_nan(o, "point_density");
  r.coverage = number_or_nan(o, "coverage");
  r.point_coverage = number_or_nan(o, "point_coverage");
  r.building_coverage = number_or_nan(o, "building_coverage");
  r.h_roof_50p = number_or_nan(o, "h_roof_50p");
  r.h_roof_70p = number_or_nan(o, "h_roof_70p");
  r.h_roof_min = number_or_nan(o, "h_roof_min");
  r.h_roof_max = number_or_nan(o, "h_roof_max");
  r.h_ridge = number_or_nan(o, "h_ridge");
  r.roof_type = text_of(o, "roof_type");
  r.volume_lod12 = number_or_nan(o, "volume_lod12");
  r.volume_lod13 = number_or_nan(o, "volume_lod13");
  r.volume_lod22 = number_or_nan(o, "volume_lod22");
  r.rmse_lod12 = number_or_nan(o, "rmse_lod12");
  r.rmse_lod13 = number_or_nan(o, "rmse_lod13");
  r.rmse_lod22 = number_or_nan(o, "rmse_lod22");
  r.unexplained_points = number_or_nan(o, "unexplained_points");
  r.unexplained_share = number_or_nan(o, "unexplained_share");
  r.unsupported_area = number_or_nan(o, "unsupported_area");
  r.height_excess = number_or_nan(o, "height_excess");
  r.validity_found = text_of(o, "validity_found");
  r.repairs = text_of(o, "repairs");
  return r;
}

SurfaceType surface_of(const std::string& name) {
  if (name == "GroundSurface") return SurfaceType::ground;
  if (name == "WallSurface") return SurfaceType::wall;
  return SurfaceType::roof;
}

// The levels of detail of a CityJSONFeature (every Solid of its CityObjects, BuildingParts included,
// gathered per LoD), vertices back in metres: world = local + origin, origin = the translation.
std::vector<CityGeometry> parse_feature(const std::string& text, double scale, const Point3& translate,
                                        std::size_t position) {
  std::vector<CityGeometry> lods;
  if (text.empty()) return lods;
  json f;
  try {
    f = json::parse(text);
  } catch (const json::exception& e) {
    throw IoError("overview: feature " + std::to_string(position) + " is not JSON: " + e.what());
  }
  const json& vertices = f.at("vertices");
  std::map<std::string, std::size_t> lod_index;
  std::vector<std::map<std::size_t, std::uint32_t>> local;
  for (const auto& [id, object] : f.at("CityObjects").items()) {
    const auto geometries = object.find("geometry");
    if (geometries == object.end()) continue;
    for (const json& g : *geometries) {
      if (g.value("type", "") != "Solid") continue;
      const std::string lod = g.at("lod").is_string() ? g.at("lod").get<std::string>() : g.at("lod").dump();
      const auto [it, fresh] = lod_index.emplace(lod, lods.size());
      if (fresh) {
        lods.push_back({lod, {}});
        lods.back().model.id = f.value("id", "");
        lods.back().model.origin = translate;
        local.emplace_back();
      }
      BuildingModel& m = lods[it->second].model;
      auto& map = local[it->second];
      const json& shell = g.at("boundaries").at(0);
      std::vector<std::string> names;
      const json* values = nullptr;
      if (const auto s = g.find("semantics"); s != g.end()) {
        for (const json& surface : s->at("surfaces")) names.push_back(surface.value("type", ""));
        values = &s->at("values").at(0);
      }
      for (std::size_t k = 0; k < shell.size(); ++k) {
        std::vector<std::uint32_t> face;
        for (const json& v : shell[k].at(0)) {
          const std::size_t i = v.get<std::size_t>();
          const auto [vit, vfresh] = map.emplace(i, static_cast<std::uint32_t>(m.mesh.vertices.size()));
          if (vfresh) {
            const json& q = vertices.at(i);
            m.mesh.vertices.push_back({q[0].get<double>() * scale, q[1].get<double>() * scale, q[2].get<double>() * scale});
          }
          face.push_back(vit->second);
        }
        m.mesh.faces.push_back(std::move(face));
        const bool typed = values && k < values->size() && (*values)[k].is_number_unsigned() &&
                           (*values)[k].get<std::size_t>() < names.size();
        m.surfaces.push_back(typed ? surface_of(names[(*values)[k].get<std::size_t>()]) : SurfaceType::roof);
      }
    }
  }
  std::sort(lods.begin(), lods.end(), [](const CityGeometry& a, const CityGeometry& b) { return a.lod < b.lod; });
  return lods;
}

}  // namespace

OverviewRecord overview_record(const std::string& report_json, const std::string& feature, Footprint footprint,
                               double scale, const Point3& translate, std::size_t position, bool levels) {
  OverviewRecord r;
  r.report = parse_report(report_json, position);
  r.footprint = std::move(footprint.polygons);
  r.footprint_attributes = std::move(footprint.attributes);
  if (!levels) return r;
  try {
    r.lods = parse_feature(feature, scale, translate, position);
  } catch (const json::exception& e) {
    throw IoError("overview: feature " + std::to_string(position) + " (" + r.report.id + ") is not a CityJSONFeature: " +
                  e.what());
  }
  return r;
}

}  // namespace city3d
