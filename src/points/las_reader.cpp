// LAS reader: validates the public header (collecting every problem before throwing once), walks
// VLRs and EVLRs with bounds checks, and streams point records (formats 0-10) into PointCloud.
// Raw records come from a RecordSource: a plain file read, or the LAZ decoder (src/laz/) through the
// record sources of laz_records.hpp.
#include "points/las_reader.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/log.hpp"
#include "laz/laz_decoder.hpp"
#include "points/input_file.hpp"
#include "points/laz_records.hpp"

// Fields are copied straight out of the little-endian records with memcpy.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the LAS reader assumes a little-endian host");

namespace city3d::detail {
namespace {

// Header sizes by version (LAS 1.0-1.2: 227, 1.3 adds the waveform pointer, 1.4 EVLRs and 64-bit counts).
constexpr std::size_t kHeaderSize12 = 227;
constexpr std::size_t kHeaderSize13 = 235;
constexpr std::size_t kHeaderSize14 = 375;
constexpr std::size_t kVlrHeaderSize = 54;
constexpr std::size_t kEvlrHeaderSize = 60;
constexpr std::uint16_t kLaszipRecordId = 22204;
constexpr std::uint16_t kWktRecordId = 2112;
constexpr std::uint16_t kGeoKeyDirectoryRecordId = 34735;
constexpr std::uint16_t kProjectedCsTypeGeoKey = 3072;
constexpr std::uint16_t kGeographicTypeGeoKey = 2048;
constexpr std::uint16_t kGeoKeyUserDefined = 32767;
constexpr std::size_t kMaxCrsPayload = 1u << 20;   // a WKT larger than this is not a CRS
constexpr std::size_t kReadBlockBytes = 2u << 20;  // raw records per fread: about 2 MB

// Minimum record size of point data formats 0-10.
constexpr std::array<std::uint16_t, 11> kFormatSize = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};

template <typename T>
T get(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

std::string fixed_string(const std::uint8_t* p, std::size_t n) {
  std::string s(reinterpret_cast<const char*>(p), n);
  s = s.substr(0, s.find('\0'));
  while (!s.empty() && (s.back() == ' ' || s.back() == '\n' || s.back() == '\r')) s.pop_back();
  return s;
}

std::string number(double v) {
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}

/// Where the optional fields of a point data format sit inside a record.
struct PointLayout {
  bool extended = false;  // formats 6-10: 4-bit return fields, full-byte class at 16
  // The withheld flag, in byte 15 of every format: bit 7 beside the 5-bit class of formats 0-5, bit 2
  // of the classification flags of formats 6-10.
  std::uint8_t withheld_bit = 0x80;
  int gps_offset = -1;
  int rgb_offset = -1;

  static PointLayout of(int format) {
    PointLayout l;
    l.extended = format >= 6;
    if (l.extended) l.withheld_bit = 0x04;
    switch (format) {
      case 1: case 4: l.gps_offset = 20; break;
      case 2: l.rgb_offset = 20; break;
      case 3: case 5: l.gps_offset = 20; l.rgb_offset = 28; break;
      case 6: case 9: l.gps_offset = 22; break;
      case 7: case 8: case 10: l.gps_offset = 22; l.rgb_offset = 30; break;
      default: break;
    }
    return l;
  }
};

/// The header facts the point reader needs, after validation.
struct LasHeader {
  std::uint16_t header_size = 0;
  std::uint32_t offset_to_point_data = 0;
  int point_format = 0;
  std::uint16_t record_length = 0;
  std::uint64_t point_count = 0;
  std::array<double, 3> scale{};
  std::array<double, 3> offset{};
  bool compressed = false;
  bool may_overflow = false;  // some int32 * scale + offset is not finite: check every point
  std::vector<std::uint8_t> laszip_vlr;  // payload of the LASzip VLR, for the LAZ decoder
};

std::size_t minimum_header_size(int major, int minor) {
  if (major == 1 && minor == 3) return kHeaderSize13;
  if (major == 1 && minor >= 4) return kHeaderSize14;
  return kHeaderSize12;
}

/// Reads the CRS out of a GeoTIFF GeoKeyDirectory: entries of (key, location, count, value); a
/// location of 0 means the value is stored inline.
std::string crs_from_geokeys(const std::uint8_t* data, std::size_t size) {
  if (size < 8) return {};
  const std::size_t keys = get<std::uint16_t>(data + 6);
  std::string projected, geographic;
  for (std::size_t k = 0; k < keys && 8 + (k + 1) * 8 <= size; ++k) {
    const std::uint8_t* e = data + 8 + k * 8;
    const auto id = get<std::uint16_t>(e);
    const auto location = get<std::uint16_t>(e + 2);
    const auto value = get<std::uint16_t>(e + 6);
    if (location != 0 || value == 0 || value == kGeoKeyUserDefined) continue;
    if (id == kProjectedCsTypeGeoKey) projected = "EPSG:" + std::to_string(value);
    if (id == kGeographicTypeGeoKey) geographic = "EPSG:" + std::to_string(value);
  }
  return projected.empty() ? geographic : projected;
}

std::string vlr_label(const std::string& user_id, std::uint16_t record_id, std::uint64_t bytes,
                      bool extended) {
  return user_id + "/" + std::to_string(record_id) + " (" + std::to_string(bytes) + " bytes" +
         (extended ? ", EVLR)" : ")");
}

/// Collects CRS candidates while walking (E)VLRs: WKT wins over GeoTIFF keys.
struct CrsFinder {
  std::string wkt;
  std::string geokeys;
  void look_at(const std::string& user_id, std::uint16_t record_id, const std::uint8_t* data,
               std::size_t size) {
    if (user_id != "LASF_Projection") return;
    if (record_id == kWktRecordId) wkt = fixed_string(data, size);
    if (record_id == kGeoKeyDirectoryRecordId) geokeys = crs_from_geokeys(data, size);
  }
  std::string best() const { return wkt.empty() ? geokeys : wkt; }
};

/// Walks the VLRs between the header and the point data. A VLR that runs past the point data is
/// reported once and ends the walk: the points can still be read.
void walk_vlrs(InputFile& file, std::uint32_t count, std::uint64_t begin, std::uint64_t end,
               LasHeader& h, PointCloudInfo& info, CrsFinder& crs) {
  std::vector<std::uint8_t> block(static_cast<std::size_t>(end > begin ? end - begin : 0));
  if (!block.empty() && file.read_at(begin, block.data(), block.size()) != block.size())
    throw IoError("las: cannot read the VLRs (bytes " + std::to_string(begin) + "-" +
                  std::to_string(end) + ") of " + file.path());
  std::size_t pos = 0;
  for (std::uint32_t i = 0; i < count; ++i) {
    if (pos + kVlrHeaderSize > block.size()) {
      log_warning("las: VLR " + std::to_string(i + 1) + " of " + std::to_string(count) + " in " +
                  file.path() + " starts at byte " + std::to_string(begin + pos) +
                  " but its header runs past the point data at byte " + std::to_string(end) +
                  "; ignoring it and the rest");
      return;
    }
    const std::uint8_t* v = block.data() + pos;
    const std::string user_id = fixed_string(v + 2, 16);
    const auto record_id = get<std::uint16_t>(v + 18);
    const std::size_t length = get<std::uint16_t>(v + 20);
    if (pos + kVlrHeaderSize + length > block.size()) {
      log_warning("las: VLR " + std::to_string(i + 1) + " of " + std::to_string(count) + " (" +
                  user_id + "/" + std::to_string(record_id) + ", " + std::to_string(length) +
                  " bytes) in " + file.path() + " runs past the point data at byte " +
                  std::to_string(end) + "; ignoring it and the rest");
      return;
    }
    const std::uint8_t* payload = v + kVlrHeaderSize;
    info.vlrs.push_back(vlr_label(user_id, record_id, length, false));
    if (user_id == "laszip encoded" && record_id == kLaszipRecordId) {
      h.compressed = true;
      h.laszip_vlr.assign(payload, payload + length);
    }
    crs.look_at(user_id, record_id, payload, length);
    pos += kVlrHeaderSize + length;
  }
}

/// Walks the LAS 1.4 EVLRs at the end of the file. Pointers out of range are warnings.
void walk_evlrs(InputFile& file, std::uint64_t start, std::uint32_t count, std::uint64_t min_start,
                PointCloudInfo& info, CrsFinder& crs) {
  if (count == 0) return;
  if (start < min_start || start >= file.size()) {
    log_warning("las: EVLR pointer " + std::to_string(start) + " in " + file.path() +
                " is outside the file (" + std::to_string(file.size()) + " bytes, points end at " +
                std::to_string(min_start) + "); ignoring " + std::to_string(count) + " EVLRs");
    return;
  }
  std::uint64_t pos = start;
  for (std::uint32_t i = 0; i < count; ++i) {
    std::uint8_t head[kEvlrHeaderSize];
    if (pos > file.size() || file.size() - pos < kEvlrHeaderSize ||
        file.read_at(pos, head, kEvlrHeaderSize) != kEvlrHeaderSize) {
      log_warning("las: EVLR " + std::to_string(i + 1) + " of " + std::to_string(count) + " in " +
                  file.path() + " at byte " + std::to_string(pos) +
                  " runs past the end of the file; ignoring it and the rest");
      return;
    }
    const std::string user_id = fixed_string(head + 2, 16);
    const auto record_id = get<std::uint16_t>(head + 18);
    const auto length = get<std::uint64_t>(head + 20);
    if (file.size() - pos - kEvlrHeaderSize < length) {
      log_warning("las: EVLR " + std::to_string(i + 1) + " of " + std::to_string(count) + " (" +
                  user_id + "/" + std::to_string(record_id) + ", " + std::to_string(length) +
                  " bytes) in " + file.path() + " runs past the end of the file; ignoring it and the rest");
      return;
    }
    info.vlrs.push_back(vlr_label(user_id, record_id, length, true));
    if (user_id == "LASF_Projection" && length <= kMaxCrsPayload) {
      std::vector<std::uint8_t> payload(static_cast<std::size_t>(length));
      file.read_at(pos + kEvlrHeaderSize, payload.data(), payload.size());
      crs.look_at(user_id, record_id, payload.data(), payload.size());
    }
    pos += kEvlrHeaderSize + length;
  }
}

/// Reads and validates the header of `file`, fills `info`, and returns what the point reader needs.
/// Every header problem is collected and thrown in one IoError.
LasHeader read_header(InputFile& file, PointCloudInfo& info) {
  const std::string& path = file.path();
  const std::uint64_t file_size = file.size();
  if (file_size == 0) throw IoError("las: " + path + " is empty (0 bytes)");

  std::array<std::uint8_t, kHeaderSize14> raw{};
  const std::size_t got = file.read_at(0, raw.data(), raw.size());
  const std::uint8_t* b = raw.data();
  const bool signature_ok = got >= 4 && std::memcmp(b, "LASF", 4) == 0;
  if (got < kHeaderSize12 || (got >= 26 && got < minimum_header_size(b[24], b[25]))) {
    const std::size_t need = got >= 26 ? minimum_header_size(b[24], b[25]) : kHeaderSize12;
    throw IoError("las: header truncated at byte " + std::to_string(got) + " in " + path +
                  " (a LAS header needs " + std::to_string(need) + " bytes)" +
                  (signature_ok ? "" : "; no 'LASF' signature either"));
  }

  LasHeader h;
  std::vector<std::string> problems;
  if (!signature_ok) problems.push_back("signature is '" + fixed_string(b, 4) + "', expected 'LASF'");

  const int major = b[24];
  const int minor = b[25];
  const std::string version = std::to_string(major) + "." + std::to_string(minor);
  if (major != 1 || minor > 4) problems.push_back("version " + version + " is not LAS 1.0-1.4");
  const std::size_t min_header = minimum_header_size(major, minor);

  h.header_size = get<std::uint16_t>(b + 94);
  h.offset_to_point_data = get<std::uint32_t>(b + 96);
  const auto vlr_count = get<std::uint32_t>(b + 100);
  const std::uint8_t format_byte = b[104];
  h.record_length = get<std::uint16_t>(b + 105);
  h.point_count = get<std::uint32_t>(b + 107);
  const bool has_14_fields = major == 1 && minor >= 4 && h.header_size >= kHeaderSize14;
  if (has_14_fields) {
    // LAS 1.4 keeps a 64-bit count at 247; the legacy 32-bit one is 0 for formats 6-10.
    const auto count64 = get<std::uint64_t>(b + 247);
    if (count64 != 0) h.point_count = count64;
  }
  for (int a = 0; a < 3; ++a) {
    h.scale[a] = get<double>(b + 131 + 8 * a);
    h.offset[a] = get<double>(b + 155 + 8 * a);
  }

  if (h.header_size < min_header)
    problems.push_back("header size " + std::to_string(h.header_size) + " is below the LAS " +
                       version + " minimum of " + std::to_string(min_header));
  if (h.header_size > file_size)
    problems.push_back("header size " + std::to_string(h.header_size) + " is larger than the file (" +
                       std::to_string(file_size) + " bytes)");
  if (h.offset_to_point_data < h.header_size)
    problems.push_back("offset to point data " + std::to_string(h.offset_to_point_data) +
                       " is inside the header (" + std::to_string(h.header_size) + " bytes)");
  if (h.offset_to_point_data > file_size)
    problems.push_back("offset to point data " + std::to_string(h.offset_to_point_data) +
                       " is past the end of the file (" + std::to_string(file_size) + " bytes)");

  // Bit 7 (LASzip) or bit 6 (old LAStools marker) of the format byte flags compression.
  h.compressed = (format_byte & 0xC0) != 0;
  h.point_format = format_byte & 0x3F;
  const bool format_known = h.point_format < static_cast<int>(kFormatSize.size());
  if (!format_known)
    problems.push_back("point data format " + std::to_string(h.point_format) +
                       " is unknown (expected 0-10)");
  else if (h.record_length < kFormatSize[h.point_format])
    problems.push_back("point record length " + std::to_string(h.record_length) +
                       " is smaller than point data format " + std::to_string(h.point_format) +
                       " needs (" + std::to_string(kFormatSize[h.point_format]) + ")");

  const char* axis = "xyz";
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(h.scale[a]) || h.scale[a] == 0.0)
      problems.push_back(std::string("scale ") + axis[a] + " is " + number(h.scale[a]) +
                         " (must be finite and non-zero)");
    if (!std::isfinite(h.offset[a]))
      problems.push_back(std::string("offset ") + axis[a] + " is " + number(h.offset[a]) +
                         " (must be finite)");
    // |int32| <= 2^31: when this bound overflows, points must be checked one by one.
    if (!std::isfinite(std::fabs(h.scale[a]) * 2147483648.0 + std::fabs(h.offset[a])))
      h.may_overflow = true;
  }

