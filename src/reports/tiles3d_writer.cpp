// 3D Tiles 1.1 output: a tileset.json of a quadtree over the buildings and binary glTF content
// (written here byte by byte: see below), LoD1.2 where the geometric error is large and LoD2.2 near,
// each building's id and attributes as EXT_mesh_features / EXT_structural_metadata, vertices placed
// on the globe from the run's CRS through PROJ. Everything is made from the overview records, so
// a merge of shards writes the same bytes as one process.
//
// Why no glTF library: Debian's libtinygltf-dev would give a model struct to fill and serialise,
// but the extensions are free-form JSON values there too, and the EXT_structural_metadata binary
// layout (8-byte aligned buffer views, string offsets) is ours to build either way; draco and
// meshoptimizer compress geometry, which LoD2 buildings of some hundred triangles do not need and
// which every reader (and the glTF validator) would have to decode. What is written is one buffer
// of plain accessors, about 150 lines, with every byte decided here (determinism).
//
// Placing vertices on the globe. The run's CRS is projected (RD New, UTM) with heights in metres. A
// compound CRS whose vertical datum PROJ can turn into ellipsoidal heights (a geoid grid installed)
// goes to EPSG:4979 (WGS 84, ellipsoidal height) that way. Otherwise the horizontal CRS, promoted to
// 3D, goes to EPSG:4979 through its datum's transformation, the heights taken as heights above the
// datum's own ellipsoid: PROJ's own pick for a compound without its grid is a "ballpark" that drops
// the datum shift (RD New + NAP to WGS 84: 110 m off in plan), while the promoted path applies it;
// for NAP heights, which the Bessel ellipsoid of Amersfoort follows closely, it lands within about
// a metre of EGM96 (Delft: NAP 0 -> 43.57 m, EGM96 geoid 43.46 m; 0.05-0.76 m at five places
// across the Netherlands, 2026-11-25). Then geodetic -> ECEF (WGS 84) and a local east-north-up frame
// per leaf tile (its tile transform), so that float32 positions keep 0.1 mm.
#include <proj.h>
#include <proj_experimental.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/log.hpp"
#include "city3d/run_outputs.hpp"
#include "files/atomic_file.hpp"
#include "reports/report.hpp"

namespace city3d {
namespace {

namespace fs = std::filesystem;
using ordered_json = nlohmann::ordered_json;


// The quadtree: a cell of more buildings than this is split, unless it is already this small.
// 64 LoD2.2 buildings of the Delft block make a tile of about 0.4 MB.
constexpr std::size_t kMaxBuildingsPerTile = 64;
constexpr double kMinTileSize = 32.0;  // metres
constexpr int kMaxDepth = 20;

// glTF constants.
constexpr int kFloat = 5126, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

// --- the globe ---------------------------------------------------------------------------------

struct Geodetic {
  double lon = 0, lat = 0, h = 0;  // radians, radians, metres above the WGS 84 ellipsoid
};

struct Vec3 {
  double x = 0, y = 0, z = 0;
};

Vec3 ecef_of(const Geodetic& g) {
  constexpr double a = 6378137.0, f = 1.0 / 298.257223563, e2 = f * (2 - f);
  const double n = a / std::sqrt(1 - e2 * std::sin(g.lat) * std::sin(g.lat));
  return {(n + g.h) * std::cos(g.lat) * std::cos(g.lon), (n + g.h) * std::cos(g.lat) * std::sin(g.lon),
          (n * (1 - e2) + g.h) * std::sin(g.lat)};
}

double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// The run's CRS to EPSG:4979 (WGS 84, degrees and ellipsoidal height), chosen as the file's opening
// comment says.
class Globe {
 public:
  Globe(const std::string& crs, const Point3& sample) : ctx_(proj_context_create()) {
    proj_log_level(ctx_, PJ_LOG_NONE);
    PJ* source = proj_create(ctx_, crs.c_str());
    if (!source) fail("cannot understand the run's CRS '" + crs.substr(0, 80) + "'");
    PJ* target = proj_create(ctx_, "EPSG:4979");
    const bool compound = proj_get_type(source) == PJ_TYPE_COMPOUND_CRS;
    if (compound) {
      // Only a real height transformation (its grid installed) is taken, never a ballpark.
      PJ* op = normalised(source, target);
      if (op) {
        proj_trans(op, PJ_FWD, proj_coord(sample.x, sample.y, sample.z, 0));
        PJ* used = proj_trans_get_last_used_operation(op);
        if (used && !proj_coordoperation_has_ballpark_transformation(ctx_, used)) {
          op_ = op;
          method_ = std::string("heights through ") + proj_get_name(used);
        } else {
          proj_destroy(op);
        }
        if (used) proj_destroy(used);
      }
    }
    if (!op_) {
      PJ* horizontal = compound ? proj_crs_get_sub_crs(ctx_, source, 0) : proj_clone(ctx_, source);
      PJ* promoted = horizontal ? proj_crs_promote_to_3D(ctx_, nullptr, horizontal) : nullptr;
      op_ = promoted ? normalised(promoted, target) : nullptr;
      if (promoted) proj_destroy(promoted);
      if (horizontal) proj_destroy(horizontal);
      method_ = compound ? "heights as heights above the horizontal datum's ellipsoid (PROJ has no grid for the "
                           "vertical datum here)"
                         : "heights as heights above the datum's ellipsoid (the CRS states no vertical datum)";
    }
    proj_destroy(source);
    proj_destroy(target);
    if (!op_) fail("PROJ has no transformation from " + crs.substr(0, 80) + " to WGS 84");
    log_info("3dtiles: " + crs.substr(0, 80) + " to the globe: " + method_);
  }
  ~Globe() {
    if (op_) proj_destroy(op_);
    proj_context_destroy(ctx_);
  }
  Globe(const Globe&) = delete;
  Globe& operator=(const Globe&) = delete;

