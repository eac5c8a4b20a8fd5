// The LAZ record sources of the LAS reader: chunks decoded ahead on worker threads, or chunk by
// chunk in the calling thread, the records always handed out in file order.
#include "points/laz_records.hpp"

#include <algorithm>
#include <condition_variable>
#include <cstring>
#include <exception>
#include <mutex>
#include <thread>

namespace city3d::detail {
namespace {

/// LAZ on several threads: workers decode the chunks after the one being handed out, and the
/// records still leave in file order, so the output is the same bytes as with one thread. Chunk c
/// goes to slot c % slots; a slot is refilled only after all its records have been handed out, so
/// at most `slots` decoded chunks are held. More slots than workers let the workers run ahead
/// while the reader's caller converts and crops the records it was handed (with one slot per
/// worker they could only decode the next chunk each, and waited for the rest of the caller's
/// work). An error in a chunk is kept in its slot and thrown
/// when that chunk's records are due (the records before it are handed out first). The destructor
/// stops the workers and joins them; a worker in the middle of a chunk finishes that chunk first.
class ParallelLazRecordSource final : public RecordSource {
 public:
  /// Decodes `chunks` (indices into the file's chunks, in file order).
  ParallelLazRecordSource(std::unique_ptr<LazDecoder> decoder, std::vector<std::size_t> chunks,
                          std::size_t record_length, unsigned threads, std::size_t slots)
      : decoder_(std::move(decoder)),
        chunks_(std::move(chunks)),
        record_length_(record_length),
        chunk_count_(chunks_.size()),
        slots_(std::max<std::size_t>(slots, threads)) {
    try {
      for (unsigned i = 0; i < threads; ++i) workers_.emplace_back([this] { work(); });
    } catch (...) {  // a thread could not be started: stop the ones that were
      stop();
      throw;
    }
  }
  ~ParallelLazRecordSource() override { stop(); }
  ParallelLazRecordSource(const ParallelLazRecordSource&) = delete;
  ParallelLazRecordSource& operator=(const ParallelLazRecordSource&) = delete;

  std::size_t read_records(std::uint8_t* out, std::size_t max_records) override {
    if (error_) std::rethrow_exception(error_);  // every call after an error throws it again
    std::size_t produced = 0;
    while (produced < max_records && next_chunk_ < chunk_count_) {
      Slot& slot = slots_[next_chunk_ % slots_.size()];
      {
        std::unique_lock<std::mutex> lock(mutex_);
        decoded_.wait(lock, [&] { return slot.state == Slot::kDecoded; });
      }
      if (slot.error) {
        if (produced > 0) return produced;  // the records before the broken chunk first
        error_ = slot.error;
        std::rethrow_exception(error_);
      }
      const std::uint64_t chunk_points = decoder_->chunk_points(chunks_[next_chunk_]);
      const auto n = static_cast<std::size_t>(
          std::min<std::uint64_t>(max_records - produced, chunk_points - handed_out_));
      std::memcpy(out + produced * record_length_, slot.records.data() + handed_out_ * record_length_,
                  n * record_length_);
      produced += n;
      handed_out_ += n;
      if (handed_out_ == chunk_points) {
        {
          std::lock_guard<std::mutex> lock(mutex_);
          slot.state = Slot::kFree;
        }
        free_.notify_all();
        ++next_chunk_;
        handed_out_ = 0;
      }
    }
    return produced;
  }

 private:
  /// One decoded chunk. `records` and `error` belong to the worker while kDecoding and to the
  /// reader while kDecoded; `state` changes under the mutex.
  struct Slot {
    enum State { kFree, kDecoding, kDecoded };
    State state = kFree;
    std::vector<std::uint8_t> records;
    std::exception_ptr error;
  };

  /// Worker loop: claim the next chunk in file order as soon as its slot is free, decode it
  /// outside the lock, publish it.
  void work() {
    for (;;) {
      std::size_t chunk = 0;
      Slot* slot = nullptr;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        // chunks are claimed in order and at most slots_.size() are ahead of the reader, so the
        // slot of the next chunk is the one the reader frees next
        free_.wait(lock, [&] {
          return stopping_ || next_to_decode_ == chunk_count_ ||
                 slots_[next_to_decode_ % slots_.size()].state == Slot::kFree;
        });
        if (stopping_ || next_to_decode_ == chunk_count_) return;
        chunk = next_to_decode_++;
        slot = &slots_[chunk % slots_.size()];
        slot->state = Slot::kDecoding;
      }
      slot->error = nullptr;
      try {
        slot->records.resize(static_cast<std::size_t>(decoder_->chunk_points(chunks_[chunk])) *
                             record_length_);
        decoder_->decode_chunk(chunks_[chunk], slot->records.data());
      } catch (...) {
        slot->error = std::current_exception();
      }
      {
        std::lock_guard<std::mutex> lock(mutex_);
        slot->state = Slot::kDecoded;
      }
      decoded_.notify_all();
    }
  }

  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    free_.notify_all();
    for (std::thread& worker : workers_) worker.join();
    workers_.clear();
  }

