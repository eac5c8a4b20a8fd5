// LASzip entropy decoding: the range decoder, its adaptive symbol and bit models, and the integer
// decompressor that decodes corrections to predicted values. Header-only so the hot path inlines.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace city3d::detail::laz {

/// Thrown when compressed bytes run out or cannot be valid; LazDecoder rethrows it as an IoError
/// that names the file and the chunk.
class CorruptData : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

[[noreturn]] inline __attribute__((noinline, cold)) void throw_corrupt(const char* what) {
  throw CorruptData(what);
}

// Range-coder constants of the LASzip arithmetic coder.
constexpr std::uint32_t kMinLength = 0x01000000u;  ///< renormalise below this interval length
constexpr std::uint32_t kMaxLength = 0xFFFFFFFFu;  ///< interval length after init
constexpr std::uint32_t kBitLengthShift = 13;      ///< bit-model probabilities are 13-bit
constexpr std::uint32_t kBitMaxCount = 1u << kBitLengthShift;
constexpr std::uint32_t kSymbolLengthShift = 15;  ///< symbol-model distributions are 15-bit
constexpr std::uint32_t kSymbolMaxCount = 1u << kSymbolLengthShift;
constexpr std::uint32_t kMaxSymbols = 2048;  ///< largest alphabet the format allows

/// Adaptive model of a binary event (probability of 0 re-estimated every few bits).
class BitModel {
 public:
  BitModel() { reset(); }
  void reset() {
    bit_0_count_ = 1;
    bit_count_ = 2;
    bit_0_prob_ = 1u << (kBitLengthShift - 1);
    update_cycle_ = bits_until_update_ = 4;  // frequent updates at first
  }

 private:
  friend class ArithmeticDecoder;
  void update() {
    bit_count_ += update_cycle_;
    if (bit_count_ > kBitMaxCount) {  // halve the counts so the model keeps adapting
      bit_count_ = (bit_count_ + 1) >> 1;
      bit_0_count_ = (bit_0_count_ + 1) >> 1;
      if (bit_0_count_ == bit_count_) ++bit_count_;
    }
    const std::uint32_t scale = 0x80000000u / bit_count_;
    bit_0_prob_ = (bit_0_count_ * scale) >> (31 - kBitLengthShift);
    update_cycle_ = (5 * update_cycle_) >> 2;
    if (update_cycle_ > 64) update_cycle_ = 64;
    bits_until_update_ = update_cycle_;
  }

  std::uint32_t bit_0_count_, bit_count_, bit_0_prob_, update_cycle_, bits_until_update_;
};

/// Adaptive model of an alphabet of `symbols` symbols. Alphabets above 16 symbols get a lookup
/// table that narrows the binary search of the decoder.
class SymbolModel {
 public:
  explicit SymbolModel(std::uint32_t symbols) : symbols_(symbols) {
    if (symbols < 2 || symbols > kMaxSymbols) throw std::logic_error("laz: bad alphabet size");
    if (symbols > 16) {
      std::uint32_t table_bits = 3;
      while (symbols > (1u << (table_bits + 2))) ++table_bits;
      table_size_ = 1u << table_bits;
      table_shift_ = kSymbolLengthShift - table_bits;
    }
    // distribution, counts, and (table_size + 2) table entries in one block
    storage_.reset(new std::uint32_t[2 * symbols + (table_size_ ? table_size_ + 2 : 0)]);
    distribution_ = storage_.get();
    symbol_count_ = distribution_ + symbols;
    decoder_table_ = table_size_ ? symbol_count_ + symbols : nullptr;
    reset();
  }
  SymbolModel(const SymbolModel&) = delete;
  SymbolModel& operator=(const SymbolModel&) = delete;
  SymbolModel(SymbolModel&&) = default;
  SymbolModel& operator=(SymbolModel&&) = default;