  Geodetic geodetic(const Point3& p) const {
    const PJ_COORD r = proj_trans(op_, PJ_FWD, proj_coord(p.x, p.y, p.z, 0));
    if (!std::isfinite(r.xyz.x) || !std::isfinite(r.xyz.y) || !std::isfinite(r.xyz.z))
      throw IoError("3dtiles: PROJ cannot place (" + std::to_string(p.x) + ", " + std::to_string(p.y) +
                    ") on the globe: is the run's CRS right?");
    return {r.lpz.lam * kPi / 180.0, r.lpz.phi * kPi / 180.0, r.lpz.z};
  }

 private:
  [[noreturn]] void fail(const std::string& what) {
    proj_context_destroy(ctx_);
    ctx_ = nullptr;
    throw ConfigError("3dtiles: " + what);
  }
  // An operation with x = longitude, y = latitude in degrees, whatever the CRS's axis order.
  PJ* normalised(PJ* source, PJ* target) {
    PJ* op = proj_create_crs_to_crs_from_pj(ctx_, source, target, nullptr, nullptr);
    if (!op) return nullptr;
    PJ* norm = proj_normalize_for_visualization(ctx_, op);
    proj_destroy(op);
    return norm;
  }

  PJ_CONTEXT* ctx_ = nullptr;
  PJ* op_ = nullptr;
  std::string method_;
};

// A local east-north-up frame at a point of the ellipsoid: the tile transform of a leaf.
struct Frame {
  Vec3 origin, east, north, up;
  explicit Frame(const Geodetic& g) : origin(ecef_of(g)) {
    east = {-std::sin(g.lon), std::cos(g.lon), 0};
    north = {-std::sin(g.lat) * std::cos(g.lon), -std::sin(g.lat) * std::sin(g.lon), std::cos(g.lat)};
    up = {std::cos(g.lat) * std::cos(g.lon), std::cos(g.lat) * std::sin(g.lon), std::sin(g.lat)};
  }
  // glTF is y-up: a tile's content is turned by +90 degrees about x into z-up before the tile
  // transform applies, so (east, up, -north) here lands on (east, north, up) there.
  std::array<float, 3> gltf(const Vec3& ecef) const {
    const Vec3 d{ecef.x - origin.x, ecef.y - origin.y, ecef.z - origin.z};
    return {static_cast<float>(dot(east, d)), static_cast<float>(dot(up, d)), static_cast<float>(-dot(north, d))};
  }
  std::array<double, 16> matrix() const {  // column-major
    return {east.x, east.y, east.z, 0, north.x, north.y, north.z, 0, up.x, up.y, up.z, 0, origin.x, origin.y, origin.z, 1};
  }
};

// A region bounding volume: west, south, east, north (radians), lowest and highest height.
struct Region {
  double w = INFINITY, s = INFINITY, e = -INFINITY, n = -INFINITY, lo = INFINITY, hi = -INFINITY;
  bool empty() const { return w > e; }
  void add(const Geodetic& g) {
    w = std::min(w, g.lon), e = std::max(e, g.lon), s = std::min(s, g.lat), n = std::max(n, g.lat);
    lo = std::min(lo, g.h), hi = std::max(hi, g.h);
  }
  void add(const Region& r) {
    if (r.empty()) return;
    w = std::min(w, r.w), e = std::max(e, r.e), s = std::min(s, r.s), n = std::max(n, r.n);
    lo = std::min(lo, r.lo), hi = std::max(hi, r.hi);
  }
  ordered_json json() const { return {{"region", {w, s, e, n, lo, hi}}}; }
};

// --- triangles ---------------------------------------------------------------------------------

// The triangles of a planar polygon (a model face: one ring, simple, any convexity), as triples of
// positions in the face: ear clipping in the plane of the face's largest projection, keeping the
// face's winding. Collinear vertices are dropped; a ring with no ear left (degenerate) is closed by
// a fan.
std::vector<std::array<std::size_t, 3>> triangulate(const std::vector<Point3>& ring) {
  std::vector<std::array<std::size_t, 3>> triangles;
  const std::size_t n = ring.size();
  if (n < 3) return triangles;
  double nx = 0, ny = 0, nz = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Point3& a = ring[i];
    const Point3& b = ring[(i + 1) % n];
    nx += (a.y - b.y) * (a.z + b.z);
    ny += (a.z - b.z) * (a.x + b.x);
    nz += (a.x - b.x) * (a.y + b.y);
  }
  // Drop the axis of the largest normal component; the sign keeps the ring counter-clockwise in 2D.
  const double ax = std::fabs(nx), ay = std::fabs(ny), az = std::fabs(nz);
  std::vector<std::array<double, 2>> p(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Point3& v = ring[i];
    if (az >= ax && az >= ay) p[i] = {v.x, nz >= 0 ? v.y : -v.y};
    else if (ax >= ay) p[i] = {v.y, nx >= 0 ? v.z : -v.z};
    else p[i] = {v.z, ny >= 0 ? v.x : -v.x};
  }
  const auto cross = [&](std::size_t a, std::size_t b, std::size_t c) {
    return (p[b][0] - p[a][0]) * (p[c][1] - p[a][1]) - (p[b][1] - p[a][1]) * (p[c][0] - p[a][0]);
  };
  double scale = 0;
  for (const auto& q : p) scale = std::max({scale, std::fabs(q[0] - p[0][0]), std::fabs(q[1] - p[0][1])});
  const double eps = 1e-12 * std::max(scale * scale, 1e-12);
  std::vector<std::size_t> left(n);
  for (std::size_t i = 0; i < n; ++i) left[i] = i;
  std::size_t misses = 0, i = 0;
  while (left.size() > 3 && misses < left.size()) {
    const std::size_t m = left.size();
    const std::size_t a = left[(i + m - 1) % m], b = left[i % m], c = left[(i + 1) % m];
    const double turn = cross(a, b, c);
    bool ear = turn > eps;
    if (std::fabs(turn) <= eps) {
      left.erase(left.begin() + static_cast<std::ptrdiff_t>(i % m));  // collinear: no triangle
      misses = 0;
      continue;
    }
    for (std::size_t k = 0; ear && k < m; ++k) {
      const std::size_t q = left[k];
      if (q == a || q == b || q == c) continue;
      if (cross(a, b, q) >= -eps && cross(b, c, q) >= -eps && cross(c, a, q) >= -eps) ear = false;
    }
    if (ear) {
      triangles.push_back({a, b, c});
      left.erase(left.begin() + static_cast<std::ptrdiff_t>(i % m));
      misses = 0;
    } else {
      ++i;
      ++misses;
    }
    if (!left.empty()) i %= left.size();
  }
  for (std::size_t k = 1; k + 1 < left.size(); ++k)
    if (std::fabs(cross(left[0], left[k], left[k + 1])) > eps) triangles.push_back({left[0], left[k], left[k + 1]});
  return triangles;
}

// --- metadata ----------------------------------------------------------------------------------

// A property of the class "building": its name in the schema (an identifier), its attribute's
// name, and its type.
enum class PropertyType { int64, float64, string };

struct Property {
  std::string key;        // [A-Za-z_][A-Za-z0-9_]*
  std::string attribute;  // as the building's attributes name it
  PropertyType type = PropertyType::string;
};

// The type that holds every value an attribute takes in the run: INT64 for integers, FLOAT64 for
// numbers (integers among them too), STRING for the rest (text, lists as their JSON, booleans as
// "true" / "false": a BOOLEAN property cannot say null).
PropertyType join(PropertyType a, bool known, const AttributeValue& v) {
  PropertyType t;
  if (std::holds_alternative<std::monostate>(v)) return a;
  if (std::holds_alternative<std::int64_t>(v)) t = PropertyType::int64;
  else if (std::holds_alternative<double>(v)) t = PropertyType::float64;
  else t = PropertyType::string;
  if (!known || a == t) return t;
  if (a == PropertyType::string || t == PropertyType::string) return PropertyType::string;
  return PropertyType::float64;
}

std::string identifier(const std::string& name) {
  std::string key;
  for (char c : name) key += (std::isalnum(static_cast<unsigned char>(c)) || c == '_') && static_cast<unsigned char>(c) < 128 ? c : '_';
  if (key.empty() || std::isdigit(static_cast<unsigned char>(key[0]))) key.insert(key.begin(), '_');
  return key;
}

// Values that stand for null (the Metadata specification's noData).
constexpr std::int64_t kNoInteger = std::numeric_limits<std::int64_t>::min();
constexpr double kNoNumber = -std::numeric_limits<double>::max();

std::string text_of(const AttributeValue& v) {
  if (const bool* b = std::get_if<bool>(&v)) return *b ? "true" : "false";
  if (const std::int64_t* i = std::get_if<std::int64_t>(&v)) return std::to_string(*i);
  if (const double* d = std::get_if<double>(&v)) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, *d);
    return std::string(buf, r.ptr);
  }
  if (const std::string* s = std::get_if<std::string>(&v)) return *s;
  if (const AttributeList* l = std::get_if<AttributeList>(&v)) return l->json;
  return "";
}

