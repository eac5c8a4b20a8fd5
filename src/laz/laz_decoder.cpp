// LASzip decoding: the LASzip VLR, the chunk table, and the chunk loop that drives the per-item
// decoders of compressor 2 (pointwise-chunked, v1/v2 items), compressor 3 (layered, v3 items) and
// the old compressor 1 (pointwise, one stream without chunks).
#include "laz/laz_decoder.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cassert>
#include <cerrno>
#include <cstring>

#include "city3d/error.hpp"
#include "laz/arithmetic_decoder.hpp"
#include "laz/items_v1.hpp"
#include "laz/items_v2.hpp"
#include "laz/items_v3.hpp"

namespace city3d::detail {

namespace {

using laz::load;

constexpr std::size_t kVlrFixedSize = 34;  ///< LASzip VLR bytes before the item list
constexpr std::size_t kVlrItemSize = 6;    ///< type, size, version: three uint16
constexpr std::size_t kChunkTablePointerSize = 8;
constexpr std::size_t kChunkTableHeaderSize = 8;  ///< uint32 version (0) + uint32 chunk count
constexpr std::uint32_t kVariableChunkSize = 0xFFFFFFFFu;
constexpr std::uint16_t kCompressorNone = 0;
constexpr std::uint16_t kCompressorPointwise = 1;
constexpr std::uint16_t kCompressorPointwiseChunked = 2;
constexpr std::uint16_t kCompressorLayeredChunked = 3;

// Item types of the LASzip VLR (types 1-5, typed extra bytes of LASzip 1.0, were never written).
enum ItemType : std::uint16_t {
  kByte = 0,
  kPoint10 = 6,
  kGpsTime11 = 7,
  kRgb12 = 8,
  kWavePacket13 = 9,
  kPoint14 = 10,
  kRgb14 = 11,
  kRgbNir14 = 12,
  kWavePacket14 = 13,
  kByte14 = 14,
};

const char* item_name(std::uint16_t type) {
  switch (type) {
    case kByte:
      return "BYTE";
    case kPoint10:
      return "POINT10";
    case kGpsTime11:
      return "GPSTIME11";
    case kRgb12:
      return "RGB12";
    case kWavePacket13:
      return "WAVEPACKET13";
    case kPoint14:
      return "POINT14";
    case kRgb14:
      return "RGB14";
    case kRgbNir14:
      return "RGBNIR14";
    case kWavePacket14:
      return "WAVEPACKET14";
    case kByte14:
      return "BYTE14";
    default:
      return nullptr;
  }
}

/// Fixed raw size of an item type; 0 for the variable-size byte items.
std::uint16_t fixed_item_size(std::uint16_t type) {
  switch (type) {
    case kPoint10:
      return 20;
    case kGpsTime11:
      return 8;
    case kRgb12:
      return 6;
    case kWavePacket13:
      return 29;
    case kPoint14:
      return 30;
    case kRgb14:
      return 6;
    case kRgbNir14:
      return 8;
    case kWavePacket14:
      return 29;
    default:
      return 0;
  }
}

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw IoError("laz: " + path + ": " + what);
}

}  // namespace

