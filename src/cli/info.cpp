// `city3d info`: summaries of point-cloud files and footprint sources, streamed so that a tile of any
// size is summarised in bounded memory.
#include "city3d/info.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/evaluation.hpp"
#include "city3d/log.hpp"
#include "city3d/model_io.hpp"
#include "city3d/pipeline.hpp"
#include "city3d/surface_support.hpp"

namespace city3d {
namespace {

std::string fields_text(PointFields f) {
  std::string s = "xyz";
  if (f & kFieldIntensity) s += " intensity";
  if (f & kFieldReturns) s += " returns";
  if (f & kFieldClassification) s += " classification";
  if (f & kFieldGpsTime) s += " gps_time";
  if (f & kFieldRgb) s += " rgb";
  if (f & kFieldNormal) s += " normal";
  return s;
}

/// Points farther than this outside the model's box in plan (metres) are not the model's building.
constexpr double kBeyondModel = 1.0;
/// More than this share of such points gets a warning: the RMSE is not the model's.
constexpr double kBeyondModelShare = 0.05;

std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

}  // namespace

bool looks_like_point_cloud(const std::string& path) {
  // By extension first: a missing or empty tile_07.las is a point cloud that cannot be read, and
  // its error must say so, not that it is no vector source.
  const auto dot = path.find_last_of('.');
  std::string ext = dot == std::string::npos ? "" : path.substr(dot + 1);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == "las" || ext == "laz" || ext == "ply") return true;
  std::ifstream in(path, std::ios::binary);
  char magic[4] = {0, 0, 0, 0};
  in.read(magic, 4);
  const std::string m(magic, static_cast<std::size_t>(in.gcount()));
  return m == "LASF" || m.rfind("ply", 0) == 0;
}

PointCloudSummary summarise_point_cloud(const std::string& path) {
  PointCloudSummary summary;
  auto reader = open_point_cloud(path, kFieldClassification);
  summary.info = reader->info();
  PointCloud chunk;
  constexpr std::size_t kChunk = 1 << 20;
  Box3 bounds;
  for (;;) {
    chunk.clear();
    const std::size_t n = reader->read(chunk, kChunk);
    if (n == 0) break;
    summary.points_read += n;
    if (!chunk.classification.empty()) {
      summary.has_classes = true;
      for (std::uint8_t c : chunk.classification) ++summary.class_counts[c];
    }
    for (const Point3& p : chunk.points) bounds.add(p);
  }
  summary.withheld = reader->withheld_points();
  // PLY headers carry no bounds: report the bounds of the points read.
  if (summary.info.bounds.empty()) summary.info.bounds = bounds;
  return summary;
}

std::string describe_point_cloud(const PointCloudSummary& s) {
  const PointCloudInfo& i = s.info;
  const int d = i.format == "PLY" ? 3 : std::max(0, static_cast<int>(std::ceil(-std::log10(i.scale[0]) - 1e-9)));
  std::ostringstream out;
  out << "file: " << i.path << "\n";
  out << "format: " << i.format << " " << i.version;
  if (i.point_format >= 0) out << ", point format " << i.point_format << ", record length " << i.record_length;
  out << "\n";
  out << "points: " << i.point_count << "\n";
  if (i.uncounted_records > 0)
    out << "uncounted: " << i.uncounted_records
        << " more records follow the counted points (a header not rewritten when points were added?): not "
           "read\n";
  if (i.mesh_faces > 0) out << "faces: " << i.mesh_faces << " (a mesh, such as a model: not a point cloud)\n";
  if (!i.bounds.empty()) {
    out << "bounds: x " << fixed(i.bounds.min.x, d) << " .. " << fixed(i.bounds.max.x, d) << ", y "
        << fixed(i.bounds.min.y, d) << " .. " << fixed(i.bounds.max.y, d) << ", z " << fixed(i.bounds.min.z, d)
        << " .. " << fixed(i.bounds.max.z, d) << "\n";
  }
  if (i.format != "PLY") {
    out << "scale: " << i.scale[0] << " " << i.scale[1] << " " << i.scale[2] << "  offset: " << i.offset[0] << " "
        << i.offset[1] << " " << i.offset[2] << "\n";
  }
  out << "crs: " << (i.crs.empty() ? "none recorded" : i.crs) << "\n";
  if (!i.generating_software.empty()) out << "software: " << i.generating_software << "\n";
  out << "fields: " << fields_text(i.fields) << "\n";
  for (const std::string& v : i.vlrs) out << "vlr: " << v << "\n";
  if (s.withheld > 0)
    out << "withheld: " << s.withheld
        << " (flagged withheld: left out as deleted, as the LAS specification asks)\n";
  if (s.has_classes) {
    out << "classes:\n";
    for (int c = 0; c < 256; ++c)
      if (s.class_counts[c] > 0) out << "  " << c << " " << las_class_name(c) << ": " << s.class_counts[c] << "\n";
  } else {
    out << "classes: none in file\n";
  }
  return out.str();
}

