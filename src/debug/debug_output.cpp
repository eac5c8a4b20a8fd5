// Debug output (--debug DIR): each stage's intermediate result of one building written as PNG, PLY or
// OBJ for a person to look at. The geometry modules do no file IO; the pipeline hands their results here.
#include "city3d/debug_output.hpp"

#include <cpl_error.h>
#include <gdal.h>
#include <gdal_frmts.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <system_error>
#include <tuple>
#include <type_traits>

#include "city3d/error.hpp"
#include "city3d/model_io.hpp"

namespace city3d {
namespace fs = std::filesystem;

namespace {

/// An 8-bit image of `bands` channels (1 grey, 3 RGB), interleaved by pixel, rows from the top.
struct Image {
  int width = 0, height = 0, bands = 1;
  std::vector<std::uint8_t> pixels;
};

/// Grey image, north up: 0 no data, 1..255 lowest..highest.
Image grey_image(const Heightmap& map) {
  Image image{map.width, map.height, 1,
              std::vector<std::uint8_t>(
                  static_cast<std::size_t>(map.width) * static_cast<std::size_t>(map.height), 0)};
  const auto [lowest, highest] = height_range(map);
  const double span = highest > lowest ? static_cast<double>(highest) - lowest : 0.0;
  for (int row = 0; row < map.height; ++row) {
    std::uint8_t* out = image.pixels.data() + static_cast<std::size_t>(map.height - 1 - row) * map.width;
    for (int col = 0; col < map.width; ++col) {
      const float z = map.at(col, row);
      if (std::isnan(z)) continue;
      out[col] = span > 0.0 ? static_cast<std::uint8_t>(std::lround(1.0 + 254.0 * (z - lowest) / span))
                            : std::uint8_t{255};
    }
  }
  return image;
}

/// Writes `image` as a PNG through GDAL's PNG driver, from an in-memory copy. GDAL is the project's
/// file-format library already; OpenCV's imgcodecs, which did this before, linked some 15 more shared
/// libraries (GDCM's DICOM libraries, OpenEXR) into every run for the debug images alone: about 14 ms
/// of CPU at each start of the program (docs/BENCHMARKS.md).
void write_png(const Image& image, const std::string& path) {
  // Only the two drivers this needs: GDALAllRegister would also reorder the driver list, which a
  // footprint reader on another thread may be walking through in GDALOpenEx.
  static std::once_flag registered;
  std::call_once(registered, [] {
    GDALRegister_MEM();  // each a no-op when its driver is registered already
    GDALRegister_PNG();
  });
  const GDALDriverH memory = GDALGetDriverByName("MEM"), png = GDALGetDriverByName("PNG");
  if (!memory || !png) throw IoError("debug: cannot write " + path + ": GDAL has no MEM or PNG driver");
  CPLPushErrorHandler(CPLQuietErrorHandler);
  CPLErrorReset();
  const auto failed = [&path](const char* what) {
    const std::string reason = CPLGetLastErrorMsg();
    CPLPopErrorHandler();
    return IoError("debug: cannot write " + path + ": " + what + (reason.empty() ? "" : ": " + reason));
  };
  const GDALDatasetH copy = GDALCreate(memory, "", image.width, image.height, image.bands, GDT_Byte, nullptr);
  if (!copy) throw failed("no in-memory raster");
  const int pixel = image.bands, line = image.bands * image.width;
  if (GDALDatasetRasterIO(copy, GF_Write, 0, 0, image.width, image.height,
                          const_cast<std::uint8_t*>(image.pixels.data()), image.width, image.height, GDT_Byte,
                          image.bands, nullptr, pixel, line, 1) != CE_None) {
    GDALClose(copy);
    throw failed("raster write");
  }
  const GDALDatasetH written = GDALCreateCopy(png, path.c_str(), copy, FALSE, nullptr, nullptr, nullptr);
  GDALClose(copy);
  if (!written) throw failed("PNG driver");
  GDALClose(written);  // flushes the file
  if (CPLGetLastErrorType() >= CE_Failure) throw failed("PNG driver");
  CPLPopErrorHandler();
}

// An OBJ file drawing each of `items` as one element over corners of its own: `element` is 'l' (a
// polyline) or 'f' (a face), `corners` gives an item's corners as a std::array. `stage` names the
// module in messages, `what` the items in the header line.
template <class Item, class Corners>
void write_items_obj(const std::string& path, const char* stage, const char* what,
                     const std::vector<Item>& items, char element, Corners corners) {
  constexpr std::size_t n = std::tuple_size_v<std::invoke_result_t<Corners, const Item&>>;
  std::ofstream out(path);
  if (!out) throw IoError(std::string(stage) + ": cannot open " + path + " for writing");
  out.precision(17);
  out << "# city3d " << what << ": " << items.size() << "\n";
  for (const Item& item : items)
    for (const Point3& c : corners(item)) out << "v " << c.x << ' ' << c.y << ' ' << c.z << "\n";
  for (std::size_t i = 0; i < items.size(); ++i) {
    out << element;
    for (std::size_t k = 1; k <= n; ++k) out << ' ' << n * i + k;
    out << "\n";
  }
  if (!out) throw IoError(std::string(stage) + ": write failed for " + path);
}

// The height of the walls drawn above the floor, metres.
constexpr double kDebugWallHeight = 20.0;

}  // namespace

std::string debug_path(const std::string& debug_dir, const BuildingId& id, const std::string& name) {
  const fs::path dir = fs::path(debug_dir) / fs::path(model_file_name(id, MeshFormat::obj)).stem();
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw IoError("debug: cannot create folder " + dir.string() + ": " + ec.message());
  return (dir / name).string();
}

void write_planes_ply(const std::string& path, const std::vector<Point3>& points,
                      const std::vector<PlanarSegment>& segments) {
  std::vector<int> label(points.size(), -1);
  for (std::size_t s = 0; s < segments.size(); ++s)
    for (std::uint32_t i : segments[s].points) label[i] = static_cast<int>(s);
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw IoError("debug: cannot write " + path);
  std::fprintf(f, "ply\nformat ascii 1.0\nelement vertex %zu\nproperty double x\nproperty double y\nproperty double z\n"
               "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty int segment\nend_header\n",
               points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    // A fixed pseudo-random colour per segment.
    const unsigned h = label[i] < 0 ? 0u : static_cast<unsigned>(label[i] + 1) * 2654435761u;
    const int r = label[i] < 0 ? 160 : 40 + (h >> 8) % 200, g = label[i] < 0 ? 160 : 40 + (h >> 16) % 200,
              b = label[i] < 0 ? 160 : 40 + (h >> 24) % 200;
    std::fprintf(f, "%.4f %.4f %.4f %d %d %d %d\n", points[i].x, points[i].y, points[i].z, r, g, b, label[i]);
  }
  if (std::fclose(f) != 0) throw IoError("debug: cannot write " + path);
}

void write_heightmap_png(const Heightmap& heightmap, const std::string& path) {
  if (heightmap.width <= 0 || heightmap.height <= 0)
    throw IoError("heightmap: cannot write " + path + ": empty heightmap");
  write_png(grey_image(heightmap), path);
}

void write_edges_png(const Heightmap& heightmap, const std::vector<Point2>& edges, const std::string& path) {
  if (heightmap.width <= 0 || heightmap.height <= 0)
    throw IoError("heightmap: cannot write " + path + ": empty heightmap");
  const Image grey = grey_image(heightmap);
  Image colour{grey.width, grey.height, 3, std::vector<std::uint8_t>(grey.pixels.size() * 3)};
  for (std::size_t i = 0; i < grey.pixels.size(); ++i)
    for (std::size_t c = 0; c < 3; ++c) colour.pixels[3 * i + c] = grey.pixels[i];
  for (const Point2& p : edges) {
    const int col = static_cast<int>(std::floor((p.x - heightmap.origin.x) / heightmap.resolution));
    const int row = static_cast<int>(std::floor((p.y - heightmap.origin.y) / heightmap.resolution));
    if (col < 0 || row < 0 || col >= heightmap.width || row >= heightmap.height) continue;
    std::uint8_t* rgb = colour.pixels.data() +
                        3 * (static_cast<std::size_t>(heightmap.height - 1 - row) * heightmap.width + col);
    rgb[0] = 255, rgb[1] = 0, rgb[2] = 0;  // red
  }
  write_png(colour, path);
}

void write_polylines_obj(const std::string& path, const std::vector<Polyline2>& polylines, double z) {
  std::ofstream out(path);
  if (!out) throw IoError("polylines: cannot open " + path + " for writing");
  out.precision(17);
  out << "# city3d polylines: " << polylines.size() << "\n";
  std::size_t base = 1;
  for (const auto& line : polylines) {
    const bool closed = is_closed(line);
    const std::size_t n = closed ? line.size() - 1 : line.size();
    for (std::size_t i = 0; i < n; ++i) out << "v " << line[i].x << ' ' << line[i].y << ' ' << z << "\n";
    if (n >= 2) {
      out << 'l';
      for (std::size_t i = 0; i < n; ++i) out << ' ' << base + i;
      if (closed) out << ' ' << base;
      out << "\n";
    }
    base += n;
  }
  if (!out) throw IoError("polylines: write failed for " + path);
}

void write_segments_obj(const std::string& path, const std::vector<Segment2>& segments, double z) {
  write_items_obj(path, "regularise", "segments", segments, 'l', [z](const Segment2& s) {
    return std::array<Point3, 2>{{{s.a.x, s.a.y, z}, {s.b.x, s.b.y, z}}};
  });
}

void write_walls_obj(const std::string& path, const std::vector<VerticalPlane>& walls, double z0, double z1) {
  write_items_obj(path, "walls", "walls", walls, 'f', [z0, z1](const VerticalPlane& w) {
    return std::array<Point3, 4>{
        {{w.a.x, w.a.y, z0}, {w.b.x, w.b.y, z0}, {w.b.x, w.b.y, z1}, {w.a.x, w.a.y, z1}}};
  });
}

void write_candidates_obj(const std::string& path, const CandidateFaces& candidates) {
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (!file) throw IoError("hypothesis: cannot write " + path);
  std::fprintf(file, "# city3d candidate faces\n");
  for (const auto& v : candidates.vertices) std::fprintf(file, "v %.6f %.6f %.6f\n", v.x, v.y, v.z);
  static const char* kind_names[] = {"roof", "wall", "floor"};
  for (std::size_t i = 0; i < candidates.faces.size(); ++i) {
    const auto& f = candidates.faces[i];
    // roof_<face>_plane<roof plane>_cell<cell>, wall_<face>_edge<edge>, floor_<face>_cell<cell>
    std::fprintf(file, "o %s_%zu", kind_names[static_cast<int>(f.kind)], i);
    if (f.kind == FaceKind::roof) std::fprintf(file, "_plane%d", f.source);
    std::fprintf(file, "_%s%u\nf", f.kind == FaceKind::wall ? "edge" : "cell", f.cell_or_edge);
    for (auto v : f.vertices) std::fprintf(file, " %u", v + 1);
    std::fprintf(file, "\n");
  }
  if (std::fclose(file) != 0) throw IoError("hypothesis: cannot write " + path);
}

void write_selection_csv(const std::string& path, const CandidateFaces& candidates, const std::vector<bool>& selected,
                         const SelectionParams& energy) {
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (!file) throw IoError("selection: cannot write " + path);
  const SelectionProblem& problem = candidates.problem;
  std::vector<char> prior(candidates.faces.size(), 0), forced(candidates.faces.size(), 0);
  for (auto i : problem.face_prior) prior[i] = 1;
  for (auto i : problem.forced_on) forced[i] = 1;
  for (auto i : problem.forced_off) forced[i] = -1;
  static const char* kind_names[] = {"roof", "wall", "floor"};
  // The energy's coefficient of each face as selection.hpp writes it: data and roof preference.
  const double points = static_cast<double>(std::max<std::size_t>(problem.point_count, 1));
  const double faces = static_cast<double>(std::max<std::size_t>(problem.face_count, 1));
  std::fprintf(file, "face,kind,plane,cell_or_edge,area,z_min,z_max,support,unsupported_area,data_term,roof_term,"
                     "unsupported_term,fixed,selected\n");
  for (std::size_t i = 0; i < candidates.faces.size(); ++i) {
    const CandidateFace& f = candidates.faces[i];
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Point3& p : candidates.polygons[i]) {
      lo = std::min(lo, p.z);
      hi = std::max(hi, p.z);
    }
    const double support = i < problem.support.size() ? problem.support[i] : 0.0;
    const double centroid = i < problem.centroid_z.size() ? problem.centroid_z[i] : 0.0;
    const double data = -energy.lambda_data * support / points;
    const double roof =
        energy.lambda_roof * (problem.z_max - centroid) / ((problem.z_max - problem.z_min) * faces);
    const double unsupported = i < problem.unsupported.size() ? problem.unsupported[i] : 0.0;
    const double unsupported_term =
        problem.plan_area > 0.0 ? energy.lambda_unsupported * unsupported / problem.plan_area : 0.0;
    const char* fixed = prior[i] ? "prior" : forced[i] > 0 ? "on" : forced[i] < 0 ? "off" : "";
    std::fprintf(file, "%zu,%s,%d,%u,%.4f,%.4f,%.4f,%.0f,%.4f,%.6g,%.6g,%.6g,%s,%d\n", i,
                 kind_names[static_cast<int>(f.kind)], f.kind == FaceKind::roof ? f.source : -1, f.cell_or_edge, f.area,
                 lo, hi, support, unsupported, data, roof, unsupported_term, fixed, i < selected.size() && selected[i] ? 1 : 0);
  }
  if (std::fclose(file) != 0) throw IoError("selection: cannot write " + path);
}

