// Input checks across files: file identity by device and inode (names, links, folders), copies by
// size and the bytes at both ends, CRS comparison through OGR.
#include "batch/input_check.hpp"

#include <cpl_conv.h>
#include <ogr_spatialref.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <utility>

#include "city3d/error.hpp"
#include "city3d/log.hpp"
#include "points/input_file.hpp"
#include "points/las_reader.hpp"

namespace city3d::detail {
namespace {

constexpr std::size_t kCompareBytes = 64 * 1024;
// Metres: plan coordinates recorded in coarser steps are named (a LAS scale of 1, 32-bit floats of UTM
// coordinates). A quarter of the plane distance the method reads roofs with (0.2 m).
constexpr double kCoarsestCoordinateStep = 0.05;

/// The first and last kCompareBytes of a file (all of it when smaller).
std::string ends_of(const std::string& path, std::uint64_t size) {
  InputFile file(path, "input");
  const std::size_t head = static_cast<std::size_t>(std::min<std::uint64_t>(size, kCompareBytes));
  std::string bytes(head, '\0');
  file.read_at(0, bytes.data(), head);
  if (size > kCompareBytes) {
    const std::size_t tail = static_cast<std::size_t>(std::min<std::uint64_t>(size - kCompareBytes, kCompareBytes));
    std::string end(tail, '\0');
    file.read_at(size - tail, end.data(), tail);
    bytes += end;
  }
  return bytes;
}

}  // namespace

std::string fixed(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", std::fabs(v) <= 360 ? 6 : 3, v);
  return buf;
}

namespace {

std::string short_crs(const std::string& crs) {
  if (crs.empty()) return "no CRS recorded";
  return crs.size() > 60 ? crs.substr(0, 57) + "..." : crs;
}

std::unique_ptr<OGRSpatialReference> parse_crs(const std::string& text, const std::string& file) {
  auto srs = std::make_unique<OGRSpatialReference>();
  if (srs->SetFromUserInput(text.c_str()) != OGRERR_NONE)
    throw IoError("input: " + file + " records a CRS city3d cannot understand: '" + short_crs(text) + "'");
  srs->SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return srs;
}

/// The header facts of a LAS/LAZ file, or nullopt when `path` is no readable LAS/LAZ file (its
/// reader names the problem later).
std::optional<PointCloudInfo> las_header(const std::string& path) {
  try {
    InputFile file(path, "input");
    char signature[4] = {};
    if (file.read_at(0, signature, 4) != 4 || std::memcmp(signature, "LASF", 4) != 0) return std::nullopt;
    return read_las_info(path);
  } catch (const Error&) {
    return std::nullopt;
  }
}

/// True when two headers could be of one tile: the same point count, format, record length,
/// scale and offset, and bounds within half a scale step (LASzip writes the bounds it recomputes
/// from the quantised points, a last bit off: laz/cases/las12_pf0_point10). The LAS version and
/// the VLRs may differ (a LAZ file has one more).
bool same_header_facts(const PointCloudInfo& a, const PointCloudInfo& b) {
  if (a.point_count != b.point_count || a.point_format != b.point_format || a.record_length != b.record_length ||
      a.scale != b.scale || a.offset != b.offset || a.bounds.empty() != b.bounds.empty())
    return false;
  if (a.bounds.empty()) return true;
  const double ax[] = {a.bounds.min.x, a.bounds.min.y, a.bounds.min.z, a.bounds.max.x, a.bounds.max.y, a.bounds.max.z};
  const double bx[] = {b.bounds.min.x, b.bounds.min.y, b.bounds.min.z, b.bounds.max.x, b.bounds.max.y, b.bounds.max.z};
  for (int k = 0; k < 6; ++k)
    if (!(std::fabs(ax[k] - bx[k]) <= std::fabs(a.scale[k % 3]) / 2)) return false;
  return true;
}

/// True when two LAS/LAZ files hold the same point records at both ends.
bool same_end_records(const std::string& a, const std::string& b) {
  try {
    return read_las_end_records(a, kTwinRecords) == read_las_end_records(b, kTwinRecords);
  } catch (const Error&) {
    return false;  // its reader names the problem when the file is read
  }
}

}  // namespace

std::vector<std::string> distinct_inputs(const std::vector<std::string>& files, Repeats repeats) {
  std::vector<std::string> kept;
  std::map<std::pair<dev_t, ino_t>, std::string> by_identity;
  std::multimap<off_t, std::string> by_size;  // kept files, for the copy check
  // Kept LAS/LAZ files by point count, with their headers, for the twin check.
  std::multimap<std::uint64_t, std::pair<PointCloudInfo, std::string>> by_count;
  for (const std::string& f : files) {
    struct stat st {};
    if (::stat(f.c_str(), &st) != 0) {  // the reader names the problem
      kept.push_back(f);
      continue;
    }
    const auto [it, inserted] = by_identity.emplace(std::make_pair(st.st_dev, st.st_ino), f);
    if (!inserted) {
      log_warning("input: " + f + " is the same file as " + it->second + ": read once");
      continue;
    }
    std::string copy_of;
    const auto range = by_size.equal_range(st.st_size);
    if (range.first != range.second) {
      const std::string mine = ends_of(f, static_cast<std::uint64_t>(st.st_size));
      for (auto k = range.first; k != range.second && copy_of.empty(); ++k)
        if (ends_of(k->second, static_cast<std::uint64_t>(st.st_size)) == mine) copy_of = k->second;
    }
    if (!copy_of.empty() && repeats == Repeats::clouds) {
      log_warning("input: " + f + " holds the same bytes as " + copy_of +
                  ": each is a building of its own (without footprints every file is one)");
    } else if (!copy_of.empty()) {
      log_warning("input: " + f + " is a copy of " + copy_of + " (same size and content): read once");
      continue;
    }
    by_size.emplace(st.st_size, f);
    const std::optional<PointCloudInfo> header = repeats == Repeats::tiles ? las_header(f) : std::nullopt;
    if (header) {
      std::string twin_of;
      const auto same = by_count.equal_range(header->point_count);
      for (auto k = same.first; k != same.second && twin_of.empty(); ++k)
        if (same_header_facts(*header, k->second.first) && same_end_records(f, k->second.second))
          twin_of = k->second.second;
      if (!twin_of.empty()) {
        log_warning("input: " + f + " holds the same points as " + twin_of + " (the same header and first and last " +
                    std::to_string(kTwinRecords) + " point records, in another encoding): read once");
        continue;
      }
      by_count.emplace(header->point_count, std::make_pair(*header, f));
    }
    kept.push_back(f);
  }
  return kept;
}

std::string common_point_cloud_crs(const std::vector<std::string>& files, const std::vector<PointCloudInfo>& infos) {
  std::string crs, first_file;
  std::unique_ptr<OGRSpatialReference> first;
  for (std::size_t i = 0; i < infos.size(); ++i) {
    if (infos[i].crs.empty()) continue;
    auto srs = parse_crs(infos[i].crs, files[i]);
    if (!first) {
      if (srs->IsGeographic()) {
        const Box3& b = infos[i].bounds;
        const bool degrees = !b.empty() && std::fabs(b.min.x) <= 360 && std::fabs(b.max.x) <= 360 &&
                             std::fabs(b.min.y) <= 90 && std::fabs(b.max.y) <= 90;
        throw IoError("input: " + files[i] + " declares a geographic CRS (" + short_crs(infos[i].crs) +
                      ", degrees); city3d needs projected coordinates in metres" +
                      (degrees || b.empty() ? std::string(": reproject the points")
                                            : ": its coordinates (x " + fixed(b.min.x) + " .. " + fixed(b.max.x) +
                                                  ") are not degrees either, so its CRS record is probably wrong"));
      }
      first = std::move(srs);
      crs = infos[i].crs;
      first_file = files[i];
    } else if (!srs->IsSame(first.get())) {
      throw IoError("input: " + files[i] + " is in " + short_crs(infos[i].crs) + " but " + first_file + " is in " +
                    short_crs(crs) + ": give point clouds of one CRS");
    }
  }
  return crs;
}

CrsFacts crs_facts(const std::string& text) {
  OGRSpatialReference srs;
  if (text.empty() || srs.SetFromUserInput(text.c_str()) != OGRERR_NONE)
    throw ConfigError("crs: '" + short_crs(text) + "' is no CRS OGR/PROJ understand (give e.g. EPSG:7415, "
                      "EPSG:28992+5709 or WKT)");
  // A height datum alone (EPSG:5709, NAP height) places nothing in plan.
  if (srs.IsVertical() && !srs.IsCompound() && !srs.IsProjected() && !srs.IsGeographic())
    throw ConfigError(
        "crs: '" + short_crs(text) + "' (" + (srs.GetName() ? srs.GetName() : "") +
        ") is a vertical CRS alone: give the horizontal one with it (e.g. EPSG:28992+5709, or EPSG:7415)");
  CrsFacts facts;
  facts.title = srs.GetName() ? srs.GetName() : "";
  facts.vertical = srs.IsCompound() || srs.IsVertical();
  facts.geographic = srs.IsGeographic();
  // The code PROJ's database has for it: itself when given by one, else the best match (a compound
  // of two codes that has one of its own, EPSG:28992+5709 -> EPSG:7415).
  const auto code_of = [](const OGRSpatialReference& s) -> std::string {
    const char* authority = s.GetAuthorityName(nullptr);
    const char* code = s.GetAuthorityCode(nullptr);
    if (authority && code && std::string(authority) == "EPSG") return std::string("EPSG:") + code;
    return {};
  };
  facts.name = code_of(srs);
  if (facts.name.empty()) {
    int count = 0;
    int* confidence = nullptr;
    OGRSpatialReferenceH* matches = srs.FindMatches(nullptr, &count, &confidence);
    for (int i = 0; i < count && facts.name.empty(); ++i)
      if (confidence[i] == 100) facts.name = code_of(*OGRSpatialReference::FromHandle(matches[i]));
    OSRFreeSRSArray(matches);
    CPLFree(confidence);
  }
  OGRSpatialReference plan(srs);
  if (plan.IsCompound()) plan.StripVertical();
  if (plan.IsProjected()) {
    const char* unit = nullptr;
    facts.unit_metres = plan.GetLinearUnits(&unit);
    facts.unit = unit ? unit : "";
  }
  facts.horizontal = code_of(plan);
  if (facts.horizontal.empty()) {
    OGRSpatialReference matched(plan);
    if (matched.AutoIdentifyEPSG() == OGRERR_NONE) facts.horizontal = code_of(matched);
  }
  if (facts.horizontal.empty()) {
    char* wkt = nullptr;
    if (plan.exportToWkt(&wkt) == OGRERR_NONE && wkt) facts.horizontal = wkt;
    CPLFree(wkt);
  }
  // A compound of two codes without one of its own keeps both.
  if (facts.name.empty() && srs.IsCompound()) {
    const OGR_SRSNode* vertical_node = srs.GetAttrNode("VERT_CS");
    OGRSpatialReference height;
    if (vertical_node) {
      char* wkt = nullptr;
      vertical_node->exportToWkt(&wkt);
      if (wkt && height.importFromWkt(wkt) == OGRERR_NONE) {
        const std::string v = code_of(height);
        if (facts.horizontal.rfind("EPSG:", 0) == 0 && v.rfind("EPSG:", 0) == 0)
          facts.name = facts.horizontal + "+" + v.substr(5);
      }
      CPLFree(wkt);
    }
  }
  return facts;
}

RunCrs resolve_run_crs(const std::string& given, const std::string& points_crs, const std::string& footprints_srs,
                       const std::string& footprints_path) {
  const auto described = [](const CrsFacts& f) {
    return (f.name.empty() ? std::string("a CRS without EPSG code") : f.name) +
           (f.title.empty() ? std::string() : " (" + f.title + ")");
  };
  // How a user states the heights' datum, for the messages below: AHN is RD New with NAP heights.
  const auto how_to_state = [](const CrsFacts& f) {
    if (f.horizontal == "EPSG:28992") return std::string("AHN heights are NAP: give --crs EPSG:7415, RD New + NAP height");
    return std::string("give --crs ") + (f.horizontal.rfind("EPSG:", 0) == 0 ? f.horizontal : "HORIZONTAL") +
           "+VERTICAL, VERTICAL the EPSG code of the heights' datum";
  };
  // The CRS the run takes: --crs, else what the point clouds record, else the footprints'.
  const bool from_flag = !given.empty(), from_points = !from_flag && !points_crs.empty();
  const std::string& stated = from_flag ? given : from_points ? points_crs : footprints_srs;
  if (stated.empty()) {
    if (!footprints_path.empty())
      log_warning("input: neither the point clouds nor the footprints " + footprints_path +
                  " record a CRS: the outputs carry none (give --crs)");
    else
      log_info("crs: the point clouds record none: the outputs carry none (give --crs when they are in one)");
    return {};
  }
  const CrsFacts facts = crs_facts(stated);
  if (from_flag) {
    if (facts.geographic)
      throw ConfigError("crs: " + described(facts) + " is geographic (degrees); city3d needs projected coordinates in "
                        "metres");
    if (!points_crs.empty()) {
      // The tiles' own record must agree in plan: --crs states the heights, or a CRS they lack.
      OGRSpatialReference mine, theirs;
      mine.SetFromUserInput(facts.horizontal.c_str());
      theirs.SetFromUserInput(points_crs.c_str());
      if (theirs.IsCompound()) theirs.StripVertical();
      if (!mine.IsSame(&theirs))
        throw IoError("input: --crs " + given + " is " + described(facts) + " but the point clouds record " +
                      short_crs(points_crs) + ": give the CRS they are in, or none to take theirs");
    }
  }
  const RunCrs run = {facts.name.empty() ? stated : facts.name,
                      from_flag ? "--crs" : from_points ? "point clouds" : "footprints"};
  if (std::fabs(facts.unit_metres - 1.0) > 1e-9) {
    std::ostringstream unit;
    unit << facts.unit << ", " << std::setprecision(10) << facts.unit_metres << " m";
    log_warning(
        "crs: " + described(facts) + " has its coordinates in " + unit.str() +
        ": every length city3d takes or gives (its parameters, the heights, areas and volumes of the "
        "report) is read in that unit as if it were the metre; reproject the points and footprints to a "
        "CRS in metres");
  }
  if (from_flag || from_points)
    log_info("crs: " + described(facts) + (from_flag ? ", from --crs" : ", as the point clouds record it") +
             (facts.vertical ? "" : "; its heights have no stated vertical datum (" + how_to_state(facts) + ")"));
  else
    log_warning("input: the point clouds record no CRS: the run takes " + described(facts) + " from the footprints " +
                footprints_path +
                (facts.vertical ? std::string(" (say so with --crs)")
                                : "; the heights then have no stated vertical datum (" + how_to_state(facts) + ")"));
  return run;
}

void check_footprints_meet_points(const std::vector<Box2>& boxes, const FootprintSet& footprints,
                                  const std::vector<PointCloudInfo>& infos, const std::string& points_crs) {
  if (boxes.empty() || infos.empty()) return;
  Box2 points;
  for (const PointCloudInfo& info : infos) {
    if (info.bounds.empty()) return;  // PLY: bounds unknown until read
    points.add({info.bounds.min.x, info.bounds.min.y});
    points.add({info.bounds.max.x, info.bounds.max.y});
  }
  Box2 all;
  for (const Box2& box : boxes) {
    if (box.empty()) continue;
    all.add(box.min);
    all.add(box.max);
    for (const PointCloudInfo& info : infos) {
      Box2 tile;
      tile.add({info.bounds.min.x, info.bounds.min.y});
      tile.add({info.bounds.max.x, info.bounds.max.y});
      if (box.intersects(tile)) return;
    }
  }
  const std::string footprint_crs = footprints.reprojected_from.empty()
                                        ? short_crs(footprints.srs)
                                        : short_crs(footprints.srs) + ", reprojected from " +
                                              short_crs(footprints.reprojected_from);
  std::string hint = "are footprints and points in the same coordinate system?";
  if (points_crs.empty() && !footprints.srs.empty())
    hint = "the point clouds record no CRS: if they are not in " + short_crs(footprints.srs) +
           ", reproject the footprints to theirs (ogr2ogr -t_srs)";
  throw IoError("input: no footprint meets any point cloud: the " + std::to_string(boxes.size()) +
                " footprints of " + footprints.path + " (" + footprint_crs + ") span x " + fixed(all.min.x) +
                " .. " + fixed(all.max.x) + ", y " + fixed(all.min.y) + " .. " + fixed(all.max.y) +
                "; the point clouds' headers (" + short_crs(points_crs) +
                ") give their points as spanning x " + fixed(points.min.x) + " .. " + fixed(points.max.x) +
                ", y " + fixed(points.min.y) + " .. " + fixed(points.max.y) + ": " + hint);
}

void check_output_folder(const std::vector<std::string>& point_clouds, const std::string& footprints,
                         const std::string& output_dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  for (const std::string& in : point_clouds)
    if (fs::is_directory(in, ec) && fs::equivalent(in, output_dir, ec))
      throw ConfigError("input: " + in +
                        " is both a folder of point clouds and the output folder (-o): a later run "
                        "would read the models written there as points; give another output folder");
  static const char* const kWritten[] = {
      "report.csv", "report.json",         "report.html",         "run.json",
      "models.obj", "models.ply",          "city3d.mtl",          "buildings.gpkg",
      "3dtiles",    "buildings.city.json", "buildings.city.jsonl"};
  // An input where the run writes (footprints named buildings.gpkg in the output folder, a cloud in
  // its models/): the run would replace or remove it.
  std::vector<std::string> inputs = point_clouds;
  if (!footprints.empty()) inputs.push_back(footprints);
  for (const std::string& in : inputs) {
    const fs::path path(in), folder = fs::absolute(path).parent_path();
    const bool named_as_output = std::any_of(std::begin(kWritten), std::end(kWritten),
                                             [&](const char* name) { return path.filename() == name; });
    if ((named_as_output && fs::equivalent(folder, output_dir, ec)) ||
        fs::equivalent(folder, fs::path(output_dir) / "models", ec))
      throw ConfigError("input: " + in + " is where the run writes its own " +
                        (named_as_output ? path.filename().string() : std::string("models")) + " (-o " +
                        output_dir + "): it would be replaced; give another output folder");
  }
  if (!fs::is_directory(output_dir, ec) || fs::exists(fs::path(output_dir) / "resume.journal", ec)) return;
  std::string names;
  for (const char* name : kWritten)
    if (fs::exists(fs::path(output_dir) / name, ec)) names += (names.empty() ? "" : ", ") + std::string(name);
  const fs::path models = fs::path(output_dir) / "models";
  if (fs::is_directory(models, ec) && !fs::is_empty(models, ec))
    names += (names.empty() ? "" : ", ") + std::string("models/");
  if (!names.empty())
    throw IoError(
        "output: folder " + output_dir + " holds " + names + " but no resume.journal: no city3d run is " +
        "resumed there, and a run would replace them; give an empty or new folder (-o), or remove them");
}

void warn_of_meshes(const std::vector<PointCloudInfo>& infos) {
  for (const PointCloudInfo& info : infos)
    if (info.mesh_faces > 0)
      log_warning("input: " + info.path + " is a mesh of " + std::to_string(info.mesh_faces) +
                  " faces (a model?), not a point cloud: its " + std::to_string(info.point_count) +
                  " vertices are read as points");
}

void warn_of_uncounted_records(const std::vector<PointCloudInfo>& infos) {
  for (const PointCloudInfo& info : infos)
    if (info.format != "PLY" && std::max(info.scale[0], info.scale[1]) > kCoarsestCoordinateStep)
      log_warning("input: " + info.path + ": its x and y are recorded in steps of " +
                  fixed(std::max(info.scale[0], info.scale[1])) +
                  " m (the LAS scale): the models can be no finer (a scale written wrong?)");
  for (const PointCloudInfo& info : infos)
    if (info.uncounted_records > 0)
      log_warning("input: " + info.path + ": its header counts " + std::to_string(info.point_count) +
                  " points, but " + std::to_string(info.uncounted_records) +
                  " more records follow them (a header not rewritten when points were added?): only the " +
                  std::to_string(info.point_count) + " counted are read");
}

CloudPoints read_building_cloud(const std::string& path, double max_extent) {
  // LAS classes only: a PLY's class or label property follows a scheme of its own (DALES: 2 is vegetation).
  const PointCloudInfo info = read_point_cloud_info(path);
  const bool las = info.format != "PLY";
  PointCloud cloud = read_point_cloud(path, las ? kFieldXyz | kFieldClassification : kFieldXyz);
  // LAS noise (7, low point; 18, high noise) is no part of the building: a noise point metres below the
  // rest was its floor.
  std::size_t noise = 0;
  if (!cloud.classification.empty()) {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < cloud.points.size(); ++i) {
      const std::uint8_t c = cloud.classification[i];
      if (c == 7 || c == 18) continue;
      cloud.points[kept] = cloud.points[i];
      cloud.classification[kept++] = c;
    }
    noise = cloud.points.size() - kept;
    cloud.points.resize(kept);
    cloud.classification.resize(kept);
  }
  const auto ground =
      static_cast<std::size_t>(std::count(cloud.classification.begin(), cloud.classification.end(), 2));
  CloudPoints out{std::move(cloud.points), {}};
  if (noise > 0) out.note = std::to_string(noise) + " points classified noise (7, 18) left out";
  if (ground * 10 > out.points.size())
    out.note +=
        std::string(out.note.empty() ? "" : "; ") + std::to_string(ground) + " of its " +
        std::to_string(out.points.size()) +
        " points are classified ground: a tile rather than one building's cloud? (give its footprints "
        "with -f; city3d info lists its classes)";
  // Points far below all the others (a nodata height, a stray echo) would be the floor: the cloud's
  // lowest point, unless --ground-z. The dev sets' lowest points lie at most 5.6 m below their next
  // ones (city3d_dev_large's AHN3/12302: the foot of a wall under its roof).
  if (out.points.size() >= 2) {
    std::vector<double> z;
    z.reserve(out.points.size());
    for (const Point3& p : out.points) z.push_back(p.z);
    const std::size_t rank = std::max<std::size_t>(1, z.size() / 1000);
    std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(rank), z.end());
    const double reference = z[rank],
                 lowest = *std::min_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(rank));
    constexpr double kStrayDrop = 10.0;  // metres below the lowest 0.1% of the points
    if (lowest < reference - kStrayDrop) {
      const auto strays = std::count_if(out.points.begin(), out.points.end(),
                                        [&](const Point3& p) { return p.z < reference - kStrayDrop; });
      char text[200];
      std::snprintf(
          text, sizeof text,
          "%td point%s more than %.0f m below all but the lowest 0.1%% (down to z %.3f, the rest from %.3f): "
          "strays? the floor is the lowest point unless --ground-z",
          strays, strays == 1 ? "" : "s", kStrayDrop, lowest, reference);
      out.note += std::string(out.note.empty() ? "" : "; ") + text;
    }
  }
  // Millimetres read as metres: the building is kilometres wide (as no footprint may be:
  // --max-footprint-size).
  {
    Box3 span;
    for (const Point3& p : out.points) span.add(p);
    const double width = std::max(span.max.x - span.min.x, span.max.y - span.min.y);
    if (out.points.size() >= 2 && width > max_extent) {
      char text[200];
      std::snprintf(
          text, sizeof text,
          "it spans %.0f m in plan, more than any building (--max-footprint-size %.0f m): coordinates in "
          "millimetres or centimetres? city3d needs metres",
          width, max_extent);
      out.note += std::string(out.note.empty() ? "" : "; ") + text;
    }
  }
  // Coordinates recorded more coarsely than the method reads a roof (its plane distance is 0.2 m): a
  // LAS scale of 1 (metres), or 32-bit floats of large coordinates (UTM northings step by 0.5 m).
  {
    double step = las ? std::max(info.scale[0], info.scale[1]) : 0.0;
    if (!las && info.single_precision_xy) {
      double reach = 0.0;
      for (const Point3& p : out.points) reach = std::max({reach, std::fabs(p.x), std::fabs(p.y)});
      if (reach > 0) step = std::ldexp(1.0, std::ilogb(reach) - 23);  // a float's step at that magnitude
    }
    if (step > kCoarsestCoordinateStep) {
      char text[200];
      std::snprintf(text, sizeof text,
                    "its x and y are recorded in steps of %g m (%s): the model can be no finer", step,
                    las ? "the LAS scale"
                        : "32-bit floats at these coordinates; doubles, or a cloud near 0, keep them");
      out.note += std::string(out.note.empty() ? "" : "; ") + text;
    }
  }
  // Longitude and latitude read as metres: the building is a few thousandths wide.
  Box3 box;
  for (const Point3& p : out.points) box.add(p);
  if (out.points.size() >= 3 && box.min.x >= -180 && box.max.x <= 180 && box.min.y >= -90 &&
      box.max.y <= 90 && box.max.x - box.min.x < 0.01 && box.max.y - box.min.y < 0.01)
    out.note += std::string(out.note.empty() ? "" : "; ") +
                "its x and y span less than 0.01 within -180..180 and "
                "-90..90: degrees of longitude and latitude? city3d needs metres (reproject the cloud)";
  return out;
}