  info.path = path;
  info.version = version;
  info.point_format = h.point_format;
  info.record_length = h.record_length;
  info.point_count = h.point_count;
  info.scale = h.scale;
  info.offset = h.offset;
  info.generating_software = fixed_string(b + 58, 32);
  info.bounds.min = {get<double>(b + 187), get<double>(b + 203), get<double>(b + 219)};
  info.bounds.max = {get<double>(b + 179), get<double>(b + 195), get<double>(b + 211)};

  // VLRs sit between the header and the point data; walk them only when that range makes sense.
  CrsFinder crs;
  const bool vlr_range_ok = h.header_size >= min_header && h.header_size <= file_size &&
                            h.offset_to_point_data >= h.header_size;
  if (vlr_range_ok)
    walk_vlrs(file, vlr_count, h.header_size, std::min<std::uint64_t>(h.offset_to_point_data, file_size),
              h, info, crs);

  // Compressed point blocks are smaller than count * record length: that check is for LAS only.
  const std::uint64_t available =
      h.offset_to_point_data <= file_size ? file_size - h.offset_to_point_data : 0;
  if (!h.compressed && h.record_length > 0 && h.point_count > available / h.record_length)
    problems.push_back("point count " + std::to_string(h.point_count) + " x record length " +
                       std::to_string(h.record_length) + " = " +
                       number(static_cast<double>(h.point_count) * h.record_length) +
                       " bytes is larger than the file: only " + std::to_string(available) +
                       " bytes follow the point data offset " + std::to_string(h.offset_to_point_data));

