// CityJSON 2.0 and CityJSONSeq writers: Buildings with one Solid per level of detail (BuildingParts
// for a level whose model has several parts), semantic surfaces, the run's quantising transform and
// attributes. Output is byte-deterministic (fixed key order, shortest round-trip number formatting).
// Written by hand, not with nlohmann like the other JSON (issue 26), because the byte layout is the
// point: the files are compared byte for byte (a run, a resumed run, a merge of shards, two builds),
// each feature's text is spliced into them as it is (FeatureSplicer), and some numbers take forms
// nlohmann does not write (the scale as 0.0001, the extent's world coordinates with the scale's decimals).
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <map>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/model_io.hpp"
#include "core/json_text.hpp"
#include "core/mesh_faces.hpp"
#include "files/atomic_file.hpp"

namespace city3d {
namespace {

using detail::append_json_string;
using detail::JsonEscapes;

void append_number(std::string& out, double v) {
  if (!std::isfinite(v)) {
    out += "null";
    return;
  }
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

void append_value(std::string& out, const AttributeValue& v) {
  if (std::holds_alternative<std::monostate>(v)) out += "null";
  else if (const bool* b = std::get_if<bool>(&v)) out += *b ? "true" : "false";
  else if (const std::int64_t* i = std::get_if<std::int64_t>(&v)) out += std::to_string(*i);
  else if (const double* d = std::get_if<double>(&v)) append_number(out, *d);
  else if (const AttributeList* l = std::get_if<AttributeList>(&v)) out += l->json;
  else append_json_string(out, std::get<std::string>(v), JsonEscapes::short_controls);
}

// "EPSG:7415" -> the OGC URL CityJSON 2.0 expects; "EPSG:28992+5709" (a compound without a code of
// its own) -> OGC's URL of a compound of the two; anything else is not written.
std::string crs_url(const std::string& crs) {
  if (crs.rfind("EPSG:", 0) != 0) return {};
  const std::string code = crs.substr(5);
  const std::size_t plus = code.find('+');
  if (plus == std::string::npos) return "https://www.opengis.net/def/crs/EPSG/0/" + code;
  return "https://www.opengis.net/def/crs-compound?1=https://www.opengis.net/def/crs/EPSG/0/" + code.substr(0, plus) +
         "&2=https://www.opengis.net/def/crs/EPSG/0/" + code.substr(plus + 1);
}

// Digits after the decimal point of a transform scale (0.0001 -> 4): world coordinates made from
// quantised ones are printed with these, without binary noise (84123.4567, not 84123.456699999995).
int scale_decimals(double scale) {
  int decimals = 0;
  for (double s = scale; s < 0.999999 && decimals < 12; s *= 10) ++decimals;
  return decimals;
}

void append_world(std::string& out, double quantised, double scale, double translate) {
  detail::append_trimmed_number(out, translate + quantised * scale, scale_decimals(scale));
}

using Quantised = std::tuple<std::int64_t, std::int64_t, std::int64_t>;

// The faces of a model grouped into edge-connected parts, parts in order of their first face.
std::vector<std::vector<std::size_t>> model_parts(const BuildingModel& m) {
  const std::vector<std::size_t> part_of = detail::edge_connected_parts(m.mesh.faces);
  std::vector<std::vector<std::size_t>> parts;
  for (std::size_t f = 0; f < part_of.size(); ++f) {
    if (part_of[f] == parts.size()) parts.emplace_back();  // the part's first face
    parts[part_of[f]].push_back(f);
  }
  return parts;
}

// Appends one Solid of the given faces of a geometry's model, with semantic surfaces of the types
// those faces use, in the order ground, wall, roof. `remap` takes model vertices to the building's
// shared vertex list.
void append_solid(std::string& out, const CityGeometry& g, const std::vector<std::size_t>& faces,
                  const std::vector<SurfaceType>& types, const std::vector<std::size_t>& remap) {
  const BuildingModel& m = g.model;
  bool used[3] = {false, false, false};
  for (std::size_t f : faces) used[static_cast<int>(types[f])] = true;
  int surface_index[3] = {-1, -1, -1};
  int n_surfaces = 0;
  for (int t = 0; t < 3; ++t)
    if (used[t]) surface_index[t] = n_surfaces++;
  out += "{\"type\":\"Solid\",\"lod\":";
  append_json_string(out, g.lod, JsonEscapes::short_controls);
  out += ",\"boundaries\":[[";
  for (std::size_t i = 0; i < faces.size(); ++i) {
    if (i) out += ',';
    out += "[[";
    bool first = true;
    std::size_t previous = static_cast<std::size_t>(-1);
    for (std::uint32_t v : m.mesh.faces[faces[i]]) {
      const std::size_t q = remap[v];
      if (q == previous) continue;  // consecutive vertices merged by quantisation
      if (!first) out += ',';
      out += std::to_string(q);
      first = false;
      previous = q;
    }
    out += "]]";
  }
  out += "]],\"semantics\":{\"surfaces\":[";
  for (int t = 0, k = 0; t < 3; ++t) {
    if (!used[t]) continue;
    if (k++) out += ',';
    out += "{\"type\":\"";
    out += surface_type_name(static_cast<SurfaceType>(t));
    out += "\"}";
  }
  out += "],\"values\":[[";
  for (std::size_t i = 0; i < faces.size(); ++i) {
    if (i) out += ',';
    out += std::to_string(surface_index[static_cast<int>(types[faces[i]])]);
  }
  out += "]]}}";
}

// Appends the CityObject member `"id":{...}`: a Building with its attributes and one Solid per level
// of detail, vertices shared across its levels. A level whose model has several parts (detached
// blocks of a multipolygon footprint) cannot be one Solid (one exterior shell) and a Building has no
// MultiSolid: each part becomes a child BuildingPart "<id>-<lod>-<k>" with that level's Solid, so
// every Solid written is valid on its own.
void append_city_object(std::string& out, const CityObject& object, const Point3& translate, double scale,
                        std::vector<Quantised>& vertices) {
  std::map<Quantised, std::size_t> index_of;
  std::string geometry;
  std::vector<std::pair<std::string, std::string>> parts;  // id, geometry
  for (const CityGeometry& g : object.geometries) {
    const BuildingModel& m = g.model;
    std::vector<std::size_t> remap(m.mesh.vertices.size());
    for (std::size_t i = 0; i < m.mesh.vertices.size(); ++i) {
      const Point3& p = m.mesh.vertices[i];
      const Quantised q{std::llround((p.x + m.origin.x - translate.x) / scale),
                        std::llround((p.y + m.origin.y - translate.y) / scale),
                        std::llround((p.z + m.origin.z - translate.z) / scale)};
      const auto [it, inserted] = index_of.emplace(q, vertices.size());
      if (inserted) vertices.push_back(q);
      remap[i] = it->second;
    }
    const std::vector<SurfaceType> types = surface_types(m);
    const std::vector<std::vector<std::size_t>> model_faces = model_parts(m);
    if (model_faces.size() == 1) {
      if (!geometry.empty()) geometry += ',';
      append_solid(geometry, g, model_faces.front(), types, remap);
      continue;
    }
    for (std::size_t k = 0; k < model_faces.size(); ++k) {
      std::string solid;
      append_solid(solid, g, model_faces[k], types, remap);
      parts.emplace_back(object.id + "-" + g.lod + "-" + std::to_string(k + 1), std::move(solid));
    }
  }
  append_json_string(out, object.id, JsonEscapes::short_controls);
  out += ":{\"type\":\"Building\",\"attributes\":{";
  for (std::size_t a = 0; a < object.attributes.size(); ++a) {
    if (a) out += ',';
    append_json_string(out, object.attributes[a].first, JsonEscapes::short_controls);
    out += ':';
    append_value(out, object.attributes[a].second);
  }
  out += "},\"geometry\":[" + geometry + "]";
  if (!parts.empty()) {
    out += ",\"children\":[";
    for (std::size_t k = 0; k < parts.size(); ++k) {
      if (k) out += ',';
      append_json_string(out, parts[k].first, JsonEscapes::short_controls);
    }
    out += ']';
  }
  out += '}';
  for (const auto& [id, solid] : parts) {
    out += ',';
    append_json_string(out, id, JsonEscapes::short_controls);
    out += ":{\"type\":\"BuildingPart\",\"parents\":[";
    append_json_string(out, object.id, JsonEscapes::short_controls);
    out += "],\"geometry\":[" + solid + "]}";
  }
}

void append_vertices(std::string& out, const std::vector<Quantised>& vertices) {
  out += "\"vertices\":[";
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    if (i) out += ',';
    out += '[';
    out += std::to_string(std::get<0>(vertices[i]));
    out += ',';
    out += std::to_string(std::get<1>(vertices[i]));
    out += ',';
    out += std::to_string(std::get<2>(vertices[i]));
    out += ']';
  }
  out += ']';
}

// `extent` is of quantised vertices (integers held as doubles); nullptr or empty: no extent.
void append_header_fields(std::string& out, const CityJsonOptions& options, const Point3& translate,
                          const Box3* extent) {
  out += "\"type\":\"CityJSON\",\"version\":\"2.0\",\"transform\":{\"scale\":[";
  for (int i = 0; i < 3; ++i) {
    if (i) out += ',';
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.10g", options.scale);  // "0.0001", not "1e-04"
    out += buf;
  }
  out += "],\"translate\":[";
  append_number(out, translate.x);
  out += ',';
  append_number(out, translate.y);
  out += ',';
  append_number(out, translate.z);
  out += "]},\"metadata\":{";
  bool any = false;
  if (const std::string url = crs_url(options.crs); !url.empty()) {
    out += "\"referenceSystem\":";
    append_json_string(out, url, JsonEscapes::short_controls);
    any = true;
  }
  if (!options.reference_date.empty()) {
    if (any) out += ',';
    out += "\"referenceDate\":";
    append_json_string(out, options.reference_date, JsonEscapes::short_controls);
    any = true;
  }
  if (extent && !extent->empty()) {
    if (any) out += ',';
    out += "\"geographicalExtent\":[";
    const double corners[6] = {extent->min.x, extent->min.y, extent->min.z, extent->max.x, extent->max.y, extent->max.z};
    const double origin[3] = {translate.x, translate.y, translate.z};
    for (int k = 0; k < 6; ++k) {
      if (k) out += ',';
      append_world(out, corners[k], options.scale, origin[k % 3]);
    }
    out += ']';
    any = true;
  }
  if (!options.city3d.empty()) {
    if (any) out += ',';
    out += "\"city3d\":";
    out += options.city3d;
  }
  out += '}';
}

void add_to_extent(Box3& extent, const std::vector<Quantised>& vertices) {
  for (const Quantised& q : vertices)
    extent.add({static_cast<double>(std::get<0>(q)), static_cast<double>(std::get<1>(q)),
                static_cast<double>(std::get<2>(q))});
}

void check_options(const CityJsonOptions& options, const std::string& path) {
  if (!(options.scale > 0.0) || !std::isfinite(options.scale))
    throw IoError("cityjson: scale must be positive for " + path);
}

void write_all(std::FILE* f, const std::string& text) { std::fwrite(text.data(), 1, text.size(), f); }

}  // namespace

std::vector<SurfaceType> surface_types(const BuildingModel& model) {
  if (model.surfaces.size() == model.mesh.faces.size()) return model.surfaces;
  std::vector<SurfaceType> types;
  types.reserve(model.mesh.faces.size());
  for (const auto& face : model.mesh.faces) {
    // Newell's normal: robust for any planar (or nearly planar) polygon.
    const auto [nx, ny, nz] = detail::newell_normal(model.mesh.vertices, face);
    const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
    const double cz = len > 0 ? nz / len : 0.0;
    // |cos| below 0.1 (more than ~84 degrees from horizontal) counts as a wall.
    types.push_back(cz < -0.1 ? SurfaceType::ground : (cz <= 0.1 ? SurfaceType::wall : SurfaceType::roof));
  }
  return types;
}

void write_cityjson(const std::string& path, const std::vector<CityObject>& objects, const CityJsonOptions& options) {
  Point3 translate{0, 0, 0};
  Box3 box;
  for (const CityObject& o : objects)
    for (const CityGeometry& g : o.geometries)
      for (const Point3& p : g.model.mesh.vertices)
        box.add({p.x + g.model.origin.x, p.y + g.model.origin.y, p.z + g.model.origin.z});
  if (!box.empty()) {
    // A translation on the scale's grid keeps quantised coordinates exact multiples of the scale.
    translate = {std::floor(box.min.x), std::floor(box.min.y), std::floor(box.min.z)};
  }
  write_cityjson(path, objects, options, translate);
}

void write_cityjson(const std::string& path, const std::vector<CityObject>& objects, const CityJsonOptions& options,
                    const Point3& translate) {
  check_options(options, path);
  std::string body = ",\"CityObjects\":{";
  std::vector<Quantised> vertices;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    if (i) body += ',';
    append_city_object(body, objects[i], translate, options.scale, vertices);
  }
  body += "},";
  append_vertices(body, vertices);
  body += "}\n";
  Box3 extent;
  add_to_extent(extent, vertices);
  std::string out = "{";
  append_header_fields(out, options, translate, &extent);
  out += body;
  detail::AtomicFile file(path);
  write_all(file.file(), out);
  file.commit();
}