// --- one glTF ----------------------------------------------------------------------------------

// The binary buffer of one glTF, its views 8-byte aligned (EXT_structural_metadata asks for it).
class Buffer {
 public:
  template <typename T>
  int view(const std::vector<T>& values, int target, ordered_json& views) {
    return view(values.data(), values.size() * sizeof(T), target, views);
  }
  int view(const void* data, std::size_t bytes, int target, ordered_json& views) {
    while (bytes_.size() % 8) bytes_.push_back(0);
    ordered_json v = {{"buffer", 0}, {"byteOffset", bytes_.size()}, {"byteLength", bytes}};
    if (target) v["target"] = target;
    const auto* p = static_cast<const unsigned char*>(data);
    // Little-endian on every machine glTF is read on; the hosts city3d builds on are too.
    bytes_.insert(bytes_.end(), p, p + bytes);
    views.push_back(std::move(v));
    return static_cast<int>(views.size()) - 1;
  }
  std::vector<unsigned char>& bytes() { return bytes_; }

 private:
  std::vector<unsigned char> bytes_;
};

// The triangles of one semantic surface type across a tile's buildings.
struct Primitive {
  std::vector<float> positions, normals, features;
  std::vector<std::uint32_t> indices;
};

// What one building brings to a tile: its id, the level shown, its attributes (output_attributes())
// and its model at that level.
struct TileBuilding {
  std::string id, lod;
  Attributes attributes;
  const BuildingModel* model = nullptr;
};

