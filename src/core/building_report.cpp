// The names of a building's status and model level, as the reports write them.
#include "city3d/building_report.hpp"

namespace city3d {

const char* status_name(BuildingStatus status) {
  switch (status) {
    case BuildingStatus::ok: return "ok";
    case BuildingStatus::fallback: return "fallback";
    case BuildingStatus::skipped: return "skipped";
    case BuildingStatus::failed: return "failed";
    case BuildingStatus::partial: return "partial";
  }
  return "failed";
}

const char* level_name(ModelLevel level) {
  switch (level) {
    case ModelLevel::none: return "none";
    case ModelLevel::lod22: return "LoD2.2";
    case ModelLevel::lod22_footprint_walls: return "LoD2.2 footprint walls";
    case ModelLevel::lod12: return "LoD1.2";
  }
  return "none";
}

const char* cityjson_lod(ModelLevel level) {
  switch (level) {
    case ModelLevel::lod22:
    case ModelLevel::lod22_footprint_walls: return "2.2";
    case ModelLevel::lod12: return "1.2";
    case ModelLevel::none: return "";
  }
  return "";
}

std::optional<BuildingStatus> status_from_name(const std::string& name) {
  for (BuildingStatus s : {BuildingStatus::ok, BuildingStatus::fallback, BuildingStatus::skipped, BuildingStatus::failed,
                           BuildingStatus::partial})
    if (name == status_name(s)) return s;
  return std::nullopt;
}

std::optional<ModelLevel> level_from_name(const std::string& name) {
  for (ModelLevel l : {ModelLevel::none, ModelLevel::lod22, ModelLevel::lod22_footprint_walls, ModelLevel::lod12})
    if (name == level_name(l)) return l;
  return std::nullopt;
}

void add_note(BuildingReport& report, const std::string& note) {
  if (report.note.find(note) == std::string::npos) report.note += (report.note.empty() ? "" : "; ") + note;
}

}  // namespace city3d