struct CityJsonSeqWriter::Impl {
  std::string path;
  CityJsonOptions options;
  Point3 translate;
  std::unique_ptr<CityJsonSeqAssembler> assembler;
};

CityJsonSeqWriter::CityJsonSeqWriter(const std::string& path, const CityJsonOptions& options,
                                     const Point3& translate)
    : impl_(new Impl{path, options, translate, nullptr}) {
  check_options(options, path);
  impl_->assembler = std::make_unique<CityJsonSeqAssembler>(path, options, translate);
}

CityJsonSeqWriter::~CityJsonSeqWriter() = default;

void CityJsonSeqWriter::add(const CityObject& object) {
  if (!impl_->assembler) throw IoError("cityjson: " + impl_->path + " is already closed");
  impl_->assembler->add(cityjson_feature(object, impl_->options, impl_->translate));
}

void CityJsonSeqWriter::close() {
  if (!impl_->assembler) return;
  impl_->assembler->close();
  impl_->assembler.reset();
}

std::string cityjson_feature(const CityObject& object, const CityJsonOptions& options, const Point3& translate) {
  check_options(options, object.id);
  std::string line = "{\"type\":\"CityJSONFeature\",\"id\":";
  append_json_string(line, object.id, JsonEscapes::short_controls);
  line += ",\"CityObjects\":{";
  std::vector<Quantised> vertices;
  append_city_object(line, object, translate, options.scale, vertices);
  line += "},";
  append_vertices(line, vertices);
  line += "}";
  return line;
}