// The surface colours (sRGB-ish linear factors): grey ground, off-white walls, red roofs, as the OBJ
// materials and report.html's 3D view.
constexpr std::array<std::array<double, 3>, 3> kSurfaceColours = {{{0.45, 0.45, 0.45}, {0.92, 0.91, 0.87}, {0.80, 0.36, 0.28}}};

std::vector<unsigned char> make_glb(const std::vector<TileBuilding>& buildings, const std::vector<Property>& properties,
                                    const Globe& globe, const Frame& frame, Region& region) {
  Primitive prims[3];
  for (std::size_t b = 0; b < buildings.size(); ++b) {
    const BuildingModel& m = *buildings[b].model;
    std::vector<std::array<float, 3>> local(m.mesh.vertices.size());
    std::vector<Vec3> ecef(m.mesh.vertices.size());
    for (std::size_t v = 0; v < m.mesh.vertices.size(); ++v) {
      const Point3& q = m.mesh.vertices[v];
      const Geodetic g = globe.geodetic({q.x + m.origin.x, q.y + m.origin.y, q.z + m.origin.z});
      region.add(g);
      ecef[v] = ecef_of(g);
      local[v] = frame.gltf(ecef[v]);
    }
    const std::vector<SurfaceType> types = surface_types(m);
    for (std::size_t f = 0; f < m.mesh.faces.size(); ++f) {
      const auto& face = m.mesh.faces[f];
      std::vector<Point3> ring;
      for (std::uint32_t v : face) ring.push_back(m.mesh.vertices[v]);
      const auto triangles = triangulate(ring);
      if (triangles.empty()) continue;
      // The face's normal from its vertices in the glTF frame (Newell).
      double nx = 0, ny = 0, nz = 0;
      for (std::size_t k = 0; k < face.size(); ++k) {
        const auto& a = local[face[k]];
        const auto& c = local[face[(k + 1) % face.size()]];
        nx += (double(a[1]) - c[1]) * (double(a[2]) + c[2]);
        ny += (double(a[2]) - c[2]) * (double(a[0]) + c[0]);
        nz += (double(a[0]) - c[0]) * (double(a[1]) + c[1]);
      }
      const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
      if (!(len > 0)) continue;
      Primitive& p = prims[static_cast<int>(types[f])];
      const std::uint32_t base = static_cast<std::uint32_t>(p.features.size());
      for (std::uint32_t v : face) {
        p.positions.insert(p.positions.end(), local[v].begin(), local[v].end());
        p.normals.insert(p.normals.end(), {float(nx / len), float(ny / len), float(nz / len)});
        p.features.push_back(static_cast<float>(b));
      }
      for (const auto& t : triangles)
        p.indices.insert(p.indices.end(), {base + std::uint32_t(t[0]), base + std::uint32_t(t[1]), base + std::uint32_t(t[2])});
    }
  }

  Buffer buffer;
  ordered_json views = ordered_json::array(), accessors = ordered_json::array(), primitives = ordered_json::array(),
               materials = ordered_json::array();
  for (int t = 0; t < 3; ++t) {
    const Primitive& p = prims[t];
    if (p.indices.empty()) continue;
    const std::size_t count = p.features.size();
    std::array<float, 3> lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    for (std::size_t k = 0; k < count; ++k)
      for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], p.positions[3 * k + c]), hi[c] = std::max(hi[c], p.positions[3 * k + c]);
    const auto accessor = [&](int view, int component, std::size_t n, const char* type) {
      accessors.push_back({{"bufferView", view}, {"componentType", component}, {"count", n}, {"type", type}});
      return static_cast<int>(accessors.size()) - 1;
    };
    const int position = accessor(buffer.view(p.positions, kArrayBuffer, views), kFloat, count, "VEC3");
    accessors[position]["min"] = {lo[0], lo[1], lo[2]};
    accessors[position]["max"] = {hi[0], hi[1], hi[2]};
    const int normal = accessor(buffer.view(p.normals, kArrayBuffer, views), kFloat, count, "VEC3");
    const int feature = accessor(buffer.view(p.features, kArrayBuffer, views), kFloat, count, "SCALAR");
    const int indices = accessor(buffer.view(p.indices, kElementArrayBuffer, views), kUnsignedInt, p.indices.size(), "SCALAR");
    materials.push_back({{"name", surface_type_name(static_cast<SurfaceType>(t))},
                         {"pbrMetallicRoughness",
                          {{"baseColorFactor", {kSurfaceColours[t][0], kSurfaceColours[t][1], kSurfaceColours[t][2], 1.0}},
                           {"metallicFactor", 0.0},
                           {"roughnessFactor", 1.0}}}});
    primitives.push_back(
        {{"attributes", {{"POSITION", position}, {"NORMAL", normal}, {"_FEATURE_ID_0", feature}}},
         {"indices", indices},
         {"material", static_cast<int>(materials.size()) - 1},
         {"mode", 4},
         {"extensions",
          {{"EXT_mesh_features",
            {{"featureIds", {{{"featureCount", buildings.size()}, {"attribute", 0}, {"propertyTable", 0}}}}}}}}});
  }

  // The property table: one row per building, one column per property.
  ordered_json table_properties = ordered_json::object();
  for (const Property& property : properties) {
    // The first two properties are the building's id and the level shown; the others its attributes.
    const bool own = &property == &properties[0] || &property == &properties[1];
    std::vector<AttributeValue> own_values;
    std::vector<const AttributeValue*> column(buildings.size(), nullptr);
    if (own) {
      for (const TileBuilding& b : buildings) own_values.emplace_back(&property == &properties[0] ? b.id : b.lod);
      for (std::size_t b = 0; b < buildings.size(); ++b) column[b] = &own_values[b];
    } else {
      for (std::size_t b = 0; b < buildings.size(); ++b)
        for (const auto& [name, value] : buildings[b].attributes)
          if (name == property.attribute && !column[b]) column[b] = &value;
    }
    if (property.type == PropertyType::int64) {
      std::vector<std::int64_t> values;
      for (const AttributeValue* v : column) {
        const std::int64_t* i = v ? std::get_if<std::int64_t>(v) : nullptr;
        values.push_back(i ? *i : kNoInteger);
      }
      table_properties[property.key] = {{"values", buffer.view(values, 0, views)}};
    } else if (property.type == PropertyType::float64) {
      std::vector<double> values;
      for (const AttributeValue* v : column) {
        double d = kNoNumber;
        if (v && std::holds_alternative<double>(*v)) d = std::get<double>(*v);
        if (v && std::holds_alternative<std::int64_t>(*v)) d = static_cast<double>(std::get<std::int64_t>(*v));
        values.push_back(std::isfinite(d) ? d : kNoNumber);
      }
      table_properties[property.key] = {{"values", buffer.view(values, 0, views)}};
    } else {
      std::string text;
      std::vector<std::uint32_t> offsets{0};
      for (const AttributeValue* v : column) {
        text += v ? text_of(*v) : "";
        offsets.push_back(static_cast<std::uint32_t>(text.size()));
      }
      // A column of nothing but noData is left out (a buffer view cannot be empty); the class says
      // what readers make of a property a table does not give: its noData.
      if (text.empty()) continue;
      const int values = buffer.view(text.data(), text.size(), 0, views);
      table_properties[property.key] = {{"values", values}, {"stringOffsets", buffer.view(offsets, 0, views)}};
    }
  }
  ordered_json class_properties = ordered_json::object();
  for (const Property& property : properties) {
    ordered_json p;
    if (property.key != property.attribute) p["name"] = property.attribute;
    if (property.type == PropertyType::int64) p.update({{"type", "SCALAR"}, {"componentType", "INT64"}, {"noData", kNoInteger}});
    else if (property.type == PropertyType::float64) p.update({{"type", "SCALAR"}, {"componentType", "FLOAT64"}, {"noData", kNoNumber}});
    else p.update({{"type", "STRING"}});
    if (&property == &properties[0] || &property == &properties[1]) p["required"] = true;
    else if (property.type == PropertyType::string) p["noData"] = "";
    class_properties[property.key] = std::move(p);
  }
  while (buffer.bytes().size() % 8) buffer.bytes().push_back(0);

  ordered_json gltf = {
      {"asset", {{"version", "2.0"}, {"generator", std::string("city3d ") + CITY3D_VERSION}}},
      {"extensionsUsed", {"EXT_mesh_features", "EXT_structural_metadata"}},
      {"extensions",
       {{"EXT_structural_metadata",
         {{"schema", {{"id", "city3d"}, {"classes", {{"building", {{"name", "Building"}, {"properties", class_properties}}}}}}},
          {"propertyTables", {{{"class", "building"}, {"count", buildings.size()}, {"properties", table_properties}}}}}}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"mesh", 0}}}},
      {"meshes", {{{"primitives", primitives}}}},
      {"materials", materials},
      {"accessors", accessors},
      {"bufferViews", views},
      {"buffers", {{{"byteLength", buffer.bytes().size()}}}},
  };
  // GLB: header, JSON chunk padded with spaces, BIN chunk padded with zeros, both to 8 bytes.
  std::string json_text = gltf.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  while (json_text.size() % 8) json_text += ' ';
  const std::vector<unsigned char>& bin = buffer.bytes();
  std::vector<unsigned char> glb;
  const auto put32 = [&glb](std::uint32_t v) {
    for (int k = 0; k < 4; ++k) glb.push_back(static_cast<unsigned char>(v >> (8 * k)));
  };
  const std::uint32_t total = 12 + 8 + static_cast<std::uint32_t>(json_text.size()) + 8 + static_cast<std::uint32_t>(bin.size());
  put32(0x46546C67);  // "glTF"
  put32(2);
  put32(total);
  put32(static_cast<std::uint32_t>(json_text.size()));
  put32(0x4E4F534A);  // "JSON"
  glb.insert(glb.end(), json_text.begin(), json_text.end());
  put32(static_cast<std::uint32_t>(bin.size()));
  put32(0x004E4942);  // "BIN\0"
  glb.insert(glb.end(), bin.begin(), bin.end());
  return glb;
}