LaszipVlr parse_laszip_vlr(const std::uint8_t* data, std::size_t size, const std::string& path) {
  if (data == nullptr || size < kVlrFixedSize) {
    fail(path, "LASzip VLR has " + std::to_string(size) + " bytes, needs at least " +
                   std::to_string(kVlrFixedSize));
  }
  LaszipVlr vlr;
  vlr.compressor = load<std::uint16_t>(data + 0);
  vlr.coder = load<std::uint16_t>(data + 2);
  vlr.version_major = data[4];
  vlr.version_minor = data[5];
  vlr.version_revision = load<std::uint16_t>(data + 6);
  vlr.options = load<std::uint32_t>(data + 8);
  vlr.chunk_size = load<std::uint32_t>(data + 12);
  vlr.number_of_special_evlrs = load<std::int64_t>(data + 16);
  vlr.offset_to_special_evlrs = load<std::int64_t>(data + 24);
  const std::uint16_t item_count = load<std::uint16_t>(data + 32);
  const std::size_t expected = kVlrFixedSize + kVlrItemSize * item_count;
  if (size != expected) {
    fail(path, "LASzip VLR has " + std::to_string(size) + " bytes but " + std::to_string(item_count) +
                   " items need " + std::to_string(expected));
  }
  if (vlr.compressor > kCompressorLayeredChunked) {
    fail(path, "unknown compressor " + std::to_string(vlr.compressor) + " in LASzip VLR");
  }
  if (vlr.coder != 0)
    fail(path, "unknown coder " + std::to_string(vlr.coder) + " in LASzip VLR (only 0, arithmetic)");
  if (item_count == 0) fail(path, "LASzip VLR lists no items");
  for (std::uint16_t i = 0; i < item_count; ++i) {
    const std::uint8_t* p = data + kVlrFixedSize + kVlrItemSize * i;
    LaszipVlr::Item item{load<std::uint16_t>(p), load<std::uint16_t>(p + 2), load<std::uint16_t>(p + 4)};
    const char* name = item_name(item.type);
    if (name == nullptr) {
      fail(path, "unknown item type " + std::to_string(item.type) + " version " +
                     std::to_string(item.version) + " in LASzip VLR");
    }
    const std::uint16_t fixed = fixed_item_size(item.type);
    if ((fixed != 0 && item.size != fixed) || item.size == 0) {
      fail(path, std::string("item ") + name + " has size " + std::to_string(item.size) +
                     " in LASzip VLR, expected " + std::to_string(fixed));
    }
    vlr.items.push_back(item);
  }
  return vlr;
}

bool has_compression_bit(std::uint8_t point_format_byte) { return (point_format_byte & 0xC0) != 0; }

void check_laszip_vlr_present(bool vlr_found, std::uint8_t point_format_byte, const std::string& path) {
  if (has_compression_bit(point_format_byte) && !vlr_found) {
    fail(path, "point format byte " + std::to_string(point_format_byte) +
                   " has the compression bit set but there is no LASzip VLR (user id \"laszip encoded\", "
                   "record 22204)");
  }
}

namespace {

enum class ItemKind {
  kPoint10V1,
  kGpsTimeV1,
  kRgb12V1,
  kByteV1,
  kPoint10,
  kGpsTime,
  kRgb12,
  kByte,
  kPoint14,
  kRgb14,
  kRgbNir14,
  kByte14
};

struct ItemSlot {
  ItemKind kind;
  std::size_t offset;  ///< byte offset inside the record
  std::size_t size;
  std::size_t first_layer = 0;  ///< v3: index of the item's first layer
};

struct Chunk {
  std::uint64_t offset = 0;  ///< file offset of the chunk's first byte
  std::uint64_t bytes = 0;
  std::uint64_t points = 0;
};

/// Reads from a file with every length checked against the file size. pread() keeps no file
/// position, so one File serves any number of threads at once.
class File {
 public:
  File(const std::string& path, std::uint64_t size) : path_(path), size_(size) {
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) fail(path, std::string("cannot open: ") + std::strerror(errno));
  }
  ~File() {
    if (fd_ >= 0) ::close(fd_);
  }
  File(const File&) = delete;
  File& operator=(const File&) = delete;

  std::uint64_t size() const { return size_; }

  /// Reads `n` bytes at `offset`; `what` names the structure in the error message.
  void read(std::uint64_t offset, std::uint8_t* out, std::size_t n, const std::string& what) const {
    if (offset > size_ || n > size_ - offset) {
      fail(path_, "truncated file: " + what + " at byte " + std::to_string(offset) + " (" +
                      std::to_string(n) + " bytes) runs past the end of the file (" + std::to_string(size_) +
                      " bytes)");
    }
    std::size_t done = 0;
    while (done < n) {
      const ssize_t got = ::pread(fd_, out + done, n - done, static_cast<off_t>(offset + done));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) fail(path_, "cannot read " + what + " at byte " + std::to_string(offset + done));
      done += static_cast<std::size_t>(got);
    }
  }

 private:
  std::string path_;
  std::uint64_t size_;
  int fd_ = -1;
};