std::string cityjson_seq_header(const CityJsonOptions& options, const Point3& translate, const Box3* extent) {
  std::string header = "{";
  append_header_fields(header, options, translate, extent);
  header += ",\"CityObjects\":{},\"vertices\":[]}";
  return header;
}

namespace {

// A byte-preserving walk over one CityJSONFeature text: copies its CityObjects members and its
// vertices unchanged, except that every integer inside a "boundaries" value (the only place CityJSON
// refers to the vertex list) is moved by the number of vertices already in the file. Nothing is
// re-serialised, so whatever a feature holds (attributes, several geometries, LoDs) reaches the
// CityJSON file byte for byte.
class FeatureSplicer {
 public:
  FeatureSplicer(const std::string& text, std::size_t feature_number, std::uint64_t offset)
      : s_(text), feature_(feature_number), offset_(offset) {}

  /// Appends the feature's CityObjects members to `objects` and its vertices to `vertices` (both
  /// without brackets; empty when there are none), and adds the vertices (quantised) to `extent`;
  /// returns the number of vertices.
  std::uint64_t split(std::string& objects, std::string& vertices, Box3& extent) {
    std::uint64_t count = 0;
    bool seen_objects = false, seen_vertices = false;
    skip_ws();
    expect('{');
    skip_ws();
    if (peek() == '}') fail("no CityObjects");
    each_element('}', nullptr, [&] {
      const std::string key = read_key();
      skip_ws();
      expect(':');
      skip_ws();
      if (key == "CityObjects") {
        seen_objects = true;
        expect('{');
        copy_members(objects, false);
      } else if (key == "vertices") {
        seen_vertices = true;
        expect('[');
        each_element(']', &vertices, [&] {
          const std::size_t begin = p_;
          extent.add(read_vertex());
          vertices.append(s_, begin, p_ - begin);
          ++count;
        });
      } else {
        skip_value(0);
      }
    });
    skip_ws();
    if (p_ != s_.size()) fail("text after the feature");
    if (!seen_objects || !seen_vertices) fail(seen_objects ? "no vertices" : "no CityObjects");
    return count;
  }