// --- the tileset -------------------------------------------------------------------------------

// What the tiling needs of one building, from the first pass.
struct Summary {
  std::size_t record = 0;
  double x = 0, y = 0;       // plan-view centre of its model's box
  double height = 0;         // highest vertex above its ground: the error of not drawing it
  double coarse_error = 0;   // how far its lowest level's roof lies from its highest level's vertices
  bool levels = false;       // it has more than one level
};

struct Node {
  int level = 0;
  std::int64_t x = 0, y = 0;
  std::vector<std::size_t> buildings;  // indices into the summaries
  std::vector<Node> children;          // non-empty quadrants
};

void split(Node& node, const std::vector<Summary>& all, double x0, double y0, double size) {
  if (node.buildings.size() <= kMaxBuildingsPerTile || size / 2 < kMinTileSize || node.level >= kMaxDepth) return;
  const double half = size / 2;
  Node quadrants[4];
  for (int q = 0; q < 4; ++q) {
    quadrants[q].level = node.level + 1;
    quadrants[q].x = 2 * node.x + (q & 1);
    quadrants[q].y = 2 * node.y + (q >> 1);
  }
  for (std::size_t i : node.buildings) {
    const int qx = all[i].x >= x0 + half ? 1 : 0, qy = all[i].y >= y0 + half ? 1 : 0;
    quadrants[qx + 2 * qy].buildings.push_back(i);
  }
  node.buildings.clear();
  for (int q = 0; q < 4; ++q) {
    if (quadrants[q].buildings.empty()) continue;
    split(quadrants[q], all, x0 + (q & 1) * half, y0 + (q >> 1) * half, half);
    node.children.push_back(std::move(quadrants[q]));
  }
}

