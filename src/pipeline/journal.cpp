// Resume journal: a line-oriented text file, tab-separated fields with \\, \t and \n escaped, doubles
// printed with 17 significant digits so that restored models are bit-identical to computed ones.
#include "pipeline/journal.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/log.hpp"

namespace city3d::detail {
namespace fs = std::filesystem;
namespace {

constexpr const char* kMagic = "city3d-journal 2";

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '\\') out += "\\\\";
    else if (c == '\t') out += "\\t";
    else if (c == '\n') out += "\\n";
    else if (c == '\r') out += "\\r";
    else out += c;
  }
  return out;
}

std::string unescape(const std::string& s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '\\' || i + 1 == s.size()) {
      out += s[i];
      continue;
    }
    const char n = s[++i];
    out += n == 't' ? '\t' : n == 'n' ? '\n' : n == 'r' ? '\r' : n;
  }
  return out;
}

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::vector<std::string> split_tabs(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  for (;;) {
    const std::size_t tab = line.find('\t', start);
    fields.push_back(line.substr(start, tab == std::string::npos ? std::string::npos : tab - start));
    if (tab == std::string::npos) return fields;
    start = tab + 1;
  }
}

// A model as four fields: origin, vertices, faces, surface types.
void serialise_model(std::ostringstream& out, const BuildingModel& m) {
  out << num(m.origin.x) << ' ' << num(m.origin.y) << ' ' << num(m.origin.z) << '\t' << m.mesh.vertices.size();
  for (const Point3& p : m.mesh.vertices) out << ' ' << num(p.x) << ' ' << num(p.y) << ' ' << num(p.z);
  out << '\t' << m.mesh.faces.size();
  for (const auto& f : m.mesh.faces) {
    out << ' ' << f.size();
    for (std::uint32_t v : f) out << ' ' << v;
  }
  out << '\t' << m.surfaces.size();
  for (SurfaceType t : m.surfaces) out << ' ' << static_cast<int>(t);
}

bool parse_model(const std::vector<std::string>& f, std::size_t at, const BuildingId& id, BuildingModel& m) {
  m.id = id;
  std::istringstream origin(f[at]), vertices(f[at + 1]), faces(f[at + 2]), surfaces(f[at + 3]);
  if (!(origin >> m.origin.x >> m.origin.y >> m.origin.z)) return false;
  std::size_t n = 0;
  if (!(vertices >> n)) return false;
  m.mesh.vertices.resize(n);
  for (Point3& p : m.mesh.vertices)
    if (!(vertices >> p.x >> p.y >> p.z)) return false;
  if (!(faces >> n)) return false;
  m.mesh.faces.resize(n);
  for (auto& face : m.mesh.faces) {
    std::size_t k = 0;
    if (!(faces >> k)) return false;
    face.resize(k);
    for (std::uint32_t& v : face)
      if (!(faces >> v) || v >= m.mesh.vertices.size()) return false;
  }
  if (!(surfaces >> n)) return false;
  m.surfaces.resize(n);
  for (SurfaceType& t : m.surfaces) {
    int v = 0;
    if (!(surfaces >> v) || v < 0 || v > 2) return false;
    t = static_cast<SurfaceType>(v);
  }
  return true;
}

// The report's 3DBAG-style fields, after the first 18.
constexpr std::size_t kReportFields = 36;

std::string serialise(const BuildingResult& result) {
  const BuildingReport& r = result.report;
  std::ostringstream out;
  out << escape(r.id) << '\t' << static_cast<int>(r.status) << '\t' << static_cast<int>(r.level) << '\t'
      << escape(r.stage) << '\t' << escape(r.reason) << '\t' << escape(r.note) << '\t' << r.points << '\t'
      << r.ground_points << '\t' << num(r.ground_z) << '\t' << escape(r.ground_method) << '\t' << num(r.roof_z)
      << '\t' << r.planes << '\t' << r.walls << '\t' << r.candidate_faces << '\t' << r.faces << '\t'
      << num(r.rmse) << '\t' << (r.valid ? 1 : 0) << '\t' << num(r.seconds) << '\t';
  out << escape(r.lods) << '\t' << escape(r.lods_reconstructed) << '\t' << num(r.footprint_area) << '\t'
      << num(r.point_density) << '\t' << num(r.h_roof_50p) << '\t' << num(r.h_roof_70p) << '\t' << num(r.h_roof_min)
      << '\t' << num(r.h_roof_max) << '\t' << num(r.h_ridge) << '\t' << escape(r.roof_type) << '\t'
      << num(r.volume_lod12) << '\t' << num(r.volume_lod13) << '\t' << num(r.volume_lod22) << '\t'
      << num(r.rmse_lod12) << '\t' << num(r.rmse_lod13) << '\t' << num(r.rmse_lod22) << '\t'
      << escape(r.validity_found) << '\t' << escape(r.repairs) << '\t';
  if (!result.model) {
    out << "-\n";
    return out.str();
  }
  serialise_model(out, *result.model);
  out << '\t' << result.lods.size();
  for (const LodModel& lod : result.lods) {
    out << '\t' << escape(lod.lod) << '\t';
    serialise_model(out, lod.model);
  }
  out << "\tend\n";
  return out.str();
}