 private:
  static constexpr int kMaxDepth = 64;

  [[noreturn]] void fail(const std::string& what) const {
    throw IoError("cityjson: feature " + std::to_string(feature_) + " is not a CityJSONFeature: " + what +
                  " at byte " + std::to_string(p_));
  }
  char peek() const {
    if (p_ >= s_.size()) fail("unexpected end");
    return s_[p_];
  }
  void expect(char c) {
    if (peek() != c) fail(std::string("expected '") + c + "'");
    ++p_;
  }
  void skip_ws() {
    while (p_ < s_.size() && (s_[p_] == ' ' || s_[p_] == '\t' || s_[p_] == '\n' || s_[p_] == '\r')) ++p_;
  }
  // A string token starting at p_ (the quote); returns its raw text without the quotes.
  std::string read_string_raw() {
    expect('"');
    const std::size_t begin = p_;
    while (peek() != '"') p_ += peek() == '\\' ? 2 : 1;
    const std::string raw = s_.substr(begin, p_ - begin);
    ++p_;
    return raw;
  }
  std::string read_key() { return read_string_raw(); }
  // The elements of an array or object whose opening bracket has been consumed, up to and including
  // `close`: `element` reads one from its first non-blank character, and the commas between them are
  // copied to `commas` unless it is null.
  template <class Element>
  void each_element(char close, std::string* commas, Element element) {
    skip_ws();
    if (peek() == close) {
      ++p_;
      return;
    }
    for (;;) {
      skip_ws();
      element();
      skip_ws();
      if (peek() == close) {
        ++p_;
        return;
      }
      expect(',');
      if (commas) *commas += ',';
    }
  }
  // One vertex "[x,y,z]" of integers.
  Point3 read_vertex() {
    double q[3];
    expect('[');
    for (int k = 0; k < 3; ++k) {
      skip_ws();
      const std::size_t begin = p_;
      skip_number();
      std::int64_t v = 0;
      const auto r = std::from_chars(s_.data() + begin, s_.data() + p_, v);
      if (r.ec != std::errc() || r.ptr != s_.data() + p_) fail("a vertex coordinate that is not an integer");
      q[k] = static_cast<double>(v);
      skip_ws();
      if (k < 2) expect(',');
    }
    expect(']');
    return {q[0], q[1], q[2]};
  }
  void skip_number() {
    const std::size_t begin = p_;
    while (p_ < s_.size() && std::strchr("+-0123456789.eE", s_[p_]) != nullptr) ++p_;
    if (p_ == begin) fail("unexpected character");
  }
  void skip_value(int depth) {
    if (depth > kMaxDepth) fail("nested too deeply");
    const char c = peek();
    if (c == '"') {
      read_string_raw();
    } else if (c == '{' || c == '[') {
      ++p_;
      each_element(c == '{' ? '}' : ']', nullptr, [&] {
        if (c == '{') {
          read_string_raw();
          skip_ws();
          expect(':');
          skip_ws();
        }
        skip_value(depth + 1);
      });
    } else if (s_.compare(p_, 4, "true") == 0 || s_.compare(p_, 4, "null") == 0) {
      p_ += 4;
    } else if (s_.compare(p_, 5, "false") == 0) {
      p_ += 5;
    } else {
      skip_number();
    }
  }
  // Copies a value, moving vertex indices when `shift` (inside "boundaries").
  void copy_value(std::string& out, bool shift, int depth) {
    if (depth > kMaxDepth) fail("nested too deeply");
    const char c = peek();
    if (c == '{') {
      ++p_;
      out += '{';
      copy_members(out, shift, depth + 1);
      out += '}';
    } else if (c == '[') {
      ++p_;
      out += '[';
      each_element(']', &out, [&] { copy_value(out, shift, depth + 1); });
      out += ']';
    } else if (shift && ((c >= '0' && c <= '9'))) {
      const std::size_t begin = p_;
      skip_number();
      std::uint64_t v = 0;
      const auto r = std::from_chars(s_.data() + begin, s_.data() + p_, v);
      if (r.ec != std::errc() || r.ptr != s_.data() + p_) fail("a vertex index that is not an integer");
      out += std::to_string(v + offset_);
    } else {
      const std::size_t begin = p_;
      skip_value(depth + 1);
      out.append(s_, begin, p_ - begin);
    }
  }
  // Copies the members of an object whose '{' has been consumed, up to and including its '}'
  // (which is not copied).
  void copy_members(std::string& out, bool shift, int depth = 1) {
    each_element('}', &out, [&] {
      const std::size_t begin = p_;
      const std::string key = read_key();
      out.append(s_, begin, p_ - begin);
      skip_ws();
      expect(':');
      out += ':';
      skip_ws();
      copy_value(out, shift || key == "boundaries", depth + 1);
    });
  }