  if (!problems.empty()) {
    std::string message = "las: invalid header in " + path + ": ";
    for (std::size_t i = 0; i < problems.size(); ++i) message += (i ? "; " : "") + problems[i];
    throw IoError(message);
  }

  const std::uint64_t points_end =
      h.compressed ? h.offset_to_point_data : h.offset_to_point_data + h.point_count * h.record_length;
  if (has_14_fields)
    walk_evlrs(file, get<std::uint64_t>(b + 235), get<std::uint32_t>(b + 243), points_end, info, crs);
  // Whole records after the counted ones that no later part of the file claims (LAS 1.3's waveform
  // packets, 1.4's EVLRs): a header whose count was not rewritten when points were added.
  if (!h.compressed && h.record_length > 0) {
    std::uint64_t end = file_size;
    const auto claim = [&](std::uint64_t start) {
      if (start >= points_end && start < end) end = start;
    };
    if (minor >= 3 && h.header_size >= 235) claim(get<std::uint64_t>(b + 227));
    if (has_14_fields && get<std::uint32_t>(b + 243) > 0) claim(get<std::uint64_t>(b + 235));
    info.uncounted_records = (end - points_end) / h.record_length;
  }

  info.format = h.compressed ? "LAZ" : "LAS";
  info.compressed = h.compressed;
  info.crs = crs.best();
  const PointLayout layout = PointLayout::of(h.point_format);
  info.fields = kFieldXyz | kFieldIntensity | kFieldReturns | kFieldClassification;
  if (layout.gps_offset >= 0) info.fields |= kFieldGpsTime;
  if (layout.rgb_offset >= 0) info.fields |= kFieldRgb;
  return h;
}