/// Everything that decoding one chunk mutates: its compressed bytes and the item decoders reading
/// them. The streaming decode() keeps one for the whole file; each decode_chunk() call makes its
/// own, which is what lets chunks be decoded on several threads at once. Not movable: the v1/v2
/// item decoders hold a reference to `dec`.
struct ChunkState {
  ChunkState(const std::vector<ItemSlot>& items, std::size_t layer_count) : layers(layer_count) {
    for (const ItemSlot& it : items) {
      switch (it.kind) {
        case ItemKind::kPoint10V1:
          point10_v1 = std::make_unique<laz::Point10DecoderV1>(dec);
          break;
        case ItemKind::kGpsTimeV1:
          gps_time_v1 = std::make_unique<laz::GpsTimeDecoderV1>(dec);
          break;
        case ItemKind::kRgb12V1:
          rgb12_v1 = std::make_unique<laz::RgbDecoderV1>(dec);
          break;
        case ItemKind::kByteV1:
          byte_v1 = std::make_unique<laz::ByteDecoderV1>(dec, it.size);
          break;
        case ItemKind::kPoint10:
          point10 = std::make_unique<laz::Point10DecoderV2>(dec);
          break;
        case ItemKind::kGpsTime:
          gps_time = std::make_unique<laz::GpsTimeDecoderV2>(dec);
          break;
        case ItemKind::kRgb12:
          rgb12 = std::make_unique<laz::RgbDecoderV2>(dec);
          break;
        case ItemKind::kByte:
          byte = std::make_unique<laz::ByteDecoderV2>(dec, it.size);
          break;
        case ItemKind::kPoint14:
          point14 = std::make_unique<laz::Point14DecoderV3>();
          break;
        case ItemKind::kRgb14:
        case ItemKind::kRgbNir14:
          rgb14 = std::make_unique<laz::RgbNirDecoderV3>(it.kind == ItemKind::kRgbNir14);
          break;
        case ItemKind::kByte14:
          byte14 = std::make_unique<laz::ByteDecoderV3>(it.size);
          break;
      }
    }
  }
  ChunkState(const ChunkState&) = delete;
  ChunkState& operator=(const ChunkState&) = delete;

  std::vector<std::uint8_t> bytes;
  std::uint64_t points_left = 0;
  bool first_point = false;

  // v1 and v2: one decoder for all items
  laz::ArithmeticDecoder dec;
  std::unique_ptr<laz::Point10DecoderV1> point10_v1;
  std::unique_ptr<laz::GpsTimeDecoderV1> gps_time_v1;
  std::unique_ptr<laz::RgbDecoderV1> rgb12_v1;
  std::unique_ptr<laz::ByteDecoderV1> byte_v1;
  std::unique_ptr<laz::Point10DecoderV2> point10;
  std::unique_ptr<laz::GpsTimeDecoderV2> gps_time;
  std::unique_ptr<laz::RgbDecoderV2> rgb12;
  std::unique_ptr<laz::ByteDecoderV2> byte;

  // v3: one decoder per layer
  std::vector<laz::Layer> layers;
  std::unique_ptr<laz::Point14DecoderV3> point14;
  std::unique_ptr<laz::RgbNirDecoderV3> rgb14;
  std::unique_ptr<laz::ByteDecoderV3> byte14;
};

}  // namespace

/// The file's layout (items, chunk table) is fixed after construction and shared by every decode;
/// only the streaming members below `stream_` change.
struct LazDecoder::Impl {
  Impl(const LaszipVlr& vlr_in, const LazLayout& layout_in);

  std::size_t decode(std::uint8_t* out, std::size_t max_points);
  void decode_chunk(std::size_t index, std::uint8_t* out) const;

  void check_items();
  void read_chunk_table();
  void load_chunk(ChunkState& state, std::size_t index) const;
  void finish_chunk(const ChunkState& state) const;
  void decode_points(ChunkState& state, std::uint8_t* out, std::size_t n) const;
  void decode_points_v2(ChunkState& state, std::uint8_t* out, std::size_t n) const;
  void decode_points_v3(ChunkState& state, std::uint8_t* out, std::size_t n) const;
  std::string chunk_label(std::size_t index) const {
    return "chunk " + std::to_string(index) + " of " + std::to_string(chunks_.size());
  }

  LaszipVlr vlr_;
  LazLayout layout_;
  File file_;
  bool layered_ = false;
  bool pointwise_ = false;  ///< compressor 1: one stream from the start of the point data, no chunk table
  std::vector<ItemSlot> items_;
  std::size_t layer_count_ = 0;  ///< v3: layers of all items together
  std::vector<Chunk> chunks_;

