// Resume journal: JSON lines, each prefixed by the FNV-1a hash of its JSON text, read back with
// nlohmann-json. Doubles of a kept mesh are written in nlohmann's shortest round-trip form, so a
// restored model is bit-identical to the computed one.
#include "batch/journal.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "city3d/error.hpp"
#include "city3d/log.hpp"

namespace city3d::detail {
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// 3: records carry their footprint for buildings.gpkg and report.html, the layout says whether to write them.
// 4: report rows carry coverage and point_coverage; the status partial.
// 5: the layout says where its CRS came from, whether to write 3D Tiles, and the run's parameters and
//    inputs (for the outputs' metadata); features carry val3dity codes as lists.
// 6: report rows carry building_coverage.
constexpr int kJournalVersion = 6;
constexpr std::size_t kHashDigits = 16;

std::string dump(const json& j) { return j.dump(-1, ' ', false, json::error_handler_t::replace); }

// "<hash> <json>": the line of a JSON value.
std::string make_line(const json& j) {
  const std::string text = dump(j);
  return content_hash(text) + " " + text;
}

// The JSON text of a line whose hash matches, or nullopt.
std::optional<std::string> checked_text(const std::string& line) {
  if (line.size() < kHashDigits + 2 || line[kHashDigits] != ' ') return std::nullopt;
  std::string text = line.substr(kHashDigits + 1);
  if (content_hash(text) != line.substr(0, kHashDigits)) return std::nullopt;
  return text;
}

BuildingStatus parse_status(const std::string& s) {
  if (const std::optional<BuildingStatus> status = status_from_name(s)) return *status;
  throw std::runtime_error("unknown status " + s);
}

json layout_json(const RunLayout& l) {
  return {{"crs", l.crs},
          {"crs_source", l.crs_source},
          {"translate", {l.translate.x, l.translate.y, l.translate.z}},
          {"scale", l.scale},
          {"records", l.records},
          {"cityjson", l.cityjson},
          {"cityjson_seq", l.cityjson_seq},
          {"merged_file", l.merged_file},
          {"per_building_files", l.per_building_files},
          {"local_coordinates", l.local_coordinates},
          {"format", static_cast<int>(l.format)},
          {"gpkg", l.gpkg},
          {"html", l.html},
          {"tiles3d", l.tiles3d},
          {"parameters", l.parameters},
          {"inputs", l.inputs}};
}

RunLayout parse_layout(const json& j) {
  RunLayout l;
  l.crs = j.at("crs").get<std::string>();
  l.crs_source = j.at("crs_source").get<std::string>();
  const json& t = j.at("translate");
  l.translate = {t.at(0).get<double>(), t.at(1).get<double>(), t.at(2).get<double>()};
  l.scale = j.at("scale").get<double>();
  l.records = j.at("records").get<std::uint64_t>();
  l.cityjson = j.at("cityjson").get<bool>();
  l.cityjson_seq = j.at("cityjson_seq").get<bool>();
  l.merged_file = j.at("merged_file").get<bool>();
  l.per_building_files = j.at("per_building_files").get<bool>();
  l.local_coordinates = j.at("local_coordinates").get<bool>();
  const int format = j.at("format").get<int>();
  if (format < 0 || format > 2) throw std::runtime_error("bad format");
  l.format = static_cast<MeshFormat>(format);
  l.gpkg = j.at("gpkg").get<bool>();
  l.html = j.at("html").get<bool>();
  l.tiles3d = j.at("tiles3d").get<bool>();
  l.parameters = j.at("parameters").get<std::string>();
  l.inputs = j.at("inputs").get<std::string>();
  return l;
}

json header_json(const JournalHeader& h) {
  return {{"city3d_journal", kJournalVersion}, {"version", CITY3D_VERSION}, {"fingerprint", h.fingerprint},
          {"shard", h.shard},  {"shards", h.shards},  {"block_size", h.block_size},
          {"expected", h.expected}, {"layout", layout_json(h.layout)}};
}

JournalHeader parse_header(const json& j) {
  if (j.at("city3d_journal").get<int>() != kJournalVersion) throw std::runtime_error("other journal version");
  JournalHeader h;
  h.fingerprint = j.at("fingerprint").get<std::string>();
  h.shard = j.at("shard").get<int>();
  h.shards = j.at("shards").get<int>();
  h.block_size = j.at("block_size").get<double>();
  h.expected = j.at("expected").get<std::uint64_t>();
  h.layout = parse_layout(j.at("layout"));
  return h;
}

// A point list as [[x, y], ...]: nlohmann writes doubles in their shortest round-trip form, so the
// footprint read back is bit-identical to the one read from the source.
json ring_json(const Ring2& ring) {
  json points = json::array();
  for (const Point2& p : ring) points.push_back({p.x, p.y});
  return points;
}

Ring2 parse_ring(const json& j) {
  Ring2 ring;
  for (const json& p : j) ring.push_back({p.at(0).get<double>(), p.at(1).get<double>()});
  return ring;
}

// An attribute as [name, type, value], the type one of "null", "bool", "int", "real", "text", "list"
// (its JSON array as text), so that
// every value comes back with its type (a real that happens to be whole stays a real; 64-bit
// integers stay exact). A real that is not finite, which JSON cannot hold, is written as text.
json attribute_json(const std::string& name, const AttributeValue& v) {
  if (const bool* b = std::get_if<bool>(&v)) return {name, "bool", *b};
  if (const std::int64_t* i = std::get_if<std::int64_t>(&v)) return {name, "int", *i};
  if (const double* d = std::get_if<double>(&v)) {
    if (std::isfinite(*d)) return {name, "real", *d};
    return {name, "real", std::isnan(*d) ? "nan" : *d > 0 ? "inf" : "-inf"};
  }
  if (const std::string* t = std::get_if<std::string>(&v)) return {name, "text", *t};
  if (const AttributeList* l = std::get_if<AttributeList>(&v)) return {name, "list", l->json};
  return {name, "null", nullptr};
}

std::pair<std::string, AttributeValue> parse_attribute(const json& j) {
  const std::string name = j.at(0).get<std::string>();
  const std::string type = j.at(1).get<std::string>();
  const json& value = j.at(2);
  if (type == "null") return {name, std::monostate{}};
  if (type == "bool") return {name, value.get<bool>()};
  if (type == "int") return {name, value.get<std::int64_t>()};
  if (type == "text") return {name, value.get<std::string>()};
  if (type == "list") return {name, AttributeList{value.get<std::string>()}};
  if (type != "real") throw std::runtime_error("unknown attribute type " + type);
  if (!value.is_string()) return {name, value.get<double>()};
  const std::string special = value.get<std::string>();
  if (special == "nan") return {name, std::numeric_limits<double>::quiet_NaN()};
  if (special == "inf") return {name, std::numeric_limits<double>::infinity()};
  if (special == "-inf") return {name, -std::numeric_limits<double>::infinity()};
  throw std::runtime_error("bad real " + special);
}

json record_json(const BuildingRecord& r) {
  json j = {{"index", r.index},     {"id", r.id},           {"status", status_name(r.status)},
            {"csv", r.report_csv},  {"json", r.report_json}, {"feature", r.feature},
            {"model", r.model_file}, {"model_hash", r.model_hash}};
  if (r.mesh) {
    const BuildingModel& m = *r.mesh;
    json vertices = json::array(), faces = json::array(), surfaces = json::array();
    for (const Point3& p : m.mesh.vertices) vertices.push_back({p.x, p.y, p.z});
    for (const auto& f : m.mesh.faces) faces.push_back(f);
    for (SurfaceType t : m.surfaces) surfaces.push_back(static_cast<int>(t));
    j["mesh"] = {{"origin", {m.origin.x, m.origin.y, m.origin.z}},
                 {"vertices", vertices},
                 {"faces", faces},
                 {"surfaces", surfaces}};
  }
  if (r.footprint) {
    json polygons = json::array(), attributes = json::array();
    for (const Polygon2& p : r.footprint->polygons) {
      json rings = json::array({ring_json(p.outer)});
      for (const Ring2& h : p.holes) rings.push_back(ring_json(h));
      polygons.push_back(std::move(rings));
    }
    for (const auto& [name, value] : r.footprint->attributes) attributes.push_back(attribute_json(name, value));
    j["footprint"] = {{"polygons", polygons}, {"attributes", attributes}};
  }
  return j;
}

// The fields a BuildingRecord and its RecordRef share, read from the record's line.
template <class Record>
void parse_record_summary(const json& j, Record& r) {
  r.index = j.at("index").get<std::uint64_t>();
  r.id = j.at("id").get<std::string>();
  r.status = parse_status(j.at("status").get<std::string>());
  r.model_file = j.at("model").get<std::string>();
  r.model_hash = j.at("model_hash").get<std::string>();
}

BuildingRecord parse_record(const json& j) {
  BuildingRecord r;
  parse_record_summary(j, r);
  r.report_csv = j.at("csv").get<std::string>();
  r.report_json = j.at("json").get<std::string>();
  r.feature = j.at("feature").get<std::string>();
  if (const auto it = j.find("mesh"); it != j.end()) {
    BuildingModel m;
    m.id = r.id;
    const json& o = it->at("origin");
    m.origin = {o.at(0).get<double>(), o.at(1).get<double>(), o.at(2).get<double>()};
    for (const json& v : it->at("vertices"))
      m.mesh.vertices.push_back({v.at(0).get<double>(), v.at(1).get<double>(), v.at(2).get<double>()});
    for (const json& f : it->at("faces")) {
      std::vector<std::uint32_t> face = f.get<std::vector<std::uint32_t>>();
      for (std::uint32_t v : face)
        if (v >= m.mesh.vertices.size()) throw std::runtime_error("face vertex out of range");
      m.mesh.faces.push_back(std::move(face));
    }
    for (const json& s : it->at("surfaces")) {
      const int t = s.get<int>();
      if (t < 0 || t > 2) throw std::runtime_error("bad surface type");
      m.surfaces.push_back(static_cast<SurfaceType>(t));
    }
    r.mesh = std::move(m);
  }
  if (const auto it = j.find("footprint"); it != j.end()) {
    Footprint f;
    f.id = r.id;
    for (const json& rings : it->at("polygons")) {
      Polygon2 p;
      p.outer = parse_ring(rings.at(0));
      for (std::size_t k = 1; k < rings.size(); ++k) p.holes.push_back(parse_ring(rings.at(k)));
      f.polygons.push_back(std::move(p));
    }
    for (const json& a : it->at("attributes")) f.attributes.push_back(parse_attribute(a));
    r.footprint = std::move(f);
  }
  return r;
}

// Path, size and modification time of an input: a changed file makes another run.
std::string file_stamp(const std::string& path) {
  std::error_code ec;
  const fs::path canonical = fs::weakly_canonical(path, ec);
  const std::string name = ec ? path : canonical.string();
  const auto size = fs::file_size(path, ec);
  const auto time = fs::last_write_time(path, ec).time_since_epoch().count();
  return name + " " + std::to_string(ec ? 0 : size) + " " + std::to_string(ec ? 0 : time);
}

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

}  // namespace