  const std::string& s_;
  std::size_t feature_;
  std::uint64_t offset_;
  std::size_t p_ = 0;
};

// Copies a spooled temporary file to `out` from its start.
void copy_spool(std::FILE* spool, std::FILE* out, const std::string& path) {
  if (std::fflush(spool) != 0 || std::fseek(spool, 0, SEEK_SET) != 0)
    throw IoError("cityjson: cannot read back what was spooled for " + path);
  char buffer[1 << 16];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, spool)) > 0;) std::fwrite(buffer, 1, n, out);
  if (std::ferror(spool)) throw IoError("cityjson: cannot read back what was spooled for " + path);
}

std::FILE* open_spool(const std::string& what, const std::string& path) {
  std::FILE* f = std::tmpfile();
  if (!f) throw IoError("cityjson: cannot create a temporary file for the " + what + " of " + path);
  return f;
}

// What both assemblers hold: the file, created at once so that a path that cannot be written fails
// before the first feature; its options and translation; and the extent of the quantised vertices,
// which the header needs and only the last feature completes (so the rest is spooled until close()).
struct AssembledFile {
  AssembledFile(const std::string& path, const CityJsonOptions& options, const Point3& translate)
      : path(path), options(options), translate(translate) {
    check_options(options, path);
    file = std::make_unique<detail::AtomicFile>(path);
  }
  void check_open() const {
    if (!file) throw IoError("cityjson: " + path + " is already closed");
  }
  // The file under its name (detail::AtomicFile::commit); closed for good.
  void commit() {
    file->commit();
    file.reset();
  }
  std::string path;
  CityJsonOptions options;
  Point3 translate;
  std::unique_ptr<detail::AtomicFile> file;
  Box3 extent;  // of the quantised vertices
};

}  // namespace