  // streaming state: only the current chunk is held
  std::unique_ptr<ChunkState> stream_;
  std::size_t chunk_index_ = 0;  ///< index of the chunk being decoded (== chunks_.size() before the first)
  std::uint64_t points_emitted_ = 0;
  bool failed_ = false;
  std::string failure_;
};

LazDecoder::Impl::Impl(const LaszipVlr& vlr_in, const LazLayout& layout_in)
    : vlr_(vlr_in), layout_(layout_in), file_(layout_in.path, layout_in.file_size) {
  check_items();
  read_chunk_table();
  stream_ = std::make_unique<ChunkState>(items_, layer_count_);
  chunk_index_ = chunks_.size();  // "before the first chunk"
}

void LazDecoder::Impl::check_items() {
  const std::string& path = layout_.path;
  switch (vlr_.compressor) {
    case kCompressorPointwiseChunked:
      layered_ = false;
      break;
    case kCompressorLayeredChunked:
      layered_ = true;
      break;
    case kCompressorPointwise:
      pointwise_ = true;
      break;
    case kCompressorNone:
      fail(path, "LASzip VLR says compressor 0 (none) but the point data is compressed");
    default:
      fail(path, "unknown compressor " + std::to_string(vlr_.compressor) + " in LASzip VLR");
  }
  if (!pointwise_ && vlr_.chunk_size == 0) fail(path, "LASzip VLR chunk size is 0");
  if (layered_ && layout_.point_format < 6) {
    fail(path,
         "layered compressor 3 with point format " + std::to_string(layout_.point_format) + " (needs 6-10)");
  }
  if (!layered_ && layout_.point_format >= 6) {
    fail(path, "point format " + std::to_string(layout_.point_format) +
                   " with compressor 2 (LAS 1.4 compatibility mode) is not supported");
  }
  std::size_t offset = 0;
  std::size_t layer = 0;
  for (std::size_t i = 0; i < vlr_.items.size(); ++i) {
    const auto& item = vlr_.items[i];
    const char* name = item_name(item.type);
    if (name == nullptr) {
      fail(path, "unknown item type " + std::to_string(item.type) + " version " +
                     std::to_string(item.version) + " in LASzip VLR");
    }
    const std::string label = std::string(name) + " (type " + std::to_string(item.type) + ") version " +
                              std::to_string(item.version);
    const bool legacy_type =
        item.type == kPoint10 || item.type == kGpsTime11 || item.type == kRgb12 || item.type == kByte;
    const bool v14_type =
        item.type == kPoint14 || item.type == kRgb14 || item.type == kRgbNir14 || item.type == kByte14;
    const bool supported = layered_ ? (v14_type && item.version == 3)
                                    : (legacy_type && (item.version == 1 || item.version == 2));
    if (!supported) {
      fail(path, "unsupported item " + label + " with compressor " + std::to_string(vlr_.compressor) +
                     " (supported: v1/v2 POINT10/GPSTIME11/RGB12/BYTE, v3 POINT14/RGB14/RGBNIR14/BYTE14)");
    }
    const bool v1 = item.version == 1;
    ItemSlot slot{};
    slot.offset = offset;
    slot.size = item.size;
    slot.first_layer = layer;
    switch (item.type) {
      case kPoint10:
        slot.kind = v1 ? ItemKind::kPoint10V1 : ItemKind::kPoint10;
        break;
      case kGpsTime11:
        slot.kind = v1 ? ItemKind::kGpsTimeV1 : ItemKind::kGpsTime;
        break;
      case kRgb12:
        slot.kind = v1 ? ItemKind::kRgb12V1 : ItemKind::kRgb12;
        break;
      case kByte:
        slot.kind = v1 ? ItemKind::kByteV1 : ItemKind::kByte;
        break;
      case kPoint14:
        if (i != 0)
          fail(path, "POINT14 must be the first item in the LASzip VLR (it selects the scanner channel)");
        slot.kind = ItemKind::kPoint14;
        layer += laz::Point14DecoderV3::layer_count();
        break;
      case kRgb14:
      case kRgbNir14:
        slot.kind = item.type == kRgb14 ? ItemKind::kRgb14 : ItemKind::kRgbNir14;
        layer += laz::RgbNirDecoderV3(item.type == kRgbNir14).layer_count();
        break;
      case kByte14:
        slot.kind = ItemKind::kByte14;
        layer += laz::ByteDecoderV3(item.size).layer_count();
        break;
      default:
        break;
    }
    // one decoder per item type, whatever its version; RGB14 and RGBNIR14 share one
    auto decoder_of = [](std::uint16_t type) -> std::uint16_t {
      return type == kRgbNir14 ? std::uint16_t{kRgb14} : type;
    };
    const bool duplicate = std::any_of(
        vlr_.items.begin(), vlr_.items.begin() + static_cast<std::ptrdiff_t>(i),
        [&](const LaszipVlr::Item& seen) { return decoder_of(seen.type) == decoder_of(item.type); });
    if (duplicate) fail(path, "item " + label + " appears twice in the LASzip VLR");
    items_.push_back(slot);
    offset += item.size;
  }
  if (!layered_ && std::none_of(items_.begin(), items_.end(), [](const ItemSlot& s) {
        return s.kind == ItemKind::kPoint10 || s.kind == ItemKind::kPoint10V1;
      }))
    fail(path, "LASzip VLR has no POINT10 item");
  if (layered_ && (items_.empty() || items_[0].kind != ItemKind::kPoint14))
    fail(path, "LASzip VLR has no POINT14 item");
  // the non-byte items must be exactly the fields of the point format; extra bytes come on top
  static constexpr std::size_t kPointFormatSize[] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
  std::size_t fixed_fields = 0;
  for (const auto& item : vlr_.items)
    fixed_fields += (item.type == kByte || item.type == kByte14) ? 0 : item.size;
  if (layout_.point_format > 10 || fixed_fields != kPointFormatSize[layout_.point_format]) {
    fail(path,
         "LASzip VLR items describe " + std::to_string(fixed_fields) + "-byte points but point format " +
             std::to_string(layout_.point_format) + " has " +
             (layout_.point_format > 10 ? std::string("no known size")
                                        : std::to_string(kPointFormatSize[layout_.point_format]) + " bytes"));
  }
  if (offset != layout_.record_length) {
    fail(path, "LASzip VLR item sizes sum to " + std::to_string(offset) + " bytes but the record length is " +
                   std::to_string(layout_.record_length));
  }
  layer_count_ = layer;
}