bool JournalHeader::same_run(const JournalHeader& o) const {
  return fingerprint == o.fingerprint && shard == o.shard && shards == o.shards &&
         (shards == 0 || block_size == o.block_size) && expected == o.expected &&
         layout_json(layout) == layout_json(o.layout);
}

std::string content_hash(const std::string& bytes) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char buf[kHashDigits + 1];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

std::string file_hash(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (in.bad()) return {};
  return content_hash(bytes.str());
}

std::string batch_fingerprint(const BatchOptions& o, const std::vector<std::string>& files) {
  std::ostringstream s;
  s << CITY3D_VERSION << " journal " << kJournalVersion << '\n';
  for (const std::string& f : files) s << file_stamp(f) << '\n';
  if (!o.footprints.empty()) {
    s << file_stamp(o.footprints) << '\n';
    // A Shapefile's attributes, index, CRS and encoding are files of their own beside the .shp: a
    // changed ground field in the .dbf alone is another run too.
    const fs::path shp(o.footprints);
    std::string ext = shp.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext == ".shp")
      for (const char* side : {".dbf", ".DBF", ".shx", ".SHX", ".prj", ".PRJ", ".cpg", ".CPG"}) {
        std::error_code ec;
        const fs::path f = fs::path(shp).replace_extension(side);
        if (fs::exists(f, ec)) s << file_stamp(f.string()) << '\n';
      }
  }
  s << o.footprint.layer << '|' << o.footprint.id_field << '|' << o.footprint.attribute_filter << '|'
    << o.footprint.repair << '|' << o.footprint.ground_field << '|';
  if (o.footprint.bbox)
    s << num(o.footprint.bbox->min.x) << ',' << num(o.footprint.bbox->min.y) << ',' << num(o.footprint.bbox->max.x)
      << ',' << num(o.footprint.bbox->max.y);
  s << '\n';
  for (std::uint8_t c : o.crop.building_classes) s << int(c) << ',';
  s << '|' << int(o.crop.ground_class) << '|' << static_cast<int>(o.crop.use_classes) << '|'
    << num(o.crop.ground_buffer) << '|' << num(o.crop.wide_buffer_factor) << '|' << num(o.crop.ground_percentile)
    << '|' << o.crop.min_ground_points << '\n';
  s << parameters_text(o.reconstruction) << '\n';
  s << (o.ground_z ? num(*o.ground_z) : "-") << '|' << num(o.min_coverage) << '|'
    << num(o.min_building_coverage) << '\n';
  // What a building's record holds: its model file, its CityJSONFeature, its mesh for models.<ext>.
  s << static_cast<int>(o.format) << '|' << o.local_coordinates << '|' << o.per_building_files << '|'
    << o.merged_file << '|' << o.timings_in_cityjson << '\n';
  return content_hash(s.str());
}

