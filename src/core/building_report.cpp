// The names of a building's status and model level, as the reports write them.
#include "city3d/building_report.hpp"

#include <cstddef>
#include <iterator>

namespace city3d {

const char* status_name(BuildingStatus status) {
  // In the enum's order.
  static constexpr const char* kNames[] = {"ok", "fallback", "skipped", "failed", "partial"};
  const auto k = static_cast<std::size_t>(status);
  return k < std::size(kNames) ? kNames[k] : "failed";
}

const char* level_name(ModelLevel level) {
  // In the enum's order.
  static constexpr const char* kNames[] = {"none", "LoD2.2", "LoD2.2 footprint walls", "LoD1.2"};
  const auto k = static_cast<std::size_t>(level);
  return k < std::size(kNames) ? kNames[k] : "none";
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
