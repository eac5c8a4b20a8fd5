// Footprints from City3D's OBJ polygon files (as Easy3D writes them): `v x y z` vertices and
// `f i j k ...` faces, each face one footprint polygon; z is dropped.
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <unordered_map>
#include <utility>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/footprint_io.hpp"
#include "city3d/log.hpp"
#include "footprints/footprint_readers.hpp"

namespace city3d::detail {
namespace {

constexpr const char* kModule = "footprints: ";

/// Splits a line at blanks (spaces and tabs).
std::vector<std::string_view> split_blanks(std::string_view line) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

/// from_chars, not strtod: independent of the C locale (a "," decimal locale must not change
/// what a file means).
std::optional<double> parse_double(std::string_view token) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  double value = 0.0;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (error != std::errc() || end != token.data() + token.size()) return std::nullopt;
  return value;
}

std::optional<long long> parse_integer(std::string_view token) {
  long long value = 0;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (error != std::errc() || end != token.data() + token.size()) return std::nullopt;
  return value;
}

/// One face with the object/group name in force where it appeared.
struct ObjFace {
  std::vector<std::size_t> vertex_indices;  ///< 0-based
  std::string group;                        ///< empty when none
  std::size_t line = 0;
};

/// Rejects options that only make sense for attribute tables: an OBJ file has no layers other
/// than "obj", no attributes and no SQL.
void check_options(const std::string& path, const FootprintReadOptions& options) {
  if (!options.layer.empty() && options.layer != "obj") {
    throw IoError(kModule + std::string("no layer '") + options.layer + "' in " + path + " (layers: obj)");
  }
  if (!options.id_field.empty() && options.id_field != "FID") {
    throw IoError(kModule + std::string("no field '") + options.id_field + "' in " + path +
                  " (fields: none; an OBJ file has no attributes)");
  }
  if (!options.attribute_filter.empty()) {
    throw IoError(kModule + std::string("bad attribute filter '") + options.attribute_filter + "' on " +
                  path + ": an OBJ file has no attributes");
  }
}

}  // namespace

