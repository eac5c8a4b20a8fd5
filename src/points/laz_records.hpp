// Where the LAS reader's raw point records come from when the file is LAZ: the LASzip decoder streaming
// through the file, or chunk by chunk (some chunks only, on several threads). Private to src/points/.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "laz/laz_decoder.hpp"

namespace city3d::detail {

/// Where raw point records come from: the reader converts whatever a source hands it.
class RecordSource {
 public:
  virtual ~RecordSource() = default;
  /// Writes at most `max_records` raw records to `out`; returns how many, 0 at the end.
  virtual std::size_t read_records(std::uint8_t* out, std::size_t max_records) = 0;
};

/// LAZ: the LASzip decoder hands out the same raw records, chunk by chunk.
class LazRecordSource final : public RecordSource {
 public:
  explicit LazRecordSource(std::unique_ptr<LazDecoder> decoder) : decoder_(std::move(decoder)) {}
  std::size_t read_records(std::uint8_t* out, std::size_t max_records) override {
    return decoder_->decode(out, max_records);
  }
  const LazDecoder& decoder() const { return *decoder_; }

 private:
  std::unique_ptr<LazDecoder> decoder_;
};

/// Decoded chunks larger than this are never held whole: such a file is decoded by the streaming path
/// even when threads are asked for (the parallel path holds at least `threads` whole chunks), and read
/// whole rather than chunk by chunk (a file may have one chunk of 100M points).
constexpr std::uint64_t kMaxHeldChunkBytes = 256u << 20;

/// The records of chunks `wanted` (indices into the decoder's chunks, in file order), decoded on
/// `decode_threads` threads (0 and 1: in the calling thread). Every chunk in one thread streams
/// through the file (LazRecordSource), and so do chunks over kMaxHeldChunkBytes; a part of the chunks
/// in one thread is decoded chunk by chunk. `wanted` must be every chunk when one is over that size.
std::unique_ptr<RecordSource> make_laz_record_source(std::unique_ptr<LazDecoder> decoder,
                                                     std::vector<std::size_t> wanted,
                                                     std::size_t record_length, unsigned decode_threads);

}  // namespace city3d::detail