/// Uncompressed LAS: the records are a contiguous block read with large freads.
class FileRecordSource final : public RecordSource {
 public:
  FileRecordSource(InputFile file, const LasHeader& h)
      : file_(std::move(file)), record_length_(h.record_length), total_(h.point_count) {
    file_.seek(h.offset_to_point_data);
  }

  std::size_t read_records(std::uint8_t* out, std::size_t max_records) override {
    const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(max_records, total_ - done_));
    const std::size_t bytes = n * record_length_;
    const std::size_t got = file_.read_some(out, bytes);
    if (got != bytes)  // the header check passed, so the file shrank or the disk failed
      throw IoError("las: " + file_.path() + " ends after point " +
                    std::to_string(done_ + got / record_length_) + " of " + std::to_string(total_));
    done_ += n;
    return n;
  }

 private:
  InputFile file_;
  std::size_t record_length_;
  std::uint64_t total_;
  std::uint64_t done_ = 0;
};

/// What a read does with the chunks of a LAZ file (open_point_cloud with ChunkExtents).
struct ChunkPlan {
  ChunkExtents* extents = nullptr;             ///< learnt bounds to use, or empty ones to fill
  const std::vector<Box2>* regions = nullptr;  ///< what the reader needs, once the bounds are known
  std::vector<std::uint64_t> fill;      ///< set by make_record_source: points per chunk, to learn the bounds
  std::size_t chunks = 0, decoded = 0;  ///< set by make_record_source: the file's chunks, those read
};