JournalReader::JournalReader(std::string path) : path_(std::move(path)) {
  std::ifstream in(path_, std::ios::binary);
  if (!in) throw IoError("resume: cannot read " + path_ + ": " + std::strerror(errno));
  std::string line;
  std::uint64_t offset = 0;
  std::size_t number = 0;
  while (std::getline(in, line)) {
    const std::uint64_t line_offset = offset;
    offset += line.size() + 1;
    ++number;
    // Only lines ending in a newline are complete: a run killed in the middle of a write leaves
    // half a line, which is not counted as damage.
    if (in.eof()) break;
    const std::optional<std::string> text = checked_text(line);
    if (number == 1) {
      if (!text) return;
      try {
        header_ = parse_header(json::parse(*text));
        header_ok_ = true;
      } catch (const std::exception&) {
        return;
      }
      continue;
    }
    std::string id;
    if (text) {
      try {
        const json j = json::parse(*text);
        RecordRef ref;
        parse_record_summary(j, ref);
        ref.offset = line_offset;
        ref.length = line.size();
        add_record(std::move(ref));
        continue;
      } catch (const std::exception&) {
      }
    } else {
      // The id, when the damage left it readable, helps the user.
      try {
        const std::size_t brace = line.find('{');
        if (brace != std::string::npos) id = json::parse(line.substr(brace)).at("id").get<std::string>();
      } catch (const std::exception&) {
      }
    }
    damaged_.emplace_back(number, id);
  }
}

