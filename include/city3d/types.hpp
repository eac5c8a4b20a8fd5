// Plain value types shared by every module: points, rings, footprints, meshes, ids.
// No third-party headers here, so that any module can include it cheaply.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace city3d {

constexpr double kPi = 3.14159265358979323846;

/// A building identifier as it comes from the footprint source (or the file name for single clouds).
using BuildingId = std::string;

/// A 2D point in metres (world or local frame, as the owner documents).
struct Point2 {
  double x = 0.0;
  double y = 0.0;
};

/// A 3D point in metres (world or local frame, as the owner documents). Always double: world
/// coordinates at RD New magnitudes (x ~ 85 000, y ~ 447 000) need more than float's 24 bits.
struct Point3 {
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
};

/// An axis-aligned 3D box; empty() until something is added.
struct Box3 {
  Point3 min{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
             std::numeric_limits<double>::infinity()};
  Point3 max{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
             -std::numeric_limits<double>::infinity()};

  bool empty() const { return min.x > max.x; }
  void add(const Point3& p) {
    if (p.x < min.x) min.x = p.x;
    if (p.y < min.y) min.y = p.y;
    if (p.z < min.z) min.z = p.z;
    if (p.x > max.x) max.x = p.x;
    if (p.y > max.y) max.y = p.y;
    if (p.z > max.z) max.z = p.z;
  }
};

/// An axis-aligned 2D box; empty() until something is added.
struct Box2 {
  Point2 min{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  Point2 max{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};

  bool empty() const { return min.x > max.x; }
  void add(const Point2& p) {
    if (p.x < min.x) min.x = p.x;
    if (p.y < min.y) min.y = p.y;
    if (p.x > max.x) max.x = p.x;
    if (p.y > max.y) max.y = p.y;
  }
  bool intersects(const Box2& o) const {
    return !(o.min.x > max.x || o.max.x < min.x || o.min.y > max.y || o.max.y < min.y);
  }
};

/// A closed ring of 2D vertices; the closing vertex is not repeated.
using Ring2 = std::vector<Point2>;

/// A polygon with holes. After reading, the outer ring is counter-clockwise and every hole clockwise.
struct Polygon2 {
  Ring2 outer;
  std::vector<Ring2> holes;
};

/// A list attribute value as the text of its JSON array ("[]", "[203,104]", "[\"a\",\"b\"]"):
/// CityJSON writes it as that array, the GeoPackage as JSON text (GeoPackage has no list type).
struct AttributeList {
  std::string json = "[]";
  bool operator==(const AttributeList& o) const { return json == o.json; }
};

/// One attribute value: null, boolean, integer (64-bit), number, text or a list.
using AttributeValue = std::variant<std::monostate, bool, std::int64_t, double, std::string, AttributeList>;

/// Named attribute values, in the source's order.
using Attributes = std::vector<std::pair<std::string, AttributeValue>>;

/// One building footprint: one or more polygons (a multipolygon) with the building's id.
struct Footprint {
  BuildingId id;                    ///< value of the id field (or the feature id as text)
  std::int64_t fid = -1;            ///< OGR feature id, -1 when the source has none
  std::vector<Polygon2> polygons;   ///< world coordinates (the source's CRS), metres
  std::string note;                 ///< what the reader changed, e.g. "repaired with MakeValid: ..."; else empty
  std::optional<double> ground_z;   ///< floor height (world z) from the footprint source, when it has one
  /// Every attribute of the source feature with its type (64-bit integers intact, dates as text),
  /// carried over to the outputs.
  Attributes attributes;
};

/// A polygonal surface mesh: faces are vertex-index loops (not triangulated), counter-clockwise seen
/// from outside for a closed, outward-oriented model.
struct PolygonMesh {
  std::vector<Point3> vertices;
  std::vector<std::vector<std::uint32_t>> faces;
};

/// What a model face is, for CityJSON semantics.
enum class SurfaceType : std::uint8_t { ground, wall, roof };

/// The CityJSON semantic surface type of `t`: every output names surfaces so (CityJSON, the
/// GeoPackage's surfaces lists, the OBJ groups and materials, the glTF materials).
inline const char* surface_type_name(SurfaceType t) {
  switch (t) {
    case SurfaceType::ground: return "GroundSurface";
    case SurfaceType::wall: return "WallSurface";
    case SurfaceType::roof: return "RoofSurface";
  }
  return "RoofSurface";
}

/// A building's model: the mesh in a local frame plus the origin that takes it back to the world
/// (world = local + origin).
struct BuildingModel {
  BuildingId id;
  PolygonMesh mesh;
  Point3 origin;
  /// One entry per face, or empty: writers then classify faces by their normal.
  std::vector<SurfaceType> surfaces;
};

}  // namespace city3d