  /// Back to the equiprobable start state (what a new chunk expects).
  void reset() {
    total_count_ = 0;
    update_cycle_ = symbols_;
    for (std::uint32_t k = 0; k < symbols_; ++k) symbol_count_[k] = 1;
    update();
    symbols_until_update_ = update_cycle_ = (symbols_ + 6) >> 1;
  }

 private:
  friend class ArithmeticDecoder;
  void update() {
    total_count_ += update_cycle_;
    if (total_count_ > kSymbolMaxCount) {  // halve the counts so the model keeps adapting
      total_count_ = 0;
      for (std::uint32_t n = 0; n < symbols_; ++n) {
        symbol_count_[n] = (symbol_count_[n] + 1) >> 1;
        total_count_ += symbol_count_[n];
      }
    }
    const std::uint32_t scale = 0x80000000u / total_count_;
    std::uint32_t sum = 0;
    if (table_size_ == 0) {
      for (std::uint32_t k = 0; k < symbols_; ++k) {
        distribution_[k] = (scale * sum) >> (31 - kSymbolLengthShift);
        sum += symbol_count_[k];
      }
    } else {
      std::uint32_t s = 0;
      for (std::uint32_t k = 0; k < symbols_; ++k) {
        distribution_[k] = (scale * sum) >> (31 - kSymbolLengthShift);
        sum += symbol_count_[k];
        const std::uint32_t w = distribution_[k] >> table_shift_;
        while (s < w) decoder_table_[++s] = k - 1;
      }
      decoder_table_[0] = 0;
      while (s <= table_size_) decoder_table_[++s] = symbols_ - 1;
    }
    update_cycle_ = (5 * update_cycle_) >> 2;
    const std::uint32_t max_cycle = (symbols_ + 6) << 3;
    if (update_cycle_ > max_cycle) update_cycle_ = max_cycle;
    symbols_until_update_ = update_cycle_;
  }

  std::unique_ptr<std::uint32_t[]> storage_;
  std::uint32_t* distribution_ = nullptr;
  std::uint32_t* symbol_count_ = nullptr;
  std::uint32_t* decoder_table_ = nullptr;
  std::uint32_t symbols_;
  std::uint32_t table_size_ = 0;
  std::uint32_t table_shift_ = 0;
  std::uint32_t total_count_ = 0;
  std::uint32_t update_cycle_ = 0;
  std::uint32_t symbols_until_update_ = 0;
};

/// Range decoder over one bounded byte buffer (a v2 chunk or one v3 layer). Reading past the end
/// throws CorruptData instead of inventing bytes.
class ArithmeticDecoder {
 public:
  /// Starts decoding [begin, end): the first 4 bytes seed the code value.
  void start(const std::uint8_t* begin, const std::uint8_t* end) {
    begin_ = cur_ = begin;
    end_ = end;
    length_ = kMaxLength;
    value_ = 0;
    for (int i = 0; i < 4; ++i) value_ = (value_ << 8) | next_byte();
  }

  /// Names the stream in error messages ("chunk stream", "Z layer"); must outlive the decoder.
  void set_label(const char* label) { label_ = label; }
  const char* label() const { return label_; }

  /// Bytes read so far; a well-formed stream ends exactly at its end.
  std::size_t consumed() const { return static_cast<std::size_t>(cur_ - begin_); }
  std::size_t size() const { return static_cast<std::size_t>(end_ - begin_); }

  std::uint32_t decode_bit(BitModel& m) {
    const std::uint32_t x = m.bit_0_prob_ * (length_ >> kBitLengthShift);
    std::uint32_t bit;
    if (value_ < x) {
      bit = 0;
      length_ = x;
      ++m.bit_0_count_;
    } else {
      bit = 1;
      value_ -= x;
      length_ -= x;
    }
    if (length_ < kMinLength) renormalise();
    if (--m.bits_until_update_ == 0) m.update();
    return bit;
  }