JournalReader::JournalReader(std::string path, JournalHeader header, std::vector<RecordRef> written)
    : path_(std::move(path)), header_ok_(true), header_(std::move(header)) {
  records_.reserve(written.size());
  for (RecordRef& ref : written) add_record(std::move(ref));
}

void JournalReader::add_record(RecordRef ref) {
  const auto [it, fresh] = position_of_index_.emplace(ref.index, records_.size());
  if (fresh)
    records_.push_back(std::move(ref));
  else
    records_[it->second] = std::move(ref);
}

std::string JournalReader::line(const RecordRef& ref) const {
  const std::lock_guard<std::mutex> lock(in_mutex_);
  if (!in_.is_open()) in_.open(path_, std::ios::binary);
  in_.clear();
  std::string text(ref.length, '\0');
  if (!in_.seekg(static_cast<std::streamoff>(ref.offset)) || !in_.read(text.data(), static_cast<std::streamsize>(ref.length)))
    throw IoError("resume: cannot read back record " + std::to_string(ref.index) + " of " + path_);
  return text;
}

BuildingRecord JournalReader::read(const RecordRef& ref) const {
  const std::optional<std::string> text = checked_text(line(ref));
  if (!text) throw IoError("resume: record " + std::to_string(ref.index) + " (" + ref.id + ") of " + path_ +
                           " changed while the run used it");
  try {
    return parse_record(json::parse(*text));
  } catch (const std::exception& e) {
    throw IoError("resume: record " + std::to_string(ref.index) + " of " + path_ + " is unreadable: " + e.what());
  }
}

