// PLY reader: parses the header (ascii, binary little/big endian; every scalar type and its alias;
// list properties), skips elements before the vertex element, and streams vertices into PointCloud.
// Elements after the vertex element are never read.
#include "points/ply_reader.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "city3d/error.hpp"
#include "points/input_file.hpp"

namespace city3d::detail {
namespace {

constexpr std::size_t kMaxHeaderBytes = 1u << 20;  // a header larger than this is not a PLY header
constexpr std::size_t kBufferBytes = 1u << 20;

enum class PlyFormat { ascii, binary_le, binary_be };
enum class PlyType { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

bool parse_type(const std::string& name, PlyType& type) {
  static const struct {
    const char* name;
    PlyType type;
  } kTypes[] = {{"char", PlyType::int8},     {"int8", PlyType::int8},      {"uchar", PlyType::uint8},
                {"uint8", PlyType::uint8},   {"short", PlyType::int16},    {"int16", PlyType::int16},
                {"ushort", PlyType::uint16}, {"uint16", PlyType::uint16},  {"int", PlyType::int32},
                {"int32", PlyType::int32},   {"uint", PlyType::uint32},    {"uint32", PlyType::uint32},
                {"float", PlyType::float32}, {"float32", PlyType::float32}, {"double", PlyType::float64},
                {"float64", PlyType::float64}};
  for (const auto& t : kTypes) {
    if (name == t.name) {
      type = t.type;
      return true;
    }
  }
  return false;
}

std::size_t type_size(PlyType t) {
  switch (t) {
    case PlyType::int8: case PlyType::uint8: return 1;
    case PlyType::int16: case PlyType::uint16: return 2;
    case PlyType::int32: case PlyType::uint32: case PlyType::float32: return 4;
    case PlyType::float64: return 8;
  }
  return 0;
}

/// Decodes one binary scalar; big-endian files are byte-swapped first.
double decode(const std::uint8_t* p, PlyType t, bool big_endian) {
  std::uint8_t b[8];
  const std::size_t n = type_size(t);
  if (big_endian) {
    for (std::size_t i = 0; i < n; ++i) b[i] = p[n - 1 - i];
  } else {
    std::memcpy(b, p, n);
  }
  switch (t) {
    case PlyType::int8: { std::int8_t v; std::memcpy(&v, b, 1); return v; }
    case PlyType::uint8: return b[0];
    case PlyType::int16: { std::int16_t v; std::memcpy(&v, b, 2); return v; }
    case PlyType::uint16: { std::uint16_t v; std::memcpy(&v, b, 2); return v; }
    case PlyType::int32: { std::int32_t v; std::memcpy(&v, b, 4); return v; }
    case PlyType::uint32: { std::uint32_t v; std::memcpy(&v, b, 4); return v; }
    case PlyType::float32: { float v; std::memcpy(&v, b, 4); return v; }
    case PlyType::float64: { double v; std::memcpy(&v, b, 8); return v; }
  }
  return 0.0;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::float32;  // the item type for lists
  bool is_list = false;
  PlyType count_type = PlyType::uint8;
  std::size_t offset = 0;  // byte offset in a binary record (scalar properties of fixed-size elements)
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  bool has_list = false;
  std::size_t record_size = 0;  // binary bytes per item when there is no list
};

struct PlyHeader {
  PlyFormat format = PlyFormat::ascii;
  std::string format_name;
  std::vector<PlyElement> elements;
  std::size_t vertex_element = 0;
  std::uint64_t body_offset = 0;
};

/// Indices of the vertex properties the reader knows, -1 when absent.
struct VertexRoles {
  int x = -1, y = -1, z = -1, nx = -1, ny = -1, nz = -1, cls = -1, red = -1, green = -1, blue = -1,
      intensity = -1;