struct CityJsonAssembler::Impl : AssembledFile {
  using AssembledFile::AssembledFile;
  std::FILE* objects = nullptr;   // the CityObjects members, spooled to an anonymous temporary file
  std::FILE* vertices = nullptr;  // the vertex list, likewise
  std::uint64_t vertex_count = 0;
  std::size_t features = 0;
  bool any_object = false;
  ~Impl() {
    if (objects) std::fclose(objects);
    if (vertices) std::fclose(vertices);
  }
};

CityJsonAssembler::CityJsonAssembler(const std::string& path, const CityJsonOptions& options,
                                     const Point3& translate)
    : impl_(new Impl(path, options, translate)) {
  impl_->objects = open_spool("city objects", path);
  impl_->vertices = open_spool("vertices", path);
}

CityJsonAssembler::~CityJsonAssembler() = default;

void CityJsonAssembler::add(const std::string& feature) {
  impl_->check_open();
  std::string objects, vertices;
  FeatureSplicer splicer(feature, ++impl_->features, impl_->vertex_count);
  const std::uint64_t n = splicer.split(objects, vertices, impl_->extent);
  if (!objects.empty()) {
    if (impl_->any_object) objects.insert(objects.begin(), ',');
    impl_->any_object = true;
    write_all(impl_->objects, objects);
  }
  if (n > 0) {
    if (impl_->vertex_count > 0) vertices.insert(vertices.begin(), ',');
    write_all(impl_->vertices, vertices);
    impl_->vertex_count += n;
  }
}