void LazDecoder::Impl::read_chunk_table() {
  const std::string& path = layout_.path;
  if (pointwise_) {
    // compressor 1 has no chunk table pointer: one stream from the point data to the end of the file
    if (layout_.point_data_offset > file_.size()) fail(path, "point data starts past the end of the file");
    if (layout_.point_count > 0) {
      chunks_.push_back(
          Chunk{layout_.point_data_offset, file_.size() - layout_.point_data_offset, layout_.point_count});
    }
    return;
  }
  const std::uint64_t data_start = layout_.point_data_offset + kChunkTablePointerSize;
  std::uint8_t word[8];
  file_.read(layout_.point_data_offset, word, sizeof word, "chunk table pointer");
  std::int64_t pointer = load<std::int64_t>(word);
  if (pointer == -1) {
    // the writer could not seek back (streamed output): the real offset is in the file's last 8 bytes
    if (file_.size() < data_start + 8)
      fail(path, "chunk table pointer is -1 and the file has no room for the offset at its end");
    file_.read(file_.size() - 8, word, sizeof word, "chunk table offset at the end of the file");
    pointer = load<std::int64_t>(word);
  }
  if (pointer == static_cast<std::int64_t>(layout_.point_data_offset)) {
    fail(path, "chunk table missing: its pointer points at itself (byte " + std::to_string(pointer) +
                   "), the writer was interrupted");
  }
  if (pointer < static_cast<std::int64_t>(data_start) ||
      static_cast<std::uint64_t>(pointer) + kChunkTableHeaderSize > file_.size()) {
    fail(path, "bad chunk table: pointer " + std::to_string(pointer) +
                   " is out of range (point data starts at byte " + std::to_string(data_start) +
                   ", file has " + std::to_string(file_.size()) + " bytes)");
  }
  const auto table_offset = static_cast<std::uint64_t>(pointer);
  std::uint8_t header[kChunkTableHeaderSize];
  file_.read(table_offset, header, sizeof header, "chunk table header");
  const std::uint32_t version = load<std::uint32_t>(header);
  const std::uint32_t count = load<std::uint32_t>(header + 4);
  if (version != 0) fail(path, "bad chunk table: unknown version " + std::to_string(version));
  const std::uint64_t data_bytes = table_offset - data_start;
  if (count > layout_.point_count || count > data_bytes) {
    fail(path, "bad chunk table: " + std::to_string(count) + " chunks for " +
                   std::to_string(layout_.point_count) + " points in " + std::to_string(data_bytes) +
                   " bytes");
  }
  const bool variable = vlr_.chunk_size == kVariableChunkSize;
  if (!variable) {
    const std::uint64_t needed = (layout_.point_count + vlr_.chunk_size - 1) / vlr_.chunk_size;
    if (count != needed) {
      fail(path, "bad chunk table: it lists " + std::to_string(count) + " chunks but " +
                     std::to_string(layout_.point_count) + " points in chunks of " +
                     std::to_string(vlr_.chunk_size) + " need " + std::to_string(needed));
    }
  }
  chunks_.resize(count);
  if (count == 0) return;

  // the entries are compressed: point counts (variable chunks only) and byte sizes, each predicted
  // from the previous chunk's value
  const std::uint64_t entries_offset = table_offset + kChunkTableHeaderSize;
  // at most a few bytes per coded value; don't read EVLRs or trailing data beyond that
  constexpr std::uint64_t kMaxBytesPerChunkEntry = 32;
  std::vector<std::uint8_t> entries(
      std::min<std::uint64_t>(file_.size() - entries_offset, 64 + kMaxBytesPerChunkEntry * count));
  file_.read(entries_offset, entries.data(), entries.size(), "chunk table entries");
  try {
    laz::ArithmeticDecoder dec;
    dec.set_label("chunk table");
    dec.start(entries.data(), entries.data() + entries.size());
    laz::IntegerDecompressor ic(32, 2);
    ic.set_decoder(&dec);
    std::uint32_t last_points = 0, last_bytes = 0;
    for (std::uint32_t i = 0; i < count; ++i) {
      if (variable) {
        last_points = static_cast<std::uint32_t>(ic.decompress(static_cast<std::int32_t>(last_points), 0));
        chunks_[i].points = last_points;
      }
      last_bytes = static_cast<std::uint32_t>(ic.decompress(static_cast<std::int32_t>(last_bytes), 1));
      chunks_[i].bytes = last_bytes;
    }
  } catch (const laz::CorruptData& e) {
    fail(path, std::string("bad chunk table: ") + e.what());
  }
  std::uint64_t offset = data_start;
  std::uint64_t points = 0;
  for (std::uint32_t i = 0; i < count; ++i) {
    Chunk& chunk = chunks_[i];
    chunk.offset = offset;
    if (chunk.bytes > table_offset - offset) {
      fail(path, "bad chunk table: chunk " + std::to_string(i) + " (" + std::to_string(chunk.bytes) +
                     " bytes at byte " + std::to_string(offset) + ") runs past the chunk table at byte " +
                     std::to_string(table_offset));
    }
    offset += chunk.bytes;
    if (!variable) chunk.points = std::min<std::uint64_t>(vlr_.chunk_size, layout_.point_count - points);
    if (chunk.points == 0) fail(path, "bad chunk table: chunk " + std::to_string(i) + " has no points");
    points += chunk.points;
  }
  if (points != layout_.point_count) {
    fail(path, "bad chunk table: its chunks hold " + std::to_string(points) + " points but the header says " +
                   std::to_string(layout_.point_count));
  }
}

