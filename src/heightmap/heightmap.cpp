// Height map: CGAL 2D Delaunay TIN rasterised by linear interpolation, OpenCV closing and Canny,
// PNG debug images. The only translation unit of the module; no CGAL or OpenCV type leaves it.
#include "city3d/heightmap.hpp"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Projection_traits_xy_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>

#include "city3d/error.hpp"
#include "city3d/log.hpp"

namespace city3d {

namespace detail {
namespace {

constexpr std::size_t kMaxPixels = 50'000'000;   // ~200 MB of float; a building never needs this
constexpr int kMarginPixels = 1;                 // empty border so the outline is an edge
constexpr double kMinOutlineDrop = 5.0;          // metres below the lowest data outside the outline
// Canny works on 16-bit gradients; heights steps are passed in centimetres (up to 327 m).
constexpr double kGradientUnitsPerMetre = 100.0;
// A 3x3 Sobel sums the central difference over weights 1, 2, 1: a step of h gives 4 h.
constexpr double kSobelGain = 4.0;

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Traits = CGAL::Projection_traits_xy_3<Kernel>;
// Each vertex carries whether a kept triangle uses it (the density counts those vertices).
struct UsedMark {
  bool used = false;
};
using TinVertex = CGAL::Triangulation_vertex_base_with_info_2<UsedMark, Traits>;
using Tin = CGAL::Delaunay_triangulation_2<Traits, CGAL::Triangulation_data_structure_2<TinVertex>>;

std::string format_number(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

/// OpenCV run on the calling thread. Its own threads (TBB on Debian) split Canny and the morphology
/// into stripes, and on a building's image of a few thousand pixels the hand-off costs more than it
/// saves: a worker thread, and the caller spinning in sched_yield until the stripes are done (15,000
/// calls for the Delft block at -j 1). city3d runs buildings in parallel itself. The stripes give the
/// same pixels as one pass. The setting is OpenCV's, for the whole process; set once, before the first
/// OpenCV call of any thread that comes through here.
void opencv_on_calling_thread() {
  static const bool once = [] {
    cv::setNumThreads(0);  // 0: "run all its functions sequentially" (1 would set up a TBB arena)
    // OpenCV makes the operations of its matrix expressions (Mat::zeros and the like) on first use, by
    // double-checked locking: a second thread could read the pointer as the first one published it
    // (ThreadSanitizer, city3d_dev at -j 2). Made here, within this static's initialisation, they are
    // made before any thread passes this function.
    const cv::Mat made = cv::Mat::zeros(1, 1, CV_8U);
    return !made.empty();
  }();
  (void)once;
}

/// Heights with no-data pixels set to `fill`, as a CV_32F image (row 0 = south).
cv::Mat filled_image(const Heightmap& map, float fill) {
  opencv_on_calling_thread();
  cv::Mat image(map.height, map.width, CV_32F);
  for (int row = 0; row < map.height; ++row) {
    float* out = image.ptr<float>(row);
    for (int col = 0; col < map.width; ++col) {
      const float z = map.at(col, row);
      out[col] = std::isnan(z) ? fill : z;
    }
  }
  return image;
}


}  // namespace
}  // namespace detail

// Lowest and highest data height; {+inf, -inf} when there is none.
std::pair<float, float> height_range(const Heightmap& map) {
  float lowest = std::numeric_limits<float>::infinity();
  float highest = -std::numeric_limits<float>::infinity();
  for (float z : map.z) {
    if (std::isnan(z)) continue;
    lowest = std::min(lowest, z);
    highest = std::max(highest, z);
  }
  return {lowest, highest};
}

void HeightmapParams::validate() const {
  std::vector<std::string> problems;
  if (!(resolution >= 0.0) || !std::isfinite(resolution))
    problems.push_back("resolution = " + detail::format_number(resolution) + " m, need >= 0 (0 = automatic)");
  if (!(resolution_per_spacing > 0.0) || !std::isfinite(resolution_per_spacing))
    problems.push_back("resolution_per_spacing = " + detail::format_number(resolution_per_spacing) + ", need > 0");
  if (!(min_resolution > 0.0) || !(max_resolution >= min_resolution) || !std::isfinite(max_resolution))
    problems.push_back("min_resolution = " + detail::format_number(min_resolution) + " m, max_resolution = " +
                       detail::format_number(max_resolution) + " m, need 0 < min <= max");
  // A pixel finer than the finest automatic one (1e-9 m was taken, and every building fell back to
  // LoD1) or coarser than the coarsest is no resolution the method works at.
  else if (resolution != 0.0 && (resolution < min_resolution || resolution > max_resolution))
    problems.push_back("resolution = " + detail::format_number(resolution) + " m, need 0 (automatic) or " +
                       detail::format_number(min_resolution) + " to " +
                       detail::format_number(max_resolution) + " m (min_resolution to max_resolution)");
  if (!(max_edge_length > 0.0) || !std::isfinite(max_edge_length))
    problems.push_back("max_edge_length = " + detail::format_number(max_edge_length) + " m, need > 0");
  if (closing_size < 0 || (closing_size > 0 && closing_size % 2 == 0))
    problems.push_back("closing_size = " + std::to_string(closing_size) + " pixels, need 0 (off) or odd");
  if (!(canny_low > 0.0) || !std::isfinite(canny_low))
    problems.push_back("canny_low = " + detail::format_number(canny_low) + " m, need > 0");
  if (!(canny_high >= canny_low) || !std::isfinite(canny_high))
    problems.push_back("canny_high = " + detail::format_number(canny_high) + " m, need >= canny_low");
  if (rim_pixels < 0) problems.push_back("rim_pixels = " + std::to_string(rim_pixels) + ", need >= 0");
  if (problems.empty()) return;
  std::string message = "heightmap: invalid parameters: ";
  for (std::size_t i = 0; i < problems.size(); ++i) message += (i ? "; " : "") + problems[i];
  throw ConfigError(message);
}

double automatic_resolution(double points_per_m2, const HeightmapParams& params) {
  if (!(points_per_m2 > 0.0) || !std::isfinite(points_per_m2))
    throw ConfigError("heightmap: point density " + detail::format_number(points_per_m2) +
                      " points/m2, need > 0");
  return std::clamp(params.resolution_per_spacing / std::sqrt(points_per_m2), params.min_resolution,
                    params.max_resolution);
}

Heightmap rasterise_tin(const std::vector<Point3>& local_points, const HeightmapParams& params) {
  using namespace detail;
  params.validate();

  // Equal xy would be merged by the triangulation keeping an arbitrary one; keep the highest (the
  // roof over a wall point below it) explicitly.
  std::vector<Kernel::Point_3> points;
  points.reserve(local_points.size());
  for (std::size_t i = 0; i < local_points.size(); ++i) {
    const Point3& p = local_points[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw ReconstructionError(ReconstructionStage::heightmap, "point " + std::to_string(i) + " has a non-finite coordinate");
    points.emplace_back(p.x, p.y, p.z);
  }
  std::sort(points.begin(), points.end(), [](const Kernel::Point_3& l, const Kernel::Point_3& r) {
    if (l.x() != r.x()) return l.x() < r.x();
    if (l.y() != r.y()) return l.y() < r.y();
    return l.z() > r.z();
  });
  points.erase(std::unique(points.begin(), points.end(),
                           [](const Kernel::Point_3& l, const Kernel::Point_3& r) {
                             return l.x() == r.x() && l.y() == r.y();
                           }),
               points.end());
  if (points.size() < 3)
    throw ReconstructionError(ReconstructionStage::heightmap, "" + std::to_string(points.size()) +
                              " distinct xy positions, need at least 3");

  Tin tin(points.begin(), points.end());
  if (tin.dimension() < 2)
    throw ReconstructionError(ReconstructionStage::heightmap, "all " + std::to_string(points.size()) +
                              " points are collinear in xy, no TIN");

  // Keep the triangles whose edges are all short enough; measure the density on them.
  using Triangle = std::array<Kernel::Point_3, 3>;
  std::vector<Triangle> triangles;
  const double max_edge_squared = params.max_edge_length * params.max_edge_length;
  const auto squared_xy = [](const Kernel::Point_3& p, const Kernel::Point_3& q) {
    const double dx = p.x() - q.x(), dy = p.y() - q.y();
    return dx * dx + dy * dy;
  };
  double area = 0.0;
  std::size_t used_vertices = 0;
  for (auto face = tin.finite_faces_begin(); face != tin.finite_faces_end(); ++face) {
    const Triangle t{face->vertex(0)->point(), face->vertex(1)->point(), face->vertex(2)->point()};
    if (squared_xy(t[0], t[1]) > max_edge_squared || squared_xy(t[1], t[2]) > max_edge_squared ||
        squared_xy(t[2], t[0]) > max_edge_squared)
      continue;
    area += 0.5 * std::abs((t[1].x() - t[0].x()) * (t[2].y() - t[0].y()) -
                           (t[2].x() - t[0].x()) * (t[1].y() - t[0].y()));
    for (int k = 0; k < 3; ++k) {
      UsedMark& mark = face->vertex(k)->info();
      used_vertices += !mark.used;
      mark.used = true;
    }
    triangles.push_back(t);
  }
  if (triangles.empty() || !(area > 0.0))
    throw ReconstructionError(ReconstructionStage::heightmap, "no TIN triangle with all edges below max_edge_length = " +
                              format_number(params.max_edge_length) + " m");

  const double density = static_cast<double>(used_vertices) / area;
  const double r = params.resolution > 0.0 ? params.resolution : automatic_resolution(density, params);

  double min_x = std::numeric_limits<double>::infinity(), min_y = min_x;
  double max_x = -min_x, max_y = -min_x;
  for (const Triangle& t : triangles)
    for (const auto& p : t) {
      min_x = std::min(min_x, p.x());
      min_y = std::min(min_y, p.y());
      max_x = std::max(max_x, p.x());
      max_y = std::max(max_y, p.y());
    }

  Heightmap map;
  map.resolution = r;
  // Aligned to multiples of r in the local frame, with an empty margin.
  map.origin = {(std::floor(min_x / r) - kMarginPixels) * r, (std::floor(min_y / r) - kMarginPixels) * r};
  const double columns = std::floor((max_x - map.origin.x) / r) + 1 + kMarginPixels;
  const double rows = std::floor((max_y - map.origin.y) / r) + 1 + kMarginPixels;
  if (columns * rows > static_cast<double>(kMaxPixels))
    throw ReconstructionError(ReconstructionStage::heightmap, "raster of " + format_number(columns) + " x " +
                              format_number(rows) + " pixels at r = " + format_number(r) +
                              " m exceeds " + std::to_string(kMaxPixels) + " pixels");
  map.width = static_cast<int>(columns);
  map.height = static_cast<int>(rows);
  map.z.assign(static_cast<std::size_t>(map.width) * map.height, std::numeric_limits<float>::quiet_NaN());

  // Linear interpolation at the pixel centres inside each triangle (barycentric coordinates). The
  // small negative tolerance makes centres on a shared edge belong to both neighbours, so no
  // pixel between two kept triangles is lost to rounding.
  for (const Triangle& t : triangles) {
    const double x0 = t[0].x(), y0 = t[0].y(), x1 = t[1].x(), y1 = t[1].y(), x2 = t[2].x(), y2 = t[2].y();
    const double twice_area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
    if (twice_area == 0.0) continue;
    const double lo_x = std::min({x0, x1, x2}), hi_x = std::max({x0, x1, x2});
    const double lo_y = std::min({y0, y1, y2}), hi_y = std::max({y0, y1, y2});
    // Pixel index ranges widened by a hair: a centre exactly on a vertex (a point on the grid)
    // must not be lost to rounding in the division; the barycentric test below decides.
    constexpr double slack = 1e-7;
    const int col_begin = std::max(0, static_cast<int>(std::ceil((lo_x - map.origin.x) / r - 0.5 - slack)));
    const int col_end = std::min(map.width - 1, static_cast<int>(std::floor((hi_x - map.origin.x) / r - 0.5 + slack)));
    const int row_begin = std::max(0, static_cast<int>(std::ceil((lo_y - map.origin.y) / r - 0.5 - slack)));
    const int row_end = std::min(map.height - 1, static_cast<int>(std::floor((hi_y - map.origin.y) / r - 0.5 + slack)));
    constexpr double tolerance = 1e-9;
    for (int row = row_begin; row <= row_end; ++row) {
      const double y = map.origin.y + (row + 0.5) * r;
      for (int col = col_begin; col <= col_end; ++col) {
        const double x = map.origin.x + (col + 0.5) * r;
        const double l1 = ((x - x0) * (y2 - y0) - (x2 - x0) * (y - y0)) / twice_area;
        const double l2 = ((x1 - x0) * (y - y0) - (x - x0) * (y1 - y0)) / twice_area;
        const double l0 = 1.0 - l1 - l2;
        if (l0 < -tolerance || l1 < -tolerance || l2 < -tolerance) continue;
        map.z[static_cast<std::size_t>(row) * map.width + col] =
            static_cast<float>(l0 * t[0].z() + l1 * t[1].z() + l2 * t[2].z());
      }
    }
  }

  // Grey-level closing (dilate, then erode). No-data pixels join as a level 1 m below the data:
  // a hole enclosed by data rises to its surroundings, a pixel outside stays at that level (a
  // straight outline is restored exactly by the erosion), and sloped roofs are unchanged
  // (closing preserves linear functions away from valleys narrower than the element).
  if (params.closing_size > 1) {
    const auto [lowest, highest] = height_range(map);
    (void)highest;
    const float no_data = lowest - 1.0f;
    cv::Mat image = filled_image(map, no_data);
    cv::Mat closed;
    const cv::Mat element =
        cv::getStructuringElement(cv::MORPH_RECT, cv::Size(params.closing_size, params.closing_size));
    // Beyond the image is no data too; OpenCV's default border would act as data for the erosion
    // and grow the raster into its margin.
    cv::morphologyEx(image, closed, cv::MORPH_CLOSE, element, cv::Point(-1, -1), 1, cv::BORDER_CONSTANT,
                     cv::Scalar(no_data));
    std::size_t filled = 0;
    for (int row = 0; row < map.height; ++row) {
      const float* in = closed.ptr<float>(row);
      for (int col = 0; col < map.width; ++col) {
        float& z = map.z[static_cast<std::size_t>(row) * map.width + col];
        if (in[col] == no_data) continue;  // still outside (min/max copy values, exact compare is safe)
        if (std::isnan(z)) ++filled;
        z = in[col];
      }
    }
    if (log_level() >= LogLevel::debug)
      log_debug("heightmap: closing filled " + std::to_string(filled) + " pixels");
  }

  if (log_level() >= LogLevel::debug) {
    std::ostringstream message;
    message << "heightmap: " << map.width << " x " << map.height << " pixels at r = " << r << " m ("
            << density << " points/m2 on " << triangles.size() << " triangles)";
    log_debug(message.str());
  }
  return map;
}

std::vector<Point2> detect_edges(const Heightmap& heightmap, const HeightmapParams& params) {
  using namespace detail;
  params.validate();
  std::vector<Point2> edges;
  if (heightmap.width < 3 || heightmap.height < 3) return edges;
  const auto [lowest, highest] = height_range(heightmap);
  (void)highest;
  if (!std::isfinite(lowest)) return edges;

  const double drop = std::max(kMinOutlineDrop, 2.0 * params.canny_high);
  const cv::Mat image = filled_image(heightmap, static_cast<float>(lowest - drop));

  // Our own gradients in physical units, fed to the Canny overload that takes dx/dy, so the
  // thresholds are height steps in metres whatever the resolution (see HeightmapParams).
  cv::Mat dx, dy, dx16, dy16;
  cv::Sobel(image, dx, CV_32F, 1, 0, 3, 1.0, 0.0, cv::BORDER_REPLICATE);
  cv::Sobel(image, dy, CV_32F, 0, 1, 3, 1.0, 0.0, cv::BORDER_REPLICATE);
  const double scale = kGradientUnitsPerMetre / kSobelGain;
  dx.convertTo(dx16, CV_16S, scale);  // saturating
  dy.convertTo(dy16, CV_16S, scale);
  cv::Mat edge_image;
  cv::Canny(dx16, dy16, edge_image, params.canny_low * kGradientUnitsPerMetre,
            params.canny_high * kGradientUnitsPerMetre, /*L2gradient=*/true);

  for (int row = 0; row < heightmap.height; ++row) {
    const auto* in = edge_image.ptr<std::uint8_t>(row);
    for (int col = 0; col < heightmap.width; ++col)
      if (in[col]) edges.push_back(heightmap.pixel_centre(col, row));
  }
  if (log_level() >= LogLevel::debug)
    log_debug("heightmap: " + std::to_string(edges.size()) + " edge pixels");
  return edges;
}

std::vector<Point2> edges_off_the_rim(const Heightmap& heightmap, const std::vector<Point2>& edges,
                                      const HeightmapParams& params) {
  params.validate();
  const int w = heightmap.width, h = heightmap.height;
  const int k = std::min(params.rim_pixels, std::max(w, h) + 1);  // any wider rim takes every pixel
  // Each pixel's distance along its row from the nearest pixel without data (beyond the raster
  // counts as such), capped at k + 1: a sweep to the east, then one to the west.
  std::vector<int> row_reach(static_cast<std::size_t>(w) * h, k + 1);
  for (int row = 0; row < h; ++row) {
    for (int col = 0, last = -1; col < w; ++col) {  // the nearest empty pixel to the west
      if (std::isnan(heightmap.at(col, row))) last = col;
      row_reach[static_cast<std::size_t>(row) * w + col] = std::min(k + 1, col - last);
    }
    for (int col = w - 1, next = w; col >= 0; --col) {  // and to the east
      if (std::isnan(heightmap.at(col, row))) next = col;
      int& d = row_reach[static_cast<std::size_t>(row) * w + col];
      d = std::min(d, next - col);
    }
  }
  const auto off_the_rim = [&](int col, int row) {
    if (col < 0 || col >= w || row - k < 0 || row + k >= h) return false;
    for (int r = row - k; r <= row + k; ++r)
      if (row_reach[static_cast<std::size_t>(r) * w + col] <= k) return false;
    return true;
  };
  std::vector<Point2> kept;
  kept.reserve(edges.size());
  for (const Point2& e : edges) {
    const auto col = static_cast<int>(std::lround((e.x - heightmap.origin.x) / heightmap.resolution - 0.5));
    const auto row = static_cast<int>(std::lround((e.y - heightmap.origin.y) / heightmap.resolution - 0.5));
    if (off_the_rim(col, row)) kept.push_back(e);
  }
  return kept;
}

std::vector<Polygon2> infer_outline(const Heightmap& heightmap, const std::vector<Point3>& local_points,
                                    double tolerance, double min_area, double gap_spacings) {
  std::vector<Polygon2> outline;
  if (heightmap.width <= 0 || heightmap.height <= 0 || local_points.empty()) return outline;
  std::size_t data_pixels = 0;
  for (float z : heightmap.z) data_pixels += !std::isnan(z);
  const double r = heightmap.resolution;
  const double spacing = std::sqrt(std::max<double>(data_pixels, 1) * r * r / local_points.size());
  const int radius = std::max(1, static_cast<int>(std::ceil(gap_spacings * spacing / r)));
  // Occupancy with a border of `radius` empty pixels, so the closing never touches the image edge.
  detail::opencv_on_calling_thread();
  cv::Mat mask = cv::Mat::zeros(heightmap.height + 2 * radius, heightmap.width + 2 * radius, CV_8U);
  for (const Point3& p : local_points) {
    const int col = static_cast<int>(std::floor((p.x - heightmap.origin.x) / r));
    const int row = static_cast<int>(std::floor((p.y - heightmap.origin.y) / r));
    if (col >= 0 && col < heightmap.width && row >= 0 && row < heightmap.height)
      mask.at<std::uint8_t>(row + radius, col + radius) = 255;
  }
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1));
  cv::morphologyEx(mask, mask, cv::MORPH_CLOSE, kernel, cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  std::vector<std::pair<double, Polygon2>> found;
  for (const auto& contour : contours) {
    std::vector<cv::Point> simplified;
    // The occupancy boundary is jagged by about one point spacing: simplify beyond it.
    cv::approxPolyDP(contour, simplified, (tolerance + spacing) / heightmap.resolution, /*closed=*/true);
    if (simplified.size() < 3) continue;
    Polygon2 polygon;
    for (const cv::Point& p : simplified) polygon.outer.push_back(heightmap.pixel_centre(p.x - radius, p.y - radius));
    double area2 = 0.0;  // twice the signed area
    for (std::size_t i = 0, n = polygon.outer.size(); i < n; ++i) {
      const Point2& a = polygon.outer[i];
      const Point2& b = polygon.outer[(i + 1) % n];
      area2 += a.x * b.y - b.x * a.y;
    }
    if (std::abs(area2) / 2 < min_area) continue;
    if (area2 < 0) std::reverse(polygon.outer.begin(), polygon.outer.end());
    // The boundary pixels' centres lie half a pixel inside the occupied area, and the outermost
    // points lie on average half a point spacing inside the true wall: move every edge outward by
    // both (a miter offset, limited at sharp corners).
    const double shift = 0.5 * (r + spacing);
    const Ring2 ring = polygon.outer;
    const std::size_t n = ring.size();
    for (std::size_t i = 0; i < n; ++i) {
      const Point2& prev = ring[(i + n - 1) % n];
      const Point2& cur = ring[i];
      const Point2& next = ring[(i + 1) % n];
      auto outward = [](const Point2& a, const Point2& b) {  // right normal: outward for a CCW ring
        const double len = std::hypot(b.x - a.x, b.y - a.y);
        return Point2{(b.y - a.y) / len, -(b.x - a.x) / len};
      };
      const Point2 n1 = outward(prev, cur), n2 = outward(cur, next);
      const double denom = std::max(0.25, 1.0 + n1.x * n2.x + n1.y * n2.y);
      polygon.outer[i] = {cur.x + shift * (n1.x + n2.x) / denom, cur.y + shift * (n1.y + n2.y) / denom};
    }
    found.emplace_back(std::abs(area2) / 2, std::move(polygon));
  }
  std::stable_sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (auto& f : found) outline.push_back(std::move(f.second));
  return outline;
}

}  // namespace city3d