Journal::Journal(const std::string& output_dir, JournalHeader header, bool resume)
    : path_((fs::path(output_dir) / "resume.journal").string()) {
  std::vector<std::string> kept;
  std::error_code ec;
  if (fs::exists(path_, ec)) {
    const JournalReader old(path_);
    const bool same = old.header_ok() && old.header().same_run(header);
    if (same && resume) {
      for (const auto& [number, id] : old.damaged())
        log_warning("resume: line " + std::to_string(number) + " of " + path_ + (id.empty() ? "" : " (" + id + ")") +
                    " is damaged (checksum mismatch); its building is recomputed");
      for (const RecordRef& ref : old.records()) {
        if (ref.index >= header.layout.records) continue;
        if (!ref.model_file.empty()) {
          const std::string model = (fs::path(output_dir) / "models" / ref.model_file).string();
          if (file_hash(model) != ref.model_hash) {
            log_warning("resume: " + model + " is missing or changed since it was written; building " + ref.id +
                        " is recomputed");
            continue;
          }
        }
        kept.push_back(old.line(ref));
        done_[ref.index] = ref;
        written_.push_back(ref);  // its offset in the rewritten file below
      }
    } else {
      if (!same)
        log_warning("resume: " + path_ + (old.header_ok() ? " is from another run (inputs or parameters differ)"
                                                          : " is damaged or from another city3d version") +
                    "; starting afresh");
      for (const RecordRef& ref : old.records())
        if (!ref.model_file.empty()) earlier_models_.emplace_back(ref.model_file, ref.model_hash);
      earlier_same_run_ = same;
    }
  }
  // Rewrite the journal with its good lines only, then append to it.
  write_journal(path_, header, kept.size(), [&kept](std::size_t k) { return kept[k]; });
  // The kept lines end the file, in order, after its header line.
  std::error_code size_error;
  size_ = fs::file_size(path_, size_error);
  if (size_error) throw IoError("resume: cannot read " + path_ + ": " + size_error.message());
  std::uint64_t offset = size_;
  for (const RecordRef& ref : written_) offset -= ref.length + 1;
  for (RecordRef& ref : written_) {
    ref.offset = offset;
    offset += ref.length + 1;
  }
  // Room for the records to come, reserved here on the main thread (up to 131,072 records: beyond that
  // the lists grow, in large blocks).
  const std::size_t room = static_cast<std::size_t>(std::min<std::uint64_t>(header.expected, 1u << 17));
  appended_.reserve(room);
  appended_text_.reserve(room * 128);  // ids, model file names and hashes of about this size
  file_ = std::fopen(path_.c_str(), "ab");
  if (!file_) throw IoError("resume: cannot append to " + path_ + ": " + std::strerror(errno));
  if (!done_.empty()) log_info("resume: " + std::to_string(done_.size()) + " finished buildings in " + path_);
}