std::string describe_footprints(const FootprintSet& f, const std::vector<FieldSummary>& fields, std::size_t features) {
  std::ostringstream out;
  out << "file: " << f.path << "\n";
  out << "driver: " << f.driver << "\n";
  out << "layer: " << f.layer << "\n";
  out << "features: " << f.feature_count << "\n";
  out << "footprints: " << f.footprints.size() << "\n";
  out << "id field: " << f.id_field << "\n";
  if (!fields.empty()) {
    out << "fields (of " << features << " features; * unique: usable as --id-field):\n";
    for (const FieldSummary& field : fields)
      out << "  " << field.name << ": " << field.type << ", " << field.distinct << " distinct"
          << (field.values < features ? ", " + std::to_string(features - field.values) + " null" : std::string())
          << (field.unique(features) ? " *" : "") << "\n";
  }
  out << "srs: " << (f.srs.empty() ? "none recorded" : f.srs) << "\n";
  std::size_t multi = 0;
  Box2 bounds;
  for (const Footprint& fp : f.footprints) {
    if (fp.polygons.size() > 1) ++multi;
    for (const Polygon2& p : fp.polygons)
      for (const Point2& v : p.outer) bounds.add(v);
  }
  if (!bounds.empty())
    out << "bounds: x " << fixed(bounds.min.x, 3) << " .. " << fixed(bounds.max.x, 3) << ", y "
        << fixed(bounds.min.y, 3) << " .. " << fixed(bounds.max.y, 3) << "\n";
  out << "with holes: " << f.with_holes << "\n";
  out << "multipolygons: " << multi << "\n";
  out << "repaired (invalid): " << f.repaired << "\n";
  // What a run does to these footprints before their stages (prepare_footprint), counted per footprint.
  const ReconstructionParams params;
  std::size_t touching = 0, slips = 0;
  for (const Footprint& fp : f.footprints) {
    std::vector<Polygon2> polygons = fp.polygons;
    const FootprintPreparation prepared = prepare_footprint(polygons, params);
    touching += !prepared.opened.empty() || prepared.unopened.has_value();
    slips += prepared.tidied.merged + prepared.tidied.spikes > 0;
  }
  out << "rings touching: " << touching << " (opened by " << params.footprint_clearance
      << " m when reconstructed)\n";
  out << "vertices doubled or hairline spikes: " << slips << " (dropped when reconstructed)\n";
  out << "skipped: " << f.skipped.size() << "\n";
  for (const SkippedFootprint& s : f.skipped) out << "  " << s.id << ": " << s.reason << "\n";
  return out.str();
}