/// Picks the record source for a validated header: the file itself, or the LAZ decoder, on
/// `decode_threads` threads when the file has several chunks (0 counts as 1). With a plan whose
/// bounds are known, only the chunks that meet its regions; with one whose bounds are empty, every
/// chunk, and the plan says how many points each holds. A file whose coordinates may overflow
/// (LasHeader::may_overflow) is always read whole, so that an error names the point's index in the file,
/// and so is one whose chunks are too large to hold one decoded (kMaxHeldChunkBytes).
std::unique_ptr<RecordSource> make_record_source(InputFile file, const LasHeader& h, unsigned decode_threads,
                                                 ChunkPlan* plan = nullptr) {
  if (!h.compressed) return std::make_unique<FileRecordSource>(std::move(file), h);
  detail::check_laszip_vlr_present(!h.laszip_vlr.empty(), static_cast<std::uint8_t>(h.point_format | 0x80),
                                   file.path());
  const detail::LaszipVlr vlr =
      detail::parse_laszip_vlr(h.laszip_vlr.data(), h.laszip_vlr.size(), file.path());
  detail::LazLayout layout;
  layout.path = file.path();
  layout.point_data_offset = h.offset_to_point_data;
  layout.point_count = h.point_count;
  layout.record_length = h.record_length;
  layout.point_format = static_cast<std::uint8_t>(h.point_format);
  layout.file_size = file.size();
  auto decoder = std::make_unique<detail::LazDecoder>(vlr, layout);
  const std::size_t chunks = decoder->chunk_count();
  std::vector<std::size_t> wanted(chunks);
  std::iota(wanted.begin(), wanted.end(), std::size_t{0});
  std::uint64_t largest = 0;
  for (std::size_t i = 0; i < chunks; ++i) largest = std::max(largest, decoder->chunk_points(i));
  if (plan && plan->extents && chunks > 1 && !h.may_overflow && largest * h.record_length <= kMaxHeldChunkBytes) {
    const std::vector<Box2>& boxes = plan->extents->boxes;
    if (boxes.empty()) {
      for (std::size_t i = 0; i < chunks; ++i) plan->fill.push_back(decoder->chunk_points(i));
    } else if (boxes.size() == chunks && plan->regions) {
      wanted.clear();
      for (std::size_t i = 0; i < chunks; ++i)
        if (std::any_of(plan->regions->begin(), plan->regions->end(),
                        [&](const Box2& r) { return r.intersects(boxes[i]); }))
          wanted.push_back(i);
    }
  }
  if (plan) plan->chunks = chunks, plan->decoded = wanted.size();
  return make_laz_record_source(std::move(decoder), std::move(wanted), h.record_length, decode_threads);
}