void LazDecoder::Impl::load_chunk(ChunkState& state, std::size_t index) const {
  const Chunk& chunk = chunks_[index];
  std::vector<std::uint8_t>& bytes = state.bytes;
  bytes.resize(chunk.bytes);
  file_.read(chunk.offset, bytes.data(), bytes.size(), "data of " + chunk_label(index));
  const std::size_t record = layout_.record_length;
  if (bytes.size() < record) {
    laz::throw_corrupt("chunk is shorter than its uncompressed first point");
  }
  if (layered_) {
    // first point raw, uint32 point count, one uint32 size per layer, then the layers
    std::vector<laz::Layer>& layers = state.layers;
    const std::size_t header = record + 4 + 4 * layers.size();
    if (bytes.size() < header) laz::throw_corrupt("chunk is shorter than its layer table");
    const std::uint32_t count = load<std::uint32_t>(bytes.data() + record);
    if (count != chunk.points) {
      laz::throw_corrupt(("chunk header says " + std::to_string(count) + " points, the chunk table says " +
                          std::to_string(chunk.points))
                             .c_str());
    }
    std::uint64_t at = header;
    for (std::size_t i = 0; i < layers.size(); ++i) {
      layers[i].size = load<std::uint32_t>(bytes.data() + record + 4 + 4 * i);
      if (layers[i].size > bytes.size() - at) {
        laz::throw_corrupt(("layer " + std::to_string(i) + " (" + std::to_string(layers[i].size) +
                            " bytes) runs past the end of the chunk")
                               .c_str());
      }
      layers[i].data = bytes.data() + at;
      at += layers[i].size;
    }
  }
  state.points_left = chunk.points;
  state.first_point = true;
}