FootprintSet read_obj_footprints(const std::string& path, const FootprintReadOptions& options) {
  check_options(path, options);
  std::error_code status;
  if (!std::filesystem::exists(path, status)) {
    throw IoError(kModule + std::string("cannot open ") + path + ": no such file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in || std::filesystem::is_directory(path, status)) {
    throw IoError(kModule + std::string("cannot open ") + path + ": not a readable file");
  }

  std::vector<Point2> vertices;
  std::vector<double> heights;  // each vertex's z: only to tell a 3D model apart
  std::vector<ObjFace> faces;
  std::string group;
  std::string line;
  std::size_t line_number = 0;
  auto malformed = [&](const std::string& problem) {
    return IoError(kModule + path + " line " + std::to_string(line_number) + ": " + problem);
  };

  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();  // files written on Windows
    const std::vector<std::string_view> tokens = split_blanks(line);
    if (tokens.empty() || tokens[0].front() == '#') continue;
    const std::string_view keyword = tokens[0];
    if (keyword == "v") {
      // `v x y z [w]`, or Easy3D's `v x y z r g b` with colours: only x and y matter here.
      if (tokens.size() < 4) throw malformed("vertex needs x y z, got '" + line + "'");
      const auto x = parse_double(tokens[1]);
      const auto y = parse_double(tokens[2]);
      const auto z = parse_double(tokens[3]);
      if (!x || !y || !z) throw malformed("vertex coordinate is not a number in '" + line + "'");
      vertices.push_back({*x, *y});
      heights.push_back(*z);
    } else if (keyword == "f") {
      ObjFace face;
      face.group = group;
      face.line = line_number;
      for (std::size_t i = 1; i < tokens.size(); ++i) {
        // `i`, `i/t`, `i//n` or `i/t/n`: the vertex index is the part before the first slash.
        const std::string_view ref = tokens[i].substr(0, tokens[i].find('/'));
        const auto index = parse_integer(ref);
        if (!index || *index == 0) {
          throw malformed("bad vertex reference '" + std::string(tokens[i]) + "' in face");
        }
        // Negative indices count back from the last vertex read so far (-1 is the latest).
        const long long count = static_cast<long long>(vertices.size());
        const long long resolved = *index > 0 ? *index - 1 : count + *index;
        if (resolved < 0 || resolved >= count) {
          throw malformed("vertex index " + std::to_string(*index) + " out of range (" +
                          std::to_string(count) + " vertices so far)");
        }
        face.vertex_indices.push_back(static_cast<std::size_t>(resolved));
      }
      faces.push_back(std::move(face));
    } else if (keyword == "o" || keyword == "g") {
      // The name is the rest of the line; `g` alone returns to the default (unnamed) group.
      const std::size_t after_keyword = static_cast<std::size_t>(keyword.data() - line.data()) + 1;
      const std::size_t start = line.find_first_not_of(" \t", after_keyword);
      group = start == std::string::npos ? std::string() : line.substr(start);
      while (!group.empty() && (group.back() == ' ' || group.back() == '\t')) group.pop_back();
    }
    // Everything else (vn, vt, s, usemtl, mtllib, l, ...) says nothing about footprints.
  }
  if (in.bad()) throw IoError(kModule + std::string("read error in ") + path);

  // A 3D model (a building's walls) is no footprint file: each face of one is a footprint, lying flat.
  std::size_t standing = 0, first_standing_line = 0;
  for (const ObjFace& face : faces) {
    double nx = 0, ny = 0, nz = 0;  // Newell's normal
    const std::size_t n = face.vertex_indices.size();
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t a = face.vertex_indices[k], b = face.vertex_indices[(k + 1) % n];
      nx += (vertices[a].y - vertices[b].y) * (heights[a] + heights[b]);
      ny += (heights[a] - heights[b]) * (vertices[a].x + vertices[b].x);
      nz += (vertices[a].x - vertices[b].x) * (vertices[a].y + vertices[b].y);
    }
    const double length = std::sqrt(nx * nx + ny * ny + nz * nz);
    if (length > 0 && std::abs(nz) < 0.1 * length && standing++ == 0) first_standing_line = face.line;
  }
  if (standing > 0)
    throw IoError(
        kModule + path + " holds " + std::to_string(standing) + " standing faces (the first at line " +
        std::to_string(first_standing_line) +
        "): a 3D model, not footprints (each face of a footprint OBJ is one flat footprint polygon)");

  FootprintSet set;
  set.path = path;
  set.driver = "OBJ";
  set.layer = "obj";
  set.id_field = "FID";

  // Ids: the face number ("0", "1", ...) unless a name is in force; the second and later faces
  // under one name get "name/1", "name/2", ... so that ids stay unique.
  std::unordered_map<std::string, std::size_t> faces_per_name;
  for (std::size_t face_number = 0; face_number < faces.size(); ++face_number) {
    const ObjFace& face = faces[face_number];
    BuildingId id = std::to_string(face_number);
    if (!face.group.empty()) {
      const std::size_t seen = faces_per_name[face.group]++;
      id = seen == 0 ? face.group : face.group + "/" + std::to_string(seen);
    }
    Polygon2 polygon;
    for (std::size_t index : face.vertex_indices) polygon.outer.push_back(vertices[index]);

    if (options.bbox) {
      Box2 bounds;
      for (const Point2& p : polygon.outer) bounds.add(p);
      if (bounds.empty() || !bounds.intersects(*options.bbox)) continue;
    }
    ++set.feature_count;
    const std::string where = "face at line " + std::to_string(face.line);
    auto skip = [&](const std::string& reason) {
      log_warning(kModule + std::string("skipped ") + id + " in " + path + ": " + reason);
      set.skipped.push_back({id, reason});
    };
    if (clean_ring(polygon.outer).size() < 3) {
      skip(where + " has fewer than 3 distinct vertices");
      continue;
    }
    // The same validity check and MakeValid repair as OGR sources get: a bow-tie face becomes two
    // triangles here too.
    RepairedPolygons outcome = check_and_repair({polygon}, options.repair);
    if (outcome.polygons.empty()) {
      skip(where + ": " + outcome.skip_reason);
      continue;
    }
    if (const std::string too_big = extent_problem(outcome.polygons, options.max_extent); !too_big.empty()) {
      skip(where + ": " + too_big);
      continue;
    }
    Footprint footprint;
    footprint.id = std::move(id);
    footprint.polygons = std::move(outcome.polygons);
    if (!outcome.repair_note.empty()) {
      ++set.repaired;
      log_warning(kModule + std::string("repaired ") + footprint.id + " in " + path + " (" + where + "): " +
                  outcome.repair_note);
      footprint.note = "footprint repaired with MakeValid: " + outcome.repair_note;
    }
    set.footprints.push_back(std::move(footprint));
  }
  if (faces.empty()) throw IoError(kModule + path + " layer 'obj' has no polygon features");
  log_info(kModule + std::to_string(set.footprints.size()) + " footprints from " + path + " (" +
           std::to_string(set.skipped.size()) + " skipped, " + std::to_string(set.repaired) + " repaired)");
  return set;
}

}  // namespace city3d::detail