/// Grows a vector geometrically, so that many small appends stay linear.
template <typename T>
void reserve_for(std::vector<T>& v, std::size_t needed) {
  if (v.capacity() < needed) v.reserve(std::max(needed, v.capacity() * 2));
}

/// Makes room for `n` more values after the first `old_size` and returns where they go. Resizing to
/// the point count keeps the PointCloud invariant even when `out` arrived without this attribute
/// (its earlier entries are then zero).
template <typename T>
T* extend(std::vector<T>& v, std::size_t old_size, std::size_t n) {
  v.resize(old_size + n);
  return v.data() + old_size;
}

class LasReader final : public PointCloudReader {
 public:
  /// With `learn` (a LAZ read of every chunk, `chunk_points` per chunk), the read learns where the
  /// chunks lie and, once it has read to the end, puts their bounds in `learn`.
  LasReader(PointCloudInfo info, const LasHeader& h, std::unique_ptr<RecordSource> source, PointFields fields,
            ChunkExtents* learn = nullptr, std::vector<std::uint64_t> chunk_points = {})
      : info_(std::move(info)),
        scale_(h.scale),
        offset_(h.offset),
        layout_(PointLayout::of(h.point_format)),
        record_length_(h.record_length),
        check_finite_(h.may_overflow),
        fields_(fields & info_.fields),
        source_(std::move(source)),
        learn_(learn),
        chunk_points_(std::move(chunk_points)) {
    block_records_ = std::max<std::size_t>(1, kReadBlockBytes / record_length_);
    block_records_ = static_cast<std::size_t>(std::min<std::uint64_t>(block_records_, std::max<std::uint64_t>(1, info_.point_count)));
    buffer_.resize(block_records_ * record_length_);
  }

  const PointCloudInfo& info() const override { return info_; }
  std::uint64_t withheld_points() const override { return withheld_; }

  std::size_t read(PointCloud& out, std::size_t max_points) override {
    const std::size_t old_size = out.size();
    const std::size_t expect = static_cast<std::size_t>(
        std::min<std::uint64_t>(max_points, info_.point_count - next_index_));
    reserve_all(out, old_size + expect);
    std::size_t appended = 0;
    while (appended < max_points) {
      if (buffer_pos_ == buffer_count_) {
        buffer_count_ = source_->read_records(buffer_.data(), block_records_);
        buffer_pos_ = 0;
        if (buffer_count_ == 0) {
          if (learn_ && bounds_.size() == chunk_points_.size() && left_in_chunk_ == 0)
            learn_->boxes = std::move(bounds_);
          learn_ = nullptr;
          break;
        }
      }
      const std::size_t n = std::min(max_points - appended, buffer_count_ - buffer_pos_);
      const std::size_t before = out.points.size();
      const std::uint8_t* records = buffer_.data() + buffer_pos_ * record_length_;
      convert(records, n, out);
      if (learn_) learn_bounds(out.points.data() + before, n);
      const std::size_t kept = drop_withheld(records, n, before, out);
      buffer_pos_ += n;
      appended += kept;
      next_index_ += n;
    }
    return appended;
  }

 private:
  /// Adds `n` points just read, in file order, to the bounds of their chunks.
  void learn_bounds(const Point3* p, std::size_t n) {
    while (n > 0) {
      if (left_in_chunk_ == 0) {
        if (bounds_.size() == chunk_points_.size()) return;  // more points than the chunks hold: not learnt
        bounds_.emplace_back();
        left_in_chunk_ = chunk_points_[bounds_.size() - 1];
      }
      const auto take = static_cast<std::size_t>(std::min<std::uint64_t>(n, left_in_chunk_));
      Box2& box = bounds_.back();
      for (std::size_t i = 0; i < take; ++i) box.add({p[i].x, p[i].y});
      p += take;
      n -= take;
      left_in_chunk_ -= take;
    }
  }

  /// Takes the withheld points out of the `n` just converted from `records` (appended to `out` after
  /// its first `before`): the LAS specification has readers treat them as deleted. Returns how many
  /// points are left. Their bounds were learnt already: a LAZ chunk's bounds are those of its records.
  std::size_t drop_withheld(const std::uint8_t* records, std::size_t n, std::size_t before, PointCloud& out) {
    const std::uint8_t bit = layout_.withheld_bit;
    std::size_t first = 0;
    while (first < n && !(records[first * record_length_ + 15] & bit)) ++first;
    if (first == n) return n;
    const auto compact = [&](auto& v) {
      if (v.size() != before + n) return;  // an attribute not read
      std::size_t to = before + first;
      for (std::size_t i = first; i < n; ++i)
        if (!(records[i * record_length_ + 15] & bit)) v[to++] = v[before + i];
      v.resize(to);
    };
    compact(out.points);
    compact(out.intensity);
    compact(out.return_number);
    compact(out.number_of_returns);
    compact(out.classification);
    compact(out.gps_time);
    compact(out.rgb);
    const std::size_t kept = out.points.size() - before;
    withheld_ += n - kept;
    return kept;
  }