void write_debug_trace(DebugTrace& trace) {
  const auto path = [&trace](const std::string& name) { return debug_path(trace.dir, trace.id, name); };
  if (trace.planes && trace.points) write_planes_ply(path("planes.ply"), *trace.points, *trace.planes);
  if (trace.step_lines) write_polylines_obj(path("step_lines.obj"), *trace.step_lines, trace.ground_z);
  if (trace.heightmap && trace.edges && trace.polylines && trace.regularised) {
    write_heightmap_png(*trace.heightmap, path("heightmap.png"));
    write_edges_png(*trace.heightmap, *trace.edges, path("edges.png"));
    write_polylines_obj(path("polylines.obj"), *trace.polylines, trace.ground_z);
    write_segments_obj(path("regularised.obj"), *trace.regularised, trace.ground_z);
  }
  for (const auto& [suffix, walls] : trace.walls)
    write_walls_obj(path("walls" + suffix + ".obj"), walls, trace.ground_z, trace.ground_z + kDebugWallHeight);
  for (const auto& [suffix, candidates] : trace.candidates)
    write_candidates_obj(path("candidates" + suffix + ".obj"), candidates);
  for (const DebugTrace::Selection& s : trace.selections)
    write_selection_csv(path("selection" + s.suffix + ".csv"), s.candidates, s.selected, s.energy);
  for (const auto& [rung, model] : trace.rejected) {
    ModelWriteOptions local;
    local.local_coordinates = true;
    write_model(path("rejected_" + rung + ".obj"), model, local);
  }
  DebugTrace empty;
  empty.dir = std::move(trace.dir);
  empty.id = std::move(trace.id);
  empty.ground_z = trace.ground_z;
  empty.points = trace.points;
  trace = std::move(empty);
}

}  // namespace city3d
