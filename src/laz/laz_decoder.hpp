// LASzip decoding (private to the LAS reader): turns the compressed point block of a LAZ file back
// into raw LAS point records, chunk by chunk.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace city3d::detail {

/// The content of the LASzip VLR (user id "laszip encoded", record id 22204).
struct LaszipVlr {
  struct Item {
    std::uint16_t type =
        0;  ///< 6 POINT10, 7 GPSTIME11, 8 RGB12, 0 BYTE, 10 POINT14, 11 RGB14, 12 RGBNIR14, 14 BYTE14
    std::uint16_t size = 0;  ///< bytes of the item in a raw record
    std::uint16_t version = 0;
  };
  std::uint16_t compressor = 0;  ///< 0 none, 1 pointwise, 2 pointwise-chunked, 3 layered-chunked
  std::uint16_t coder = 0;       ///< 0 arithmetic
  std::uint8_t version_major = 0;
  std::uint8_t version_minor = 0;
  std::uint16_t version_revision = 0;
  std::uint32_t options = 0;
  std::uint32_t chunk_size = 0;  ///< points per chunk; 0xFFFFFFFF = variable (sizes in the chunk table)
  std::int64_t number_of_special_evlrs = -1;
  std::int64_t offset_to_special_evlrs = -1;
  std::vector<Item> items;
};

/// Parses the LASzip VLR payload. Throws IoError naming `path` when it is malformed.
LaszipVlr parse_laszip_vlr(const std::uint8_t* data, std::size_t size, const std::string& path);

/// True when a LAS header point-format byte carries the compression bit (bit 7, or bit 6 in
/// files from early LASzip versions).
bool has_compression_bit(std::uint8_t point_format_byte);

/// Throws IoError naming `path` when the point-format byte says "compressed" but the file has no
/// LASzip VLR (user id "laszip encoded", record id 22204).
void check_laszip_vlr_present(bool vlr_found, std::uint8_t point_format_byte, const std::string& path);

/// Where the compressed point block is and what it must decode to (taken from the LAS header).
struct LazLayout {
  std::string path;
  std::uint64_t point_data_offset = 0;  ///< header "offset to point data"
  std::uint64_t point_count = 0;        ///< legacy or 64-bit count
  std::uint16_t record_length = 0;      ///< raw record length (point format size + extra bytes)
  std::uint8_t point_format = 0;        ///< without the compression bits
  std::uint64_t file_size = 0;
};

/// Streams raw point records out of a LAZ file, one chunk in memory at a time. Reads compressor 2
/// (pointwise-chunked; v1/v2 POINT10, GPSTIME11, RGB12, BYTE), compressor 3 (layered-chunked; v3
/// POINT14, RGB14, RGBNIR14, BYTE14) and compressor 1 (one unchunked stream; v1/v2 items); fixed and
/// variable chunk sizes; a chunk-table pointer of -1 (offset stored in the file's last 8 bytes).
/// The constructor reads the chunk table and throws IoError naming the file when it or the item list
/// is unusable (missing or out-of-range table, item sizes that do not match the record length,
/// unsupported items). decode() throws IoError naming the file and the chunk when data is truncated
/// or corrupt (a stream that runs past its chunk or layer, or does not end exactly there); after
/// an error every further decode() call throws the same error.
///
/// Chunks are independent, so they can also be decoded one by one, in any order and on any number
/// of threads at once, with decode_chunk(): it is const and keeps all its state (bytes read with
/// pread(), item decoders) to itself. Compressor 1 counts as one chunk. decode() and decode_chunk()
/// may be used on the same decoder, but decode() itself is for one thread.
class LazDecoder {
 public:
  LazDecoder(const LaszipVlr& vlr, const LazLayout& layout);
  ~LazDecoder();
  LazDecoder(const LazDecoder&) = delete;
  LazDecoder& operator=(const LazDecoder&) = delete;

  /// Writes at most `max_points` raw records (record_length bytes each) to `out`; returns how many
  /// it wrote, 0 once all point_count records have been produced. Records of a call that fails
  /// are not reported as written.
  std::size_t decode(std::uint8_t* out, std::size_t max_points);

  /// Number of chunks (0 for a file without points; 1 for compressor 1).
  std::size_t chunk_count() const;

  /// Points in chunk `index` (< chunk_count()); they sum to the header's point count.
  std::uint64_t chunk_points(std::size_t index) const;

  /// Decodes chunk `index` (< chunk_count()) into `out`, which must hold chunk_points(index) records
  /// (record_length bytes each). Thread-safe. Throws IoError naming the file and the chunk
  /// ("chunk 3 of 13") when the chunk is truncated or corrupt; `out` is then partly written.
  void decode_chunk(std::size_t index, std::uint8_t* out) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace city3d::detail