  void reserve_all(PointCloud& out, std::size_t needed) {
    reserve_for(out.points, needed);
    if (fields_ & kFieldIntensity) reserve_for(out.intensity, needed);
    if (fields_ & kFieldReturns) {
      reserve_for(out.return_number, needed);
      reserve_for(out.number_of_returns, needed);
    }
    if (fields_ & kFieldClassification) reserve_for(out.classification, needed);
    if (fields_ & kFieldGpsTime) reserve_for(out.gps_time, needed);
    if (fields_ & kFieldRgb) reserve_for(out.rgb, needed);
  }

  /// Converts `n` raw records to points and the requested attributes, one tight loop per field.
  void convert(const std::uint8_t* records, std::size_t n, PointCloud& out) {
    const std::size_t old_size = out.points.size();
    const std::size_t rl = record_length_;
    Point3* p = extend(out.points, old_size, n);
    const double sx = scale_[0], sy = scale_[1], sz = scale_[2];
    const double ox = offset_[0], oy = offset_[1], oz = offset_[2];
    for (std::size_t i = 0; i < n; ++i) {
      std::int32_t xyz[3];
      std::memcpy(xyz, records + i * rl, sizeof xyz);
      p[i].x = xyz[0] * sx + ox;
      p[i].y = xyz[1] * sy + oy;
      p[i].z = xyz[2] * sz + oz;
    }
    if (check_finite_) {
      for (std::size_t i = 0; i < n; ++i) {
        if (!std::isfinite(p[i].x) || !std::isfinite(p[i].y) || !std::isfinite(p[i].z))
          throw IoError("las: point " + std::to_string(next_index_ + i) + " in " + info_.path +
                        " has a non-finite coordinate (" + number(p[i].x) + ", " + number(p[i].y) +
                        ", " + number(p[i].z) + ") after scale and offset");
      }
    }
    if (fields_ & kFieldIntensity) {
      std::uint16_t* d = extend(out.intensity, old_size, n);
      for (std::size_t i = 0; i < n; ++i) std::memcpy(d + i, records + i * rl + 12, 2);
    }
    if (fields_ & kFieldReturns) {
      std::uint8_t* r = extend(out.return_number, old_size, n);
      std::uint8_t* c = extend(out.number_of_returns, old_size, n);
      if (layout_.extended) {  // formats 6-10: two 4-bit fields
        for (std::size_t i = 0; i < n; ++i) {
          const std::uint8_t v = records[i * rl + 14];
          r[i] = v & 0x0F;
          c[i] = v >> 4;
        }
      } else {  // formats 0-5: 3-bit return number, 3-bit number of returns
        for (std::size_t i = 0; i < n; ++i) {
          const std::uint8_t v = records[i * rl + 14];
          r[i] = v & 0x07;
          c[i] = (v >> 3) & 0x07;
        }
      }
    }
    if (fields_ & kFieldClassification) {
      std::uint8_t* d = extend(out.classification, old_size, n);
      if (layout_.extended) {  // formats 6-10: the whole byte at 16 is the class
        for (std::size_t i = 0; i < n; ++i) d[i] = records[i * rl + 16];
      } else {  // formats 0-5: low 5 bits; the high 3 are synthetic / key-point / withheld flags
        for (std::size_t i = 0; i < n; ++i) d[i] = records[i * rl + 15] & 0x1F;
      }
    }
    if (fields_ & kFieldGpsTime) {
      double* d = extend(out.gps_time, old_size, n);
      const std::size_t at = static_cast<std::size_t>(layout_.gps_offset);
      for (std::size_t i = 0; i < n; ++i) std::memcpy(d + i, records + i * rl + at, 8);
    }
    if (fields_ & kFieldRgb) {
      std::array<std::uint16_t, 3>* d = extend(out.rgb, old_size, n);
      const std::size_t at = static_cast<std::size_t>(layout_.rgb_offset);
      for (std::size_t i = 0; i < n; ++i) std::memcpy(d[i].data(), records + i * rl + at, 6);
    }
  }