void LazDecoder::Impl::finish_chunk(const ChunkState& state) const {
  // a well-formed stream ends exactly where its bytes end; anything else means corrupt data
  if (pointwise_) return;  // the stream's end is unknown (EVLRs may follow it)
  if (!layered_) {
    if (state.dec.consumed() != state.dec.size()) {
      laz::throw_corrupt(("decoder stopped at byte " + std::to_string(state.dec.consumed()) + " of " +
                          std::to_string(state.dec.size()) + " (corrupt data)")
                             .c_str());
    }
    return;
  }
  for (const laz::Layer& l : state.layers) {
    if (l.size != 0 && l.dec.consumed() != l.size) {
      laz::throw_corrupt((std::string(l.dec.label()) + " decoder stopped at byte " +
                          std::to_string(l.dec.consumed()) + " of " + std::to_string(l.size) +
                          " (corrupt data)")
                             .c_str());
    }
  }
}

void LazDecoder::Impl::decode_points(ChunkState& state, std::uint8_t* out, std::size_t n) const {
  assert(n <= state.points_left);
  if (layered_)
    decode_points_v3(state, out, n);
  else
    decode_points_v2(state, out, n);
  state.points_left -= n;
}

void LazDecoder::Impl::decode_points_v2(ChunkState& s, std::uint8_t* out, std::size_t n) const {
  const std::size_t record = layout_.record_length;
  for (std::size_t p = 0; p < n; ++p, out += record) {
    if (s.first_point) {
      std::memcpy(out, s.bytes.data(), record);
      for (const ItemSlot& it : items_) {
        const std::uint8_t* raw = out + it.offset;
        switch (it.kind) {
          case ItemKind::kPoint10:
            s.point10->init(raw);
            break;
          case ItemKind::kGpsTime:
            s.gps_time->init(raw);
            break;
          case ItemKind::kRgb12:
            s.rgb12->init(raw);
            break;
          case ItemKind::kByte:
            s.byte->init(raw);
            break;
          case ItemKind::kPoint10V1:
            s.point10_v1->init(raw);
            break;
          case ItemKind::kGpsTimeV1:
            s.gps_time_v1->init(raw);
            break;
          case ItemKind::kRgb12V1:
            s.rgb12_v1->init(raw);
            break;
          case ItemKind::kByteV1:
            s.byte_v1->init(raw);
            break;
          default:
            break;
        }
      }
      s.dec.start(s.bytes.data() + record, s.bytes.data() + s.bytes.size());
      s.first_point = false;
      continue;
    }
    for (const ItemSlot& it : items_) {
      std::uint8_t* field = out + it.offset;
      switch (it.kind) {
        case ItemKind::kPoint10:
          s.point10->decode(field);
          break;
        case ItemKind::kGpsTime:
          s.gps_time->decode(field);
          break;
        case ItemKind::kRgb12:
          s.rgb12->decode(field);
          break;
        case ItemKind::kByte:
          s.byte->decode(field);
          break;
        case ItemKind::kPoint10V1:
          s.point10_v1->decode(field);
          break;
        case ItemKind::kGpsTimeV1:
          s.gps_time_v1->decode(field);
          break;
        case ItemKind::kRgb12V1:
          s.rgb12_v1->decode(field);
          break;
        case ItemKind::kByteV1:
          s.byte_v1->decode(field);
          break;
        default:
          break;
      }
    }
  }
}