  std::uint32_t decode_symbol(SymbolModel& m) {
    std::uint32_t sym, x, y = length_;
    if (m.decoder_table_) {
      length_ >>= kSymbolLengthShift;
      const std::uint32_t dv = value_ / length_;
      std::uint32_t t = dv >> m.table_shift_;
      // value < length always holds, so dv can exceed 2^15 only by a little: clamp to the table end
      if (t > m.table_size_) t = m.table_size_;
      sym = m.decoder_table_[t];
      std::uint32_t n = m.decoder_table_[t + 1] + 1;
      while (n > sym + 1) {  // binary search inside the table bucket
        const std::uint32_t k = (sym + n) >> 1;
        if (m.distribution_[k] > dv)
          n = k;
        else
          sym = k;
      }
      x = m.distribution_[sym] * length_;
      if (sym != m.symbols_ - 1) y = m.distribution_[sym + 1] * length_;
    } else {
      x = sym = 0;
      length_ >>= kSymbolLengthShift;
      std::uint32_t n = m.symbols_;
      std::uint32_t k = n >> 1;
      do {  // plain binary search over the cumulative distribution
        const std::uint32_t z = length_ * m.distribution_[k];
        if (z > value_) {
          n = k;
          y = z;
        } else {
          sym = k;
          x = z;
        }
      } while ((k = (sym + n) >> 1) != sym);
    }
    value_ -= x;
    length_ = y - x;
    if (length_ < kMinLength) renormalise();
    ++m.symbol_count_[sym];
    if (--m.symbols_until_update_ == 0) m.update();
    return sym;
  }

  /// `bits` raw (equiprobable) bits, 1..32.
  std::uint32_t read_bits(std::uint32_t bits) {
    if (bits > 19) {  // the interval cannot split into more than 2^19 parts at once
      const std::uint32_t low = read_short();
      const std::uint32_t high = read_bits(bits - 16);
      return (high << 16) | low;
    }
    length_ >>= bits;
    const std::uint32_t sym = value_ / length_;
    value_ -= length_ * sym;
    if (length_ < kMinLength) renormalise();
    return sym;
  }

  std::uint32_t read_short() {
    length_ >>= 16;
    const std::uint32_t sym = value_ / length_;
    value_ -= length_ * sym;
    if (length_ < kMinLength) renormalise();
    return sym & 0xFFFFu;
  }

  std::uint32_t read_int() {
    const std::uint32_t low = read_short();
    const std::uint32_t high = read_short();
    return (high << 16) | low;
  }

 private:
  std::uint8_t next_byte() {
    if (cur_ == end_) throw_overrun();
    return *cur_++;
  }
  [[noreturn]] __attribute__((noinline, cold)) void throw_overrun() const {
    throw CorruptData(std::string("compressed data runs past the end of the ") + label_ + " (" +
                      std::to_string(size()) + " bytes; corrupt or truncated data)");
  }
  void renormalise() {
    do {
      value_ = (value_ << 8) | next_byte();
    } while ((length_ <<= 8) < kMinLength);
  }

  const char* label_ = "chunk stream";
  const std::uint8_t* begin_ = nullptr;
  const std::uint8_t* cur_ = nullptr;
  const std::uint8_t* end_ = nullptr;
  std::uint32_t value_ = 0;
  std::uint32_t length_ = 0;
};

/// Decodes integers as prediction + correction. The correction's magnitude class k (number of bits)
/// is coded with a per-context model, then the value inside the class with per-k models; the high
/// bits of large classes are raw.
class IntegerDecompressor {
 public:
  /// `bits`: width of the values (16 or 32); `contexts`: number of k models to choose from.
  explicit IntegerDecompressor(std::uint32_t bits = 16, std::uint32_t contexts = 1,
                               std::uint32_t bits_high = 8)
      : bits_high_(bits_high) {
    if (bits > 0 && bits < 32) {
      corr_bits_ = bits;
      corr_range_ = 1u << bits;
      corr_min_ = -static_cast<std::int32_t>(corr_range_ / 2);
    } else {
      corr_bits_ = 32;
      corr_range_ = 0;  // full 32-bit range: no folding
      corr_min_ = INT32_MIN;
    }
    k_models_.reserve(contexts);
    for (std::uint32_t i = 0; i < contexts; ++i) k_models_.emplace_back(corr_bits_ + 1);
    corrector_models_.reserve(corr_bits_ + 1);
    corrector_models_.emplace_back(2);  // index 0 unused (k == 0 uses the bit model)
    for (std::uint32_t i = 1; i <= corr_bits_; ++i)
      corrector_models_.emplace_back(i <= bits_high_ ? 1u << i : 1u << bits_high_);
  }