  static VertexRoles of(const PlyElement& vertex) {
    VertexRoles r;
    for (std::size_t i = 0; i < vertex.properties.size(); ++i) {
      // Names in any case: CloudCompare writes scalar_Classification and scalar_Intensity.
      std::string n = vertex.properties[i].name;
      std::transform(n.begin(), n.end(), n.begin(),
                     [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
      const int k = static_cast<int>(i);
      if (n == "x") r.x = k;
      else if (n == "y") r.y = k;
      else if (n == "z") r.z = k;
      else if (n == "nx") r.nx = k;
      else if (n == "ny") r.ny = k;
      else if (n == "nz") r.nz = k;
      else if (n == "class" || n == "classification" || n == "label" || n == "scalar_classification") r.cls = k;
      else if (n == "red" || n == "diffuse_red") r.red = k;
      else if (n == "green" || n == "diffuse_green") r.green = k;
      else if (n == "blue" || n == "diffuse_blue") r.blue = k;
      else if (n == "intensity" || n == "scalar_intensity") r.intensity = k;
    }
    return r;
  }

  PointFields fields() const {
    PointFields f = kFieldXyz;
    if (nx >= 0 && ny >= 0 && nz >= 0) f |= kFieldNormal;
    if (cls >= 0) f |= kFieldClassification;
    if (red >= 0 && green >= 0 && blue >= 0) f |= kFieldRgb;
    if (intensity >= 0) f |= kFieldIntensity;
    return f;
  }
};

/// Reads the header text (up to and including "end_header\n") and parses it.
PlyHeader parse_header(InputFile& file) {
  const std::string& path = file.path();
  std::string text;
  std::size_t end = std::string::npos;
  char block[4096];
  while (text.size() < kMaxHeaderBytes) {
    const std::size_t got = file.read_some(block, sizeof block);
    if (got == 0) break;
    const std::size_t search_from = text.size() >= 16 ? text.size() - 16 : 0;
    text.append(block, got);
    const std::size_t at = text.find("end_header", search_from);
    if (at != std::string::npos) {
      const std::size_t nl = text.find('\n', at);
      if (nl != std::string::npos) {
        end = nl + 1;
        break;
      }
    }
  }
  if (text.compare(0, 3, "ply") != 0 || (text.size() > 3 && text[3] != '\n' && text[3] != '\r'))
    throw IoError("ply: " + path + " does not start with the 'ply' magic line");
  if (end == std::string::npos)
    throw IoError("ply: " + path + " has no end_header line in its first " +
                  std::to_string(std::min(text.size(), kMaxHeaderBytes)) + " bytes");

  PlyHeader h;
  h.body_offset = end;
  bool has_format = false;
  bool has_vertex = false;
  std::istringstream lines(text.substr(0, end));
  std::string line;
  int line_number = 0;
  std::getline(lines, line);  // "ply"
  ++line_number;
  while (std::getline(lines, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    const std::string where = "ply: " + path + " header line " + std::to_string(line_number) + " ('" + line + "')";
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "end_header") break;
    if (keyword == "format") {
      std::string version;
      words >> h.format_name >> version;
      if (h.format_name == "ascii") h.format = PlyFormat::ascii;
      else if (h.format_name == "binary_little_endian") h.format = PlyFormat::binary_le;
      else if (h.format_name == "binary_big_endian") h.format = PlyFormat::binary_be;
      else
        throw IoError(where + ": format '" + h.format_name +
                      "' is not ascii, binary_little_endian or binary_big_endian");
      has_format = true;
    } else if (keyword == "element") {
      PlyElement e;
      std::string count;
      words >> e.name >> count;
      const auto r = std::from_chars(count.data(), count.data() + count.size(), e.count);
      if (e.name.empty() || r.ec != std::errc() || r.ptr != count.data() + count.size())
        throw IoError(where + ": expected 'element <name> <count>'");
      if (e.name == "vertex") {
        if (has_vertex) throw IoError(where + ": a second vertex element");
        has_vertex = true;
        h.vertex_element = h.elements.size();
      }
      h.elements.push_back(std::move(e));
    } else if (keyword == "property") {
      if (h.elements.empty()) throw IoError(where + ": property before any element");
      PlyElement& e = h.elements.back();
      PlyProperty p;
      std::string type;
      words >> type;
      if (type == "list") {
        std::string count_type, item_type;
        words >> count_type >> item_type >> p.name;
        if (!parse_type(count_type, p.count_type) || !parse_type(item_type, p.type) || p.name.empty())
          throw IoError(where + ": expected 'property list <count type> <item type> <name>'");
        p.is_list = true;
        e.has_list = true;
      } else {
        words >> p.name;
        if (!parse_type(type, p.type)) throw IoError(where + ": unknown property type '" + type + "'");
        if (p.name.empty()) throw IoError(where + ": property without a name");
        p.offset = e.record_size;
        e.record_size += type_size(p.type);
      }
      e.properties.push_back(std::move(p));
    } else {
      throw IoError(where + ": unknown keyword '" + keyword + "'");
    }
  }
  if (!has_format) throw IoError("ply: " + path + " has no format line");
  if (!has_vertex) throw IoError("ply: " + path + " has no vertex element");

  const PlyElement& vertex = h.elements[h.vertex_element];
  for (const PlyProperty& p : vertex.properties) {
    if (p.is_list)
      throw IoError("ply: " + path + " vertex property '" + p.name +
                    "' is a list; vertices must have scalar properties only");
  }
  const VertexRoles roles = VertexRoles::of(vertex);
  for (const auto& [index, axis] : {std::pair{roles.x, "x"}, {roles.y, "y"}, {roles.z, "z"}}) {
    if (index < 0) throw IoError("ply: " + path + " vertex element has no '" + axis + "' property");
  }
  return h;
}

/// Buffered access to the body: binary reads and ascii tokens over the same block buffer.
class BodyCursor {
 public:
  BodyCursor(InputFile& file, std::uint64_t offset) : file_(file) {
    file_.seek(offset);
    buffer_.resize(kBufferBytes);
  }

  /// Returns a pointer to the next `n` bytes (valid until the next call), or nullptr at the end.
  const std::uint8_t* take(std::size_t n) {
    if (end_ - pos_ < n && !fill(n)) return nullptr;
    const std::uint8_t* p = buffer_.data() + pos_;
    pos_ += n;
    return p;
  }

  /// Skips `n` bytes; false when the file ends first.
  bool skip(std::uint64_t n) {
    while (n > 0) {
      if (pos_ == end_ && !fill(1)) return false;
      const std::size_t step = static_cast<std::size_t>(std::min<std::uint64_t>(n, end_ - pos_));
      pos_ += step;
      n -= step;
    }
    return true;
  }

  /// The next whitespace-separated token, or an empty view at the end of the file.
  std::string_view token() {
    for (;;) {
      while (pos_ < end_ && std::isspace(buffer_[pos_])) ++pos_;
      if (pos_ < end_) break;
      if (!fill(1)) return {};
    }
    std::size_t len = 0;
    for (;;) {
      while (pos_ + len < end_ && !std::isspace(buffer_[pos_ + len])) ++len;
      if (pos_ + len < end_ || !fill(len + 1)) break;  // token complete, or the file ended
    }
    const std::string_view t(reinterpret_cast<const char*>(buffer_.data() + pos_), len);
    pos_ += len;
    return t;
  }

 private:
  /// Moves the unread bytes to the front and reads more; true when at least `want` bytes are ready.
  bool fill(std::size_t want) {
    const std::size_t left = end_ - pos_;
    if (want > buffer_.size()) buffer_.resize(std::max(want, buffer_.size() * 2));
    std::memmove(buffer_.data(), buffer_.data() + pos_, left);
    pos_ = 0;
    end_ = left + file_.read_some(buffer_.data() + left, buffer_.size() - left);
    return end_ >= want;
  }

  InputFile& file_;
  std::vector<std::uint8_t> buffer_;
  std::size_t pos_ = 0;
  std::size_t end_ = 0;
};

class PlyReader final : public PointCloudReader {
 public:
  PlyReader(InputFile file, PlyHeader header, PointFields fields)
      : file_(std::move(file)), header_(std::move(header)), cursor_(file_, header_.body_offset),
        vertex_(header_.elements[header_.vertex_element]), roles_(VertexRoles::of(vertex_)) {
    info_ = make_info(file_.path(), header_);
    fields_ = fields & info_.fields;
    values_.resize(vertex_.properties.size());
    skip_elements_before_vertices();
  }

  static PointCloudInfo make_info(const std::string& path, const PlyHeader& h) {
    PointCloudInfo info;
    info.path = path;
    info.format = "PLY";
    info.version = h.format_name;
    info.point_count = h.elements[h.vertex_element].count;
    const VertexRoles roles = VertexRoles::of(h.elements[h.vertex_element]);
    info.fields = roles.fields();
    const auto& properties = h.elements[h.vertex_element].properties;
    for (int axis : {roles.x, roles.y})
      if (axis >= 0 && properties[static_cast<std::size_t>(axis)].type == PlyType::float32)
        info.single_precision_xy = true;
    for (const PlyElement& e : h.elements)
      if (e.name == "face") info.mesh_faces += e.count;
    return info;
  }

  const PointCloudInfo& info() const override { return info_; }

  std::size_t read(PointCloud& out, std::size_t max_points) override {
    const std::size_t old_size = out.size();
    const std::size_t n = static_cast<std::size_t>(
        std::min<std::uint64_t>(max_points, vertex_.count - next_vertex_));
    if (n == 0) return 0;
    // Resizing every requested attribute to the point count keeps the PointCloud invariant.
    out.points.resize(old_size + n);
    if (fields_ & kFieldNormal) out.normals.resize(old_size + n);
    if (fields_ & kFieldClassification) out.classification.resize(old_size + n);
    if (fields_ & kFieldRgb) out.rgb.resize(old_size + n);
    if (fields_ & kFieldIntensity) out.intensity.resize(old_size + n);
    for (std::size_t i = 0; i < n; ++i) {
      read_vertex();
      store(out, old_size + i);
      ++next_vertex_;
    }
    return n;
  }

 private:
  [[noreturn]] void truncated() const {
    throw IoError("ply: " + info_.path + " ends after vertex " + std::to_string(next_vertex_) +
                  " of " + std::to_string(vertex_.count));
  }

  bool binary() const { return header_.format != PlyFormat::ascii; }
  bool big_endian() const { return header_.format == PlyFormat::binary_be; }

  double number(std::string_view token, const std::string& element, std::uint64_t index,
                const std::string& property) {
    double v = 0.0;
    const auto r = std::from_chars(token.data(), token.data() + token.size(), v);
    if (r.ec != std::errc() || r.ptr != token.data() + token.size())
      throw IoError("ply: " + info_.path + " " + element + " " + std::to_string(index) + " property '" +
                    property + "': '" + std::string(token) + "' is not a number");
    return v;
  }

  void skip_elements_before_vertices() {
    for (std::size_t e = 0; e < header_.vertex_element; ++e) {
      const PlyElement& el = header_.elements[e];
      const auto fail = [&](std::uint64_t item) {
        throw IoError("ply: " + info_.path + " ends in element '" + el.name + "' item " +
                      std::to_string(item) + " of " + std::to_string(el.count) + ", before the vertices");
      };
      // An element without properties takes no bytes, however many items it claims (a count of
      // 10^11 was a loop of 10^11 turns, found by fuzz_ply).
      if (el.properties.empty()) continue;
      if (binary() && !el.has_list) {
        // count * record_size must not wrap around: a count that large cannot be in the file anyway.
        if (el.record_size != 0 && el.count > std::numeric_limits<std::uint64_t>::max() / el.record_size) fail(0);
        if (!cursor_.skip(el.count * el.record_size)) fail(0);
        continue;
      }
      for (std::uint64_t item = 0; item < el.count; ++item) {
        for (const PlyProperty& p : el.properties) {
          if (binary()) {
            std::uint64_t items = 1;
            if (p.is_list) {
              const std::uint8_t* c = cursor_.take(type_size(p.count_type));
              if (!c) fail(item);
              items = list_length(decode(c, p.count_type, big_endian()), el.name, item, p.name);
            }
            if (!cursor_.skip(items * type_size(p.type))) fail(item);
          } else {
            std::string_view t = cursor_.token();
            if (t.empty()) fail(item);
            if (!p.is_list) continue;
            const std::uint64_t count = list_length(number(t, el.name, item, p.name), el.name, item, p.name);
            for (std::uint64_t k = 0; k < count; ++k) {
              if (cursor_.token().empty()) fail(item);
            }
          }
        }
      }
    }
  }

  /// A list length as read (any PLY type, so any double): a whole number from 0 to 2^53, or the
  /// item is broken. Converting anything else to an integer would be undefined behaviour.
  std::uint64_t list_length(double count, const std::string& element, std::uint64_t item,
                            const std::string& property) const {
    if (!(count >= 0.0) || count > 9007199254740992.0 || count != std::floor(count)) {
      std::ostringstream os;
      os << "ply: " << info_.path << " " << element << " " << item << " list '" << property
         << "' has a length of " << count << " (must be a whole number >= 0)";
      throw IoError(os.str());
    }
    return static_cast<std::uint64_t>(count);
  }

  /// A double as a float normal component: out-of-range values saturate (a cast would be undefined).
  static float to_float(double v) {
    const double max = std::numeric_limits<float>::max();
    return static_cast<float>(v > max ? max : v < -max ? -max : v);  // NaN passes through as NaN
  }

  /// Fills values_ with the next vertex's properties, as doubles.
  void read_vertex() {
    if (binary()) {
      const std::uint8_t* record = cursor_.take(vertex_.record_size);
      if (!record) truncated();
      for (std::size_t k = 0; k < vertex_.properties.size(); ++k) {
        const PlyProperty& p = vertex_.properties[k];
        values_[k] = decode(record + p.offset, p.type, big_endian());
      }
    } else {
      for (std::size_t k = 0; k < vertex_.properties.size(); ++k) {
        const std::string_view t = cursor_.token();
        if (t.empty()) truncated();
        values_[k] = number(t, "vertex", next_vertex_, vertex_.properties[k].name);
      }
    }
  }

  void store(PointCloud& out, std::size_t at) {
    const Point3 p{values_[roles_.x], values_[roles_.y], values_[roles_.z]};
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      std::ostringstream os;
      os << "ply: " << info_.path << " vertex " << next_vertex_ << " has a non-finite coordinate ("
         << p.x << ", " << p.y << ", " << p.z << ")";
      throw IoError(os.str());
    }
    out.points[at] = p;
    if (fields_ & kFieldNormal)
      out.normals[at] = {to_float(values_[roles_.nx]), to_float(values_[roles_.ny]), to_float(values_[roles_.nz])};
    if (fields_ & kFieldClassification) out.classification[at] = saturate<std::uint8_t>(values_[roles_.cls]);
    // Colours are stored as in the file: 0-255 for uchar, 0-65535 for ushort.
    if (fields_ & kFieldRgb)
      out.rgb[at] = {saturate<std::uint16_t>(values_[roles_.red]), saturate<std::uint16_t>(values_[roles_.green]),
                     saturate<std::uint16_t>(values_[roles_.blue])};
    if (fields_ & kFieldIntensity) out.intensity[at] = saturate<std::uint16_t>(values_[roles_.intensity]);
  }

  template <typename T>
  static T saturate(double v) {
    if (!(v > 0.0)) return 0;  // also NaN
    const double hi = static_cast<double>(std::numeric_limits<T>::max());
    return static_cast<T>(v >= hi ? hi : std::lround(v));
  }

  InputFile file_;
  PlyHeader header_;
  BodyCursor cursor_;
  const PlyElement& vertex_;
  VertexRoles roles_;
  PointCloudInfo info_;
  PointFields fields_ = kFieldXyz;
  std::vector<double> values_;
  std::uint64_t next_vertex_ = 0;
};

}  // namespace

std::unique_ptr<PointCloudReader> open_ply(const std::string& path, PointFields fields) {
  InputFile file(path, "ply");
  PlyHeader header = parse_header(file);
  return std::make_unique<PlyReader>(std::move(file), std::move(header), fields);
}

PointCloudInfo read_ply_info(const std::string& path) {
  InputFile file(path, "ply");
  return PlyReader::make_info(path, parse_header(file));
}

}  // namespace city3d::detail