void CityJsonAssembler::close() {
  if (!impl_->file) return;
  std::FILE* out = impl_->file->file();
  std::string header = "{";
  append_header_fields(header, impl_->options, impl_->translate, &impl_->extent);
  header += ",\"CityObjects\":{";
  write_all(out, header);
  copy_spool(impl_->objects, out, impl_->path);
  write_all(out, "},\"vertices\":[");
  copy_spool(impl_->vertices, out, impl_->path);
  write_all(out, "]}\n");
  impl_->commit();
}

struct CityJsonSeqAssembler::Impl : AssembledFile {
  using AssembledFile::AssembledFile;
  std::FILE* features = nullptr;  // the feature lines, spooled until the extent is known
  std::size_t count = 0;
  ~Impl() {
    if (features) std::fclose(features);
  }
};

CityJsonSeqAssembler::CityJsonSeqAssembler(const std::string& path, const CityJsonOptions& options,
                                           const Point3& translate)
    : impl_(new Impl(path, options, translate)) {
  impl_->features = open_spool("features", path);
}

CityJsonSeqAssembler::~CityJsonSeqAssembler() = default;

void CityJsonSeqAssembler::add(const std::string& feature) {
  impl_->check_open();
  // Only the extent is taken from the feature; the line is written as it is.
  std::string objects, vertices;
  FeatureSplicer(feature, ++impl_->count, 0).split(objects, vertices, impl_->extent);
  write_all(impl_->features, feature);
  std::fputc('\n', impl_->features);
}

void CityJsonSeqAssembler::close() {
  if (!impl_->file) return;
  std::FILE* out = impl_->file->file();
  write_all(out, cityjson_seq_header(impl_->options, impl_->translate, &impl_->extent) + "\n");
  copy_spool(impl_->features, out, impl_->path);
  impl_->commit();
}

}  // namespace city3d