void LazDecoder::Impl::decode_points_v3(ChunkState& s, std::uint8_t* out, std::size_t n) const {
  const std::size_t record = layout_.record_length;
  for (std::size_t p = 0; p < n; ++p, out += record) {
    if (s.first_point) {
      std::memcpy(out, s.bytes.data(), record);
      std::uint32_t context = 0;
      for (const ItemSlot& it : items_) {
        const std::uint8_t* raw = out + it.offset;
        laz::Layer* layers = s.layers.data() + it.first_layer;
        switch (it.kind) {
          case ItemKind::kPoint14:
            context = s.point14->init(raw, layers);
            break;
          case ItemKind::kRgb14:
          case ItemKind::kRgbNir14:
            s.rgb14->init(raw, layers, context);
            break;
          case ItemKind::kByte14:
            s.byte14->init(raw, layers, context);
            break;
          default:
            break;
        }
      }
      s.first_point = false;
      continue;
    }
    const std::uint32_t context = s.point14->decode(out);
    for (std::size_t i = 1; i < items_.size(); ++i) {
      const ItemSlot& it = items_[i];
      if (it.kind == ItemKind::kByte14)
        s.byte14->decode(out + it.offset, context);
      else
        s.rgb14->decode(out + it.offset, context);
    }
  }
}

std::size_t LazDecoder::Impl::decode(std::uint8_t* out, std::size_t max_points) {
  if (failed_) throw IoError(failure_);
  std::size_t produced = 0;
  ChunkState& state = *stream_;
  try {
    while (produced < max_points && points_emitted_ < layout_.point_count) {
      if (state.points_left == 0) {
        chunk_index_ = chunk_index_ == chunks_.size() ? 0 : chunk_index_ + 1;
        if (chunk_index_ >= chunks_.size())
          fail(layout_.path, "no chunk left for point " + std::to_string(points_emitted_));
        load_chunk(state, chunk_index_);
      }
      const auto n =
          static_cast<std::size_t>(std::min<std::uint64_t>(max_points - produced, state.points_left));
      decode_points(state, out + produced * layout_.record_length, n);
      produced += n;
      points_emitted_ += n;
      if (state.points_left == 0) finish_chunk(state);
    }
  } catch (const laz::CorruptData& e) {
    failed_ = true;
    failure_ = "laz: " + layout_.path + ": " + chunk_label(chunk_index_) + ": " + e.what();
    throw IoError(failure_);
  } catch (const IoError& e) {
    failed_ = true;
    failure_ = e.what();
    throw;
  }
  return produced;
}

void LazDecoder::Impl::decode_chunk(std::size_t index, std::uint8_t* out) const {
  assert(index < chunks_.size());
  ChunkState state(items_, layer_count_);  // private to this call: no state shared with other threads
  try {
    load_chunk(state, index);
    decode_points(state, out, static_cast<std::size_t>(chunks_[index].points));
    finish_chunk(state);
  } catch (const laz::CorruptData& e) {
    throw IoError("laz: " + layout_.path + ": " + chunk_label(index) + ": " + e.what());
  }
}

LazDecoder::LazDecoder(const LaszipVlr& vlr, const LazLayout& layout)
    : impl_(std::make_unique<Impl>(vlr, layout)) {}

LazDecoder::~LazDecoder() = default;

std::size_t LazDecoder::decode(std::uint8_t* out, std::size_t max_points) {
  return impl_->decode(out, max_points);
}

std::size_t LazDecoder::chunk_count() const { return impl_->chunks_.size(); }

std::uint64_t LazDecoder::chunk_points(std::size_t index) const {
  assert(index < impl_->chunks_.size());
  return impl_->chunks_[index].points;
}

void LazDecoder::decode_chunk(std::size_t index, std::uint8_t* out) const { impl_->decode_chunk(index, out); }

}  // namespace city3d::detail