void write_file(const fs::path& path, const void* data, std::size_t size) {
  detail::AtomicFile file(path.string());
  if (std::fwrite(data, 1, size, file.file()) != size) throw IoError("3dtiles: cannot write " + path.string());
  file.commit();
}

class TilesetWriter {
 public:
  TilesetWriter(const fs::path& folder, const OverviewSource& records, const std::vector<Summary>& all,
                const std::vector<Property>& properties, const Globe& globe)
      : folder_(folder), records_(records), all_(all), properties_(properties), globe_(globe) {}

  // The tile of `node` (and its files); fills `error` and `region` for the parent.
  ordered_json tile(const Node& node, double& error, Region& region) {
    if (node.children.empty()) return leaf(node, error, region);
    ordered_json children = ordered_json::array();
    double height = 0, child_errors = 0;
    for (const Node& child : node.children) {
      double e = 0;
      Region r;
      children.push_back(tile(child, e, r));
      child_errors = std::max(child_errors, e);
      region.add(r);
    }
    for_each_building(node, [&](std::size_t i) { height = std::max(height, all_[i].height); });
    // Not drawing a cell leaves out its buildings: its error is its tallest building's height.
    error = std::max(height, child_errors);
    return {{"boundingVolume", region.json()}, {"geometricError", error}, {"refine", "REPLACE"}, {"children", children}};
  }