void take_ground_fields(std::vector<BuildingInput>& inputs, const std::string& field, double max_below,
                        double note_distance) {
  std::size_t ignored = 0, far_taken = 0;
  std::string first_ignored, first_far;
  for (BuildingInput& in : inputs) {
    if (!in.footprint.ground_z) continue;
    const double field_z = *in.footprint.ground_z - in.origin.z;
    std::vector<double> z;
    z.reserve(in.points.size());
    for (const Point3& p : in.points) z.push_back(p.z);
    if (!z.empty() && field_z > percentile(z, 50.0)) {
      std::ostringstream note;
      note << "ground field '" << field << "' (" << *in.footprint.ground_z
           << ") above half of the building's points: the ground is " << in.ground_method;
      in.footprint.note += (in.footprint.note.empty() ? "" : "; ") + note.str();
      if (ignored++ == 0) first_ignored = in.id + ": " + note.str();
      continue;
    }
    if (in.ground_measured && field_z < in.ground_z - max_below) {
      std::ostringstream note;
      note << "ground field '" << field << "' (" << *in.footprint.ground_z << ") more than " << max_below
           << " m below the ground measured around it (" << in.ground_z + in.origin.z << "): the ground is "
           << in.ground_method;
      in.footprint.note += (in.footprint.note.empty() ? "" : "; ") + note.str();
      if (ignored++ == 0) first_ignored = in.id + ": " + note.str();
      continue;
    }
    if (in.ground_measured && std::fabs(field_z - in.ground_z) > note_distance) {
      std::ostringstream note;
      note << std::fixed << std::setprecision(2) << "ground field '" << field << "' ("
           << *in.footprint.ground_z << ") taken, " << std::fabs(field_z - in.ground_z) << " m "
           << (field_z > in.ground_z ? "above" : "below") << " the ground measured around it ("
           << in.ground_z + in.origin.z << ", " << in.ground_method << ")";
      in.footprint.note += (in.footprint.note.empty() ? "" : "; ") + note.str();
      if (far_taken++ == 0) first_far = in.id + ": " + note.str();
    }
    in.ground_z = field_z;
    in.ground_method = "footprint attribute";
    in.ground_measured = true;
  }
  if (far_taken > 0)
    log_warning("input: " + std::to_string(far_taken) + " of " + std::to_string(inputs.size()) +
                " footprints' ground heights lie far from the ground measured around them (" + first_far +
                (far_taken > 1 ? "; the others' notes say the same" : "") + ")");
  if (ignored > 0)
    log_warning("input: " + std::to_string(ignored) + " of " + std::to_string(inputs.size()) +
                " footprints' ground heights not used (" + first_ignored +
                (ignored > 1 ? "; the others' notes say the same" : "") + ")");
}

}  // namespace city3d::detail