  void set_decoder(ArithmeticDecoder* dec) { dec_ = dec; }

  /// Start state for a new chunk.
  void reset() {
    for (auto& m : k_models_) m.reset();
    corrector_bit_.reset();
    for (auto& m : corrector_models_) m.reset();
  }

  std::int32_t decompress(std::int32_t prediction, std::uint32_t context = 0) {
    // sums in unsigned arithmetic: the format relies on two's-complement wrap-around
    std::uint32_t real = static_cast<std::uint32_t>(prediction) +
                         static_cast<std::uint32_t>(read_corrector(k_models_[context]));
    if (corr_range_ != 0) {  // fold back into [0, 2^bits)
      if (static_cast<std::int32_t>(real) < 0)
        real += corr_range_;
      else if (real >= corr_range_)
        real -= corr_range_;
    }
    return static_cast<std::int32_t>(real);
  }

  /// Magnitude class of the last correction; neighbouring fields use it as context.
  std::uint32_t k() const { return k_; }

 private:
  std::int32_t read_corrector(SymbolModel& k_model) {
    k_ = dec_->decode_symbol(k_model);
    if (k_ == 0) return static_cast<std::int32_t>(dec_->decode_bit(corrector_bit_));  // 0 or 1
    if (k_ >= 32) return corr_min_;
    std::uint32_t c;
    if (k_ <= bits_high_) {
      c = dec_->decode_symbol(corrector_models_[k_]);
    } else {
      const std::uint32_t low_bits = k_ - bits_high_;
      c = dec_->decode_symbol(corrector_models_[k_]);
      c = (c << low_bits) | dec_->read_bits(low_bits);
    }
    // class k holds [-(2^k - 1), -2^(k-1)] and [2^(k-1) + 1, 2^k], coded as [0, 2^k)
    if (c >= (1u << (k_ - 1)))
      c += 1;
    else
      c -= (1u << k_) - 1;  // wraps to the negative half
    return static_cast<std::int32_t>(c);
  }

  ArithmeticDecoder* dec_ = nullptr;
  std::uint32_t bits_high_;
  std::uint32_t corr_bits_;
  std::uint32_t corr_range_;
  std::int32_t corr_min_;
  std::uint32_t k_ = 0;
  std::vector<SymbolModel> k_models_;
  BitModel corrector_bit_;
  std::vector<SymbolModel> corrector_models_;
};

/// Symbol models created on first use (LASzip allocates them lazily per context value). reset()
/// is O(1): a model is re-initialised the first time it is used after a reset.
class LazySymbolModels {
 public:
  LazySymbolModels(std::size_t count, std::uint32_t symbols)
      : symbols_(symbols), models_(count), generation_(count, 0) {}

  void reset() { ++current_; }

  SymbolModel& operator[](std::size_t i) {
    if (generation_[i] != current_) {
      if (!models_[i])
        models_[i] = std::make_unique<SymbolModel>(symbols_);
      else
        models_[i]->reset();
      generation_[i] = current_;
    }
    return *models_[i];
  }

 private:
  std::uint32_t symbols_;
  std::uint32_t current_ = 1;
  std::vector<std::unique_ptr<SymbolModel>> models_;
  std::vector<std::uint32_t> generation_;
};

}  // namespace city3d::detail::laz