  const std::vector<std::string>& written() const { return written_; }

 private:
  template <typename F>
  void for_each_building(const Node& node, F f) {
    for (std::size_t i : node.buildings) f(i);
    for (const Node& child : node.children) for_each_building(child, f);
  }

  ordered_json leaf(const Node& node, double& error, Region& region) {
    // The leaf's frame: at its buildings' mean centre, on the ground of the first.
    double cx = 0, cy = 0, coarse_error = 0;
    bool refined = false;
    for (std::size_t i : node.buildings) {
      cx += all_[i].x, cy += all_[i].y;
      coarse_error = std::max(coarse_error, all_[i].coarse_error);
      refined = refined || all_[i].levels;
    }
    cx /= node.buildings.size(), cy /= node.buildings.size();
    const Geodetic centre = globe_.geodetic({cx, cy, 0});
    const Frame frame({centre.lon, centre.lat, 0});
    // The buildings, read once: the lowest level of each for the coarse tile, the highest for the fine.
    std::vector<OverviewRecord> records;
    for (std::size_t i : node.buildings) records.push_back(records_.at(all_[i].record, true));
    const auto content = [&](bool fine) {
      std::vector<TileBuilding> buildings;
      for (const OverviewRecord& r : records) {
        const CityGeometry& g = fine ? r.lods.back() : r.lods.front();
        TileBuilding b;
        b.id = r.report.id;
        b.lod = g.lod;
        b.attributes = detail::output_attributes(r.report, r.footprint_attributes, false);
        b.model = &g.model;
        buildings.push_back(std::move(b));
      }
      return buildings;
    };
    const std::string name = std::to_string(node.level) + "_" + std::to_string(node.x) + "_" + std::to_string(node.y);
    Region coarse_region, fine_region;
    const std::vector<unsigned char> coarse = make_glb(content(false), properties_, globe_, frame, coarse_region);
    write_file(folder_ / "tiles" / (name + "_coarse.glb"), coarse.data(), coarse.size());
    written_.push_back("tiles/" + name + "_coarse.glb");
    region = coarse_region;
    ordered_json tile = {{"boundingVolume", nullptr},
                         {"geometricError", refined ? coarse_error : 0.0},
                         {"refine", "REPLACE"},
                         {"transform", frame.matrix()},
                         {"content", {{"uri", "tiles/" + name + "_coarse.glb"}}}};
    if (refined) {
      const std::vector<unsigned char> fine = make_glb(content(true), properties_, globe_, frame, fine_region);
      write_file(folder_ / "tiles" / (name + "_fine.glb"), fine.data(), fine.size());
      written_.push_back("tiles/" + name + "_fine.glb");
      region.add(fine_region);
      // The same box for both (the parent's must hold the child's); heights within 0.1 mm.
      tile["children"] = {{{"boundingVolume", region.json()},
                           {"geometricError", 0.0},
                           {"refine", "REPLACE"},
                           {"content", {{"uri", "tiles/" + name + "_fine.glb"}}}}};
    }
    tile["boundingVolume"] = region.json();
    error = refined ? coarse_error : 0.0;
    return tile;
  }

  fs::path folder_;
  const OverviewSource& records_;
  const std::vector<Summary>& all_;
  const std::vector<Property>& properties_;
  const Globe& globe_;
  std::vector<std::string> written_;
};

}  // namespace