std::string evaluate_model(const std::string& model_path, const std::string& points_path,
                           const std::string& residuals_path) {
  std::string extension = std::filesystem::path(model_path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension != ".obj")
    throw IoError("evaluate: " + model_path +
                  " is not an OBJ file: evaluate reads one model as OBJ (city3d writes "
                  "them to models/ with --format obj, the default)");
  std::error_code ec;
  for (const std::string& input : {model_path, points_path})
    if (!residuals_path.empty() && std::filesystem::equivalent(residuals_path, input, ec))
      throw ConfigError("evaluate: --residuals " + residuals_path + " is the input " + input +
                        ": it would be replaced; give another file");
  BuildingModel model = read_obj_model(model_path);
  PointCloud cloud = read_point_cloud(points_path, kFieldXyz);
  Box3 box;
  for (const Point3& v : model.mesh.vertices) box.add(v);
  const Point3 centre{std::round((box.min.x + box.max.x) / 2), std::round((box.min.y + box.max.y) / 2),
                      std::round((box.min.z + box.max.z) / 2)};
  for (Point3& v : model.mesh.vertices) v = {v.x - centre.x, v.y - centre.y, v.z - centre.z};
  for (Point3& p : cloud.points) p = {p.x - centre.x, p.y - centre.y, p.z - centre.z};
  const MeshValidity v = check_validity(model.mesh);
  std::ostringstream out;
  auto yes = [](bool b) { return b ? "yes" : "no"; };
  out << "model: " << model_path << "\n";
  out << "points: " << points_path << " (" << cloud.size() << ")\n";
  out << "faces: " << model.mesh.faces.size() << "\n";
  out << "vertices: " << model.mesh.vertices.size() << "\n";
  const std::vector<double> distances = point_distances(model.mesh, cloud.points);
  double sum = 0.0;
  for (const double d : distances) sum += d * d;
  out << "rmse: " << fixed(std::sqrt(sum / static_cast<double>(distances.size())), 4) << "\n";
  // The other direction: surface no point supports (surface_support.hpp).
  const SurfaceSupportParams support_params;
  const SurfaceSupport support =
      surface_support(model.mesh, surface_types_unoriented(model.mesh), LocalTop(cloud.points, support_params.radius),
                      support_params);
  out << "unsupported_area: " << fixed(support.unsupported_area, 2) << " (m2 of surface more than "
      << fixed(support_params.tolerance, 1) << " m above the highest point within " << fixed(support_params.radius, 1)
      << " m in plan)\n";
  out << "unsupported_roof_area: " << fixed(support.unsupported_roof_area, 2) << " (of it, on roof faces)\n";
  out << "height_excess: " << fixed(support.height_excess, 3) << "\n";
  out << "unpointed_roof_area: " << fixed(support.unpointed_roof_area, 2) << " (m2 of roof with no point within "
      << fixed(support_params.radius, 1) << " m in plan)\n";
  double highest_point = -std::numeric_limits<double>::infinity(), highest_vertex = highest_point;
  for (const Point3& p : cloud.points) highest_point = std::max(highest_point, p.z);
  for (const Point3& v : model.mesh.vertices) highest_vertex = std::max(highest_vertex, v.z);
  out << "highest_vertex_above_points: " << fixed(highest_vertex - highest_point, 3) << "\n";
  // Points of more than the building (a whole tile, a neighbour) make the RMSE measure them too.
  std::size_t beyond = 0;
  for (const Point3& p : cloud.points)
    beyond += p.x < box.min.x - centre.x - kBeyondModel || p.x > box.max.x - centre.x + kBeyondModel ||
              p.y < box.min.y - centre.y - kBeyondModel || p.y > box.max.y - centre.y + kBeyondModel;
  const double beyond_share = cloud.empty() ? 0.0 : static_cast<double>(beyond) / static_cast<double>(cloud.size());
  out << "points beyond the model: " << beyond << " (" << fixed(100.0 * beyond_share, 1)
      << "%, farther than 1 m outside its box in plan)\n";
  if (beyond_share > kBeyondModelShare)
    log_warning("evaluate: " + fixed(100.0 * beyond_share, 1) + "% of the points of " + points_path +
                " lie more than 1 m outside the model's box in plan, and the RMSE measures them too: give the "
                "points of this building only");
  // By the vertex indices and, as val3dity snaps coincident vertices, by its codes too: two cubes of
  // their own vertices that share an edge in space are closed by their indices, not manifold.
  const auto found = [&v](int code) {
    return std::any_of(v.errors.begin(), v.errors.end(),
                       [code](const ValidityError& e) { return e.code == code; });
  };
  const bool closed = v.closed && !found(302);
  out << "closed: " << yes(closed) << "\n";
  out << "manifold: " << yes(v.manifold && !found(303) && !found(304)) << "\n";
  out << "outward: " << yes(v.outward) << "\n";
  out << "planar: " << yes(v.planar) << " (max error " << fixed(v.max_planarity_error, 4) << " m)\n";
  out << "self-intersecting: " << (v.self_intersecting_checked ? yes(v.self_intersects) : "not checked") << "\n";
  out << "volume: " << (closed ? fixed(v.volume, 3) : std::string("none (not closed)")) << "\n";
  out << "val3dity: " << (v.errors.empty() ? std::string("no error") : validity_codes(v.errors)) << "\n";
  out << "valid: " << yes(v.valid()) << "\n";
  if (!v.problem.empty()) out << "problems: " << v.problem << "\n";
  if (!residuals_path.empty()) {
    std::ofstream csv(residuals_path);
    csv << "x,y,z,distance\n";
    for (std::size_t i = 0; i < distances.size(); ++i) {
      const Point3& p = cloud.points[i];
      csv << fixed(p.x + centre.x, 3) << ',' << fixed(p.y + centre.y, 3) << ',' << fixed(p.z + centre.z, 3) << ','
          << fixed(distances[i], 4) << '\n';
    }
    csv.close();
    if (!csv) throw IoError(residuals_path + ": cannot write the residuals");
    out << "residuals: " << residuals_path << "\n";
  }
  return out.str();
}

}  // namespace city3d