// Parses one journal line; false when it is damaged (a run killed in the middle of a write).
bool parse(const std::string& line, BuildingResult& result) {
  const std::vector<std::string> f = split_tabs(line);
  if (f.size() != kReportFields + 1 && f.size() < kReportFields + 6) return false;
  try {
    BuildingReport& r = result.report;
    r.id = unescape(f[0]);
    r.status = static_cast<BuildingStatus>(std::stoi(f[1]));
    r.level = static_cast<ModelLevel>(std::stoi(f[2]));
    r.stage = unescape(f[3]);
    r.reason = unescape(f[4]);
    r.note = unescape(f[5]);
    r.points = std::stoull(f[6]);
    r.ground_points = std::stoull(f[7]);
    r.ground_z = std::stod(f[8]);
    r.ground_method = unescape(f[9]);
    r.roof_z = std::stod(f[10]);
    r.planes = std::stoull(f[11]);
    r.walls = std::stoull(f[12]);
    r.candidate_faces = std::stoull(f[13]);
    r.faces = std::stoull(f[14]);
    r.rmse = std::stod(f[15]);
    r.valid = f[16] == "1";
    r.seconds = std::stod(f[17]);
    r.lods = unescape(f[18]);
    r.lods_reconstructed = unescape(f[19]);
    double* numbers[] = {&r.footprint_area, &r.point_density, &r.h_roof_50p, &r.h_roof_70p, &r.h_roof_min,
                         &r.h_roof_max, &r.h_ridge};
    for (std::size_t k = 0; k < 7; ++k) *numbers[k] = std::stod(f[20 + k]);
    r.roof_type = unescape(f[27]);
    double* more[] = {&r.volume_lod12, &r.volume_lod13, &r.volume_lod22, &r.rmse_lod12, &r.rmse_lod13, &r.rmse_lod22};
    for (std::size_t k = 0; k < 6; ++k) *more[k] = std::stod(f[28 + k]);
    r.validity_found = unescape(f[34]);
    r.repairs = unescape(f[35]);
    if (f.size() == kReportFields + 1) return f[kReportFields] == "-";
    if (f.back() != "end") return false;
    BuildingModel m;
    if (!parse_model(f, kReportFields, r.id, m)) return false;
    const std::size_t lods = std::stoull(f[kReportFields + 4]);
    if (f.size() != kReportFields + 5 + 5 * lods + 1) return false;
    for (std::size_t k = 0; k < lods; ++k) {
      LodModel lod;
      lod.lod = unescape(f[kReportFields + 5 + 5 * k]);
      if (!parse_model(f, kReportFields + 6 + 5 * k, r.id, lod.model)) return false;
      result.lods.push_back(std::move(lod));
    }
    result.model = std::move(m);
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

std::string file_stamp(const std::string& path) {
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  const auto time = fs::last_write_time(path, ec).time_since_epoch().count();
  return path + " " + std::to_string(ec ? 0 : size) + " " + std::to_string(ec ? 0 : time);
}

}  // namespace

std::string batch_fingerprint(const BatchOptions& o, const std::vector<std::string>& files) {
  std::ostringstream s;
  s << CITY3D_VERSION << '\n';
  for (const std::string& f : files) s << file_stamp(f) << '\n';
  if (!o.footprints.empty()) s << file_stamp(o.footprints) << '\n';
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
  s << (o.ground_z ? num(*o.ground_z) : "-") << '\n';
  // FNV-1a, 64 bits: enough to tell runs apart; the journal is not a security boundary.
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s.str()) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

Journal::Journal(std::string path, const std::string& fingerprint, bool resume) : path_(std::move(path)) {
  const std::string header = std::string(kMagic) + " " + fingerprint;
  std::vector<std::string> kept;
  if (resume) {
    std::ifstream in(path_, std::ios::binary);
    std::string first;
    if (in && std::getline(in, first)) {
      if (first == header) {
        std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        std::size_t start = 0;
        // Only lines ending in a newline are complete.
        for (std::size_t nl = content.find('\n'); nl != std::string::npos; nl = content.find('\n', start)) {
          std::string line = content.substr(start, nl - start);
          start = nl + 1;
          BuildingResult result;
          if (parse(line, result)) {
            done_[result.report.id] = std::move(result);
            kept.push_back(std::move(line));
          }
        }
      } else {
        log_warning("resume: " + path_ + " is from another run (inputs or parameters differ); starting afresh");
      }
    }
  }
  // Rewrite the journal with its good lines only, then append to it.
  const std::string temp = path_ + ".tmp";
  std::FILE* f = std::fopen(temp.c_str(), "wb");
  if (!f) throw IoError("resume: cannot write " + temp + ": " + std::strerror(errno));
  std::fprintf(f, "%s\n", header.c_str());
  for (const std::string& line : kept) std::fprintf(f, "%s\n", line.c_str());
  if (std::fclose(f) != 0 || std::rename(temp.c_str(), path_.c_str()) != 0)
    throw IoError("resume: cannot write " + path_ + ": " + std::strerror(errno));
  file_ = std::fopen(path_.c_str(), "ab");
  if (!file_) throw IoError("resume: cannot append to " + path_ + ": " + std::strerror(errno));
  if (!done_.empty()) log_info("resume: " + std::to_string(done_.size()) + " finished buildings in " + path_);
}

Journal::~Journal() {
  if (file_) std::fclose(file_);
}

const BuildingResult* Journal::find(const BuildingId& id) const {
  const auto it = done_.find(id);
  return it == done_.end() ? nullptr : &it->second;
}

void Journal::append(const BuildingResult& result) {
  const std::string line = serialise(result);
  std::lock_guard<std::mutex> lock(mutex_);
  if (std::fwrite(line.data(), 1, line.size(), file_) != line.size() || std::fflush(file_) != 0)
    throw IoError("resume: cannot append to " + path_ + ": " + std::strerror(errno));
}

}  // namespace city3d::detail