  std::unique_ptr<LazDecoder> decoder_;  // only its const decode_chunk() is used, from every worker
  std::vector<std::size_t> chunks_;      ///< the file's chunks to decode; "chunk k" below is chunks_[k]
  std::size_t record_length_;
  std::size_t chunk_count_;
  std::vector<Slot> slots_;

  std::mutex mutex_;
  std::condition_variable free_;     ///< a slot became free, or stopping_
  std::condition_variable decoded_;  ///< a slot became kDecoded
  std::size_t next_to_decode_ = 0;   ///< next chunk a worker claims (guarded by mutex_)
  bool stopping_ = false;            ///< guarded by mutex_

  // reader side (the thread calling read_records)
  std::size_t next_chunk_ = 0;    ///< chunk whose records are handed out next
  std::uint64_t handed_out_ = 0;  ///< records of next_chunk_ already handed out
  std::exception_ptr error_;      ///< the error of a broken chunk, once it was due

  std::vector<std::thread> workers_;  // last: started after everything they use exists
};

/// LAZ, some of its chunks only, in the calling thread: each chunk is decoded whole, then handed out.
class ChunkListRecordSource final : public RecordSource {
 public:
  ChunkListRecordSource(std::unique_ptr<LazDecoder> decoder, std::vector<std::size_t> chunks,
                        std::size_t record_length)
      : decoder_(std::move(decoder)), chunks_(std::move(chunks)), record_length_(record_length) {}

  std::size_t read_records(std::uint8_t* out, std::size_t max_records) override {
    std::size_t produced = 0;
    while (produced < max_records && (left_ > 0 || next_ < chunks_.size())) {
      if (left_ == 0) {
        const std::size_t chunk = chunks_[next_++];
        left_ = decoder_->chunk_points(chunk);
        records_.resize(static_cast<std::size_t>(left_) * record_length_);
        decoder_->decode_chunk(chunk, records_.data());
        at_ = 0;
      }
      const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(max_records - produced, left_));
      std::memcpy(out + produced * record_length_, records_.data() + at_ * record_length_,
                  n * record_length_);
      produced += n;
      at_ += n;
      left_ -= n;
    }
    return produced;
  }

 private:
  std::unique_ptr<LazDecoder> decoder_;
  std::vector<std::size_t> chunks_;
  std::size_t record_length_;
  std::size_t next_ = 0;               ///< next entry of chunks_ to decode
  std::vector<std::uint8_t> records_;  ///< the chunk being handed out
  std::size_t at_ = 0;                 ///< its first record not handed out yet
  std::uint64_t left_ = 0;             ///< its records not handed out yet
};

/// Decoded chunks the parallel path may hold ahead of the reader, in bytes, beyond one per thread
/// (AHN3's chunks of 50,000 points are 1.7 MB each: up to eight per thread).
constexpr std::uint64_t kReadAheadBytes = 32u << 20;
constexpr std::size_t kMaxSlotsPerThread = 8;

}  // namespace

std::unique_ptr<RecordSource> make_laz_record_source(std::unique_ptr<LazDecoder> decoder,
                                                     std::vector<std::size_t> wanted,
                                                     std::size_t record_length, unsigned decode_threads) {
  std::uint64_t largest = 0;
  for (std::size_t i : wanted) largest = std::max(largest, decoder->chunk_points(i));
  const auto threads =
      static_cast<unsigned>(std::min<std::size_t>(std::max(decode_threads, 1u), wanted.size()));
  const bool serial = threads <= 1 || largest * record_length > kMaxHeldChunkBytes;
  if (serial && wanted.size() == decoder->chunk_count())
    return std::make_unique<LazRecordSource>(std::move(decoder));
  if (serial)
    return std::make_unique<ChunkListRecordSource>(std::move(decoder), std::move(wanted), record_length);
  const std::uint64_t chunk_bytes = std::max<std::uint64_t>(largest * record_length, 1);
  const auto slots = static_cast<std::size_t>(std::min<std::uint64_t>(
      kMaxSlotsPerThread * threads, std::max<std::uint64_t>(threads, kReadAheadBytes / chunk_bytes)));
  return std::make_unique<ParallelLazRecordSource>(std::move(decoder), std::move(wanted), record_length,
                                                   threads, slots);
}

}  // namespace city3d::detail