std::vector<std::string> write_3dtiles(const std::string& folder, const OverviewSource& records, const std::string& crs) {
  if (crs.empty()) throw ConfigError("3dtiles: the run has no CRS: its tileset cannot be placed on the globe (give --crs)");
  // First pass: what the tiling needs of each building, and the attributes' types.
  std::vector<Summary> all;
  std::vector<std::string> names;
  std::map<std::string, std::pair<PropertyType, bool>> types;  // attribute -> type, known
  Box2 extent;
  for (std::size_t k = 0; k < records.size(); ++k) {
    const OverviewRecord r = records.at(k, true);
    if (r.lods.empty()) continue;
    Summary s;
    s.record = k;
    const BuildingModel& fine = r.lods.back().model;
    const BuildingModel& coarse = r.lods.front().model;
    Box3 box;
    for (const Point3& p : fine.mesh.vertices) box.add({p.x + fine.origin.x, p.y + fine.origin.y, p.z + fine.origin.z});
    s.x = (box.min.x + box.max.x) / 2, s.y = (box.min.y + box.max.y) / 2;
    extent.add({s.x, s.y});
    const double ground = std::isfinite(r.report.ground_z) ? r.report.ground_z : box.min.z;
    s.height = std::max(0.0, box.max.z - ground);
    s.levels = r.lods.size() > 1;
    if (s.levels) {
      // How far the coarse model's roof is from the fine model's roof vertices, in height: for a
      // block, its top against the ridge and the eaves.
      double top = -INFINITY;
      for (const Point3& p : coarse.mesh.vertices) top = std::max(top, p.z + coarse.origin.z);
      const std::vector<SurfaceType> types_of = surface_types(fine);
      for (std::size_t f = 0; f < fine.mesh.faces.size(); ++f)
        if (types_of[f] == SurfaceType::roof)
          for (std::uint32_t v : fine.mesh.faces[f])
            s.coarse_error = std::max(s.coarse_error, std::fabs(fine.mesh.vertices[v].z + fine.origin.z - top));
    }
    // Errors and heights to the millimetre, as the attributes (no binary noise in tileset.json).
    s.coarse_error = std::round(s.coarse_error * 1000) / 1000;
    s.height = std::round(s.height * 1000) / 1000;
    all.push_back(s);
    for (const auto& [name, value] : detail::output_attributes(r.report, r.footprint_attributes, false)) {
      const auto [it, fresh] = types.emplace(name, std::make_pair(PropertyType::string, false));
      if (fresh) names.push_back(name);
      const bool known = it->second.second || !std::holds_alternative<std::monostate>(value);
      it->second.first = join(it->second.first, it->second.second, value);
      it->second.second = known;
    }
  }
  if (all.empty()) throw IoError("3dtiles: no building has a model: no tileset is written into " + folder);
  // The schema: id and the level shown first, then every attribute (names made identifiers, unique).
  std::vector<Property> properties = {{"id", "id", PropertyType::string}, {"lod", "lod", PropertyType::string}};
  std::map<std::string, int> taken = {{"id", 1}, {"lod", 1}};
  for (const std::string& name : names) {
    std::string key = identifier(name);
    while (taken.count(key)) key += "_";
    taken[key] = 1;
    properties.push_back({key, name, types[name].first});
  }

  // The quadtree over the buildings' centres, in a square from the extent's corner.
  Node root;
  for (std::size_t i = 0; i < all.size(); ++i) root.buildings.push_back(i);
  const double size = std::max({extent.max.x - extent.min.x, extent.max.y - extent.min.y, kMinTileSize}) * (1 + 1e-9);
  split(root, all, extent.min.x, extent.min.y, size);

  const Globe globe(crs, {(extent.min.x + extent.max.x) / 2, (extent.min.y + extent.max.y) / 2, 0});
  std::error_code ec;
  fs::create_directories(fs::path(folder) / "tiles", ec);
  if (ec) throw IoError("3dtiles: cannot create " + (fs::path(folder) / "tiles").string() + ": " + ec.message());
  TilesetWriter writer(folder, records, all, properties, globe);
  double error = 0;
  Region region;
  ordered_json root_tile = writer.tile(root, error, region);
  // Not drawing the tileset at all leaves out every building: the tallest one's height.
  double tallest = 0;
  for (const Summary& s : all) tallest = std::max(tallest, s.height);
  ordered_json tileset = {{"asset", {{"version", "1.1"}, {"generator", std::string("city3d ") + CITY3D_VERSION}}},
                          {"geometricError", std::max(error, tallest)},
                          {"root", root_tile}};
  const std::string text = tileset.dump(1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
  write_file(fs::path(folder) / "tileset.json", text.data(), text.size());
  std::vector<std::string> written = writer.written();
  written.push_back("tileset.json");
  return written;
}

}  // namespace city3d