  PointCloudInfo info_;
  std::array<double, 3> scale_;
  std::array<double, 3> offset_;
  PointLayout layout_;
  std::size_t record_length_;
  bool check_finite_;
  PointFields fields_;
  std::unique_ptr<RecordSource> source_;
  std::vector<std::uint8_t> buffer_;
  std::size_t block_records_ = 0;
  std::size_t buffer_count_ = 0;
  std::size_t buffer_pos_ = 0;
  std::uint64_t next_index_ = 0;             ///< records read so far (withheld ones included)
  std::uint64_t withheld_ = 0;               ///< withheld records left out so far
  ChunkExtents* learn_;                      ///< where the chunks' bounds go at the end, or null
  std::vector<std::uint64_t> chunk_points_;  ///< points per chunk, for learning their bounds
  std::vector<Box2> bounds_;                 ///< the bounds of the chunks read so far
  std::uint64_t left_in_chunk_ = 0;          ///< points of the last of them still to come
};

}  // namespace

std::unique_ptr<PointCloudReader> open_las(const std::string& path, PointFields fields,
                                           unsigned decode_threads, ChunkExtents* extents,
                                           const std::vector<Box2>* regions) {
  InputFile file(path, "las");
  PointCloudInfo info;
  const LasHeader h = read_header(file, info);
  ChunkPlan plan{extents, regions, {}, 0, 0};
  auto source = make_record_source(std::move(file), h, decode_threads, &plan);
  if (plan.decoded < plan.chunks)
    log_debug("las: " + path + ": " + std::to_string(plan.decoded) + " of " + std::to_string(plan.chunks) +
              " chunks meet the regions read");
  ChunkExtents* learn = plan.fill.empty() ? nullptr : extents;
  return std::make_unique<LasReader>(std::move(info), h, std::move(source), fields, learn,
                                     std::move(plan.fill));
}

PointCloudInfo read_las_info(const std::string& path) {
  InputFile file(path, "las");
  PointCloudInfo info;
  read_header(file, info);
  return info;
}

std::string read_las_end_records(const std::string& path, std::size_t n) {
  InputFile file(path, "las");
  PointCloudInfo info;
  const LasHeader h = read_header(file, info);
  const std::size_t length = h.record_length;
  const std::uint64_t count = h.point_count;
  const std::size_t k = static_cast<std::size_t>(std::min<std::uint64_t>(n, count));
  std::string first(k * length, '\0'), last(k * length, '\0');
  if (k == 0) return {};
  if (!h.compressed) {
    const std::uint64_t begin = h.offset_to_point_data;
    if (file.read_at(begin, first.data(), first.size()) != first.size() ||
        file.read_at(begin + (count - k) * length, last.data(), last.size()) != last.size())
      throw IoError("las: " + path + " ends before its last point record");
    return first + last;
  }
  // The same decoder as open_las(), one thread.
  const auto source = make_record_source(std::move(file), h, 1);
  auto& laz = dynamic_cast<LazRecordSource&>(*source);
  const detail::LazDecoder& decoder = laz.decoder();
  const std::size_t chunks = decoder.chunk_count();
  if (chunks > 1 && decoder.chunk_points(0) >= k && decoder.chunk_points(chunks - 1) >= k) {
    std::vector<std::uint8_t> chunk(static_cast<std::size_t>(decoder.chunk_points(0)) * length);
    decoder.decode_chunk(0, chunk.data());
    std::memcpy(first.data(), chunk.data(), first.size());
    chunk.resize(static_cast<std::size_t>(decoder.chunk_points(chunks - 1)) * length);
    decoder.decode_chunk(chunks - 1, chunk.data());
    std::memcpy(last.data(), chunk.data() + chunk.size() - last.size(), last.size());
    return first + last;
  }
  // One stream (or chunks smaller than n): decode through, keeping the first k and a window that
  // ends with the last k.
  constexpr std::size_t kBatch = 1 << 16;
  std::vector<std::uint8_t> batch(kBatch * length);
  std::string window;
  std::uint64_t done = 0;
  for (std::size_t got; (got = laz.read_records(batch.data(), kBatch)) > 0; done += got) {
    if (done < k) {
      const std::size_t take = static_cast<std::size_t>(std::min<std::uint64_t>(k - done, got));
      std::memcpy(first.data() + done * length, batch.data(), take * length);
    }
    window.append(reinterpret_cast<const char*>(batch.data()), got * length);
    if (window.size() > last.size()) window.erase(0, window.size() - last.size());
  }
  if (window.size() != last.size()) throw IoError("laz: " + path + " ends before its last point record");
  return first + window;
}

}  // namespace city3d::detail
