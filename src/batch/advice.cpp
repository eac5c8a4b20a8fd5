// The advice of a run's summary (advice.hpp).
#include "batch/advice.hpp"

#include <sstream>

#include "city3d/point_cloud_io.hpp"

namespace city3d::detail {
namespace {

// "12,345,678".
std::string with_thousands(std::uint64_t n) {
  std::string digits = std::to_string(n), out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

}  // namespace

std::string classes_present(const ClassCounts& classes) {
  std::string present;
  for (int c = 0; c < 256; ++c)
    if (classes.n[static_cast<std::size_t>(c)] > 0)
      present += (present.empty() ? "" : ", ") + std::to_string(c) + " (" + las_class_name(c) + ", " +
                 with_thousands(classes.n[static_cast<std::size_t>(c)]) + ")";
  return present;
}

std::string advice_for(const BatchSummary& s, const ClassCounts* classes, const std::string& building_classes) {
  if (s.main_problem.empty()) return {};
  const std::string rows = std::to_string(s.main_problem_rows) + " of " + std::to_string(s.buildings);
  const std::string problem = s.main_problem.substr(s.main_problem.find(": ") + 2);
  if (s.main_problem == "skipped: no building points inside the footprint") {
    if (s.main_problem_outside == s.main_problem_rows)
      return rows + " footprints are skipped: they lie outside every tile given; give the tiles that cover them, "
             "or choose the footprints of these tiles (--bbox, --where)";
    std::string present, wanted;
    bool building_points = false;
    if (classes) {
      present = classes_present(*classes);
      std::stringstream list(building_classes);
      for (std::string c; std::getline(list, c, ',');)
        building_points = building_points || (!c.empty() && classes->n[static_cast<std::size_t>(std::stoi(c)) & 255] > 0);
    }
    if (classes && !building_classes.empty() && !building_points)
      return rows + " footprints are skipped for want of building points: the tiles hold no point of class " +
             building_classes + " (--building-classes) but of classes " + present +
             "; give the building classes with --building-classes, or --ignore-classes to take every point inside "
             "a footprint";
    if (s.main_problem_outside > 0)
      return rows + " footprints are skipped for want of building points; " + std::to_string(s.main_problem_outside) +
             " of them lie outside every tile given: give the tiles that cover them, or choose the footprints of "
             "these tiles (--bbox, --where)";
    return rows + " footprints are skipped for want of building points inside them: are the tiles and the "
           "footprints of the same place (and the points classified as --building-classes says)?";
  }
  if (s.main_problem == "partial: building points in only part of the footprint")
    return rows +
           " buildings are partial: their own points lie in too little of their footprints, the rest holding "
           "other classes only (the building_coverage column): are the tiles' buildings classified as "
           "--building-classes says, and do the footprints outline the buildings in the points?";
  if (s.main_problem.rfind("partial: ", 0) == 0)
    return rows + " buildings are partial: the tiles given cover too little of their footprints (the coverage "
           "column); give the neighbouring tiles too";
  const std::string status = s.main_problem.substr(0, s.main_problem.find(':'));
  // "buildings": the rows are footprints or single-building clouds.
  return rows + (status == "failed" ? " buildings failed" : " buildings are " + status) +
         " for one reason: " + problem + "; see the reason column of " + s.report_path;
}

}  // namespace city3d::detail