Journal::~Journal() { close(); }

void Journal::close() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (file_) std::fclose(file_);
  file_ = nullptr;
}

const RecordRef* Journal::find(std::uint64_t index) const {
  const auto it = done_.find(index);
  return it == done_.end() ? nullptr : &it->second;
}

void Journal::append(const BuildingRecord& record) {
  const std::string line = make_line(record_json(record)) + "\n";
  // Its summary as a reader parses it back from the line: the strings as the line holds them (invalid
  // UTF-8 replaced), the status by its name.
  const auto as_written = [](const std::string& s) { return json::parse(dump(json(s))).get<std::string>(); };
  const std::string id = as_written(record.id), model_file = as_written(record.model_file),
                    model_hash = as_written(record.model_hash);
  std::lock_guard<std::mutex> lock(mutex_);
  if (!file_ || std::fwrite(line.data(), 1, line.size(), file_) != line.size() || std::fflush(file_) != 0)
    throw IoError("resume: cannot append to " + path_ + ": " + std::strerror(errno));
  Appended a{record.index, size_, line.size() - 1, parse_status(status_name(record.status)), 0, 0, 0};
  appended_text_ += id;
  a.id_end = appended_text_.size();
  appended_text_ += model_file;
  a.model_file_end = appended_text_.size();
  appended_text_ += model_hash;
  a.model_hash_end = appended_text_.size();
  appended_.push_back(a);
  size_ += line.size();
}

std::vector<RecordRef> Journal::take_written() {
  std::vector<RecordRef> refs = std::move(written_);
  refs.reserve(refs.size() + appended_.size());
  std::size_t begin = 0;
  for (const Appended& a : appended_) {
    RecordRef ref;
    ref.index = a.index;
    ref.status = a.status;
    ref.offset = a.offset;
    ref.length = a.length;
    ref.id = appended_text_.substr(begin, a.id_end - begin);
    ref.model_file = appended_text_.substr(a.id_end, a.model_file_end - a.id_end);
    ref.model_hash = appended_text_.substr(a.model_file_end, a.model_hash_end - a.model_file_end);
    begin = a.model_hash_end;
    refs.push_back(std::move(ref));
  }
  written_.clear();
  std::vector<Appended>().swap(appended_);
  std::string().swap(appended_text_);
  return refs;
}

void write_journal(const std::string& path, const JournalHeader& header, std::size_t count,
                   const std::function<std::string(std::size_t)>& line_at) {
  // A fixed temporary name: only one run may write into a folder (the folder lock), and a stale one
  // is removed when the next run starts.
  const std::string temp = path + ".tmp";
  std::FILE* f = std::fopen(temp.c_str(), "wb");
  if (!f) throw IoError("resume: cannot write " + temp + ": " + std::strerror(errno));
  const std::string first = make_line(header_json(header)) + "\n";
  bool ok = std::fwrite(first.data(), 1, first.size(), f) == first.size();
  try {
    for (std::size_t k = 0; k < count && ok; ++k) {
      const std::string line = line_at(k);
      ok = std::fwrite(line.data(), 1, line.size(), f) == line.size() && std::fputc('\n', f) != EOF;
    }
  } catch (...) {
    std::fclose(f);
    std::remove(temp.c_str());
    throw;
  }
  if (std::fclose(f) != 0 || !ok || std::rename(temp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    std::remove(temp.c_str());
    throw IoError("resume: cannot write " + path + ": " + std::strerror(err));
  }
}

}  // namespace city3d::detail
