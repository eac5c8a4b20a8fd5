// LASzip version-2 item decoders (pointwise-chunked compressor 2): POINT10, GPSTIME11, RGB12 and
// BYTE. All items of a point share one arithmetic decoder; each chunk starts with a raw record.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

#include "laz/arithmetic_decoder.hpp"

namespace city3d::detail::laz {

// Little-endian field access on raw records (the format is little-endian; so is every host we
// build for).
template <typename T>
inline T load(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
template <typename T>
inline void store(std::uint8_t* p, T v) {
  std::memcpy(p, &v, sizeof v);
}

/// Wraps a byte sum back into 0..255 (corrections are coded modulo 256).
inline std::uint8_t fold_u8(std::int32_t n) { return static_cast<std::uint8_t>(n & 0xFF); }
inline std::int32_t clamp_u8(std::int32_t n) { return n < 0 ? 0 : (n > 255 ? 255 : n); }

/// Median of the last five values, maintained incrementally (LASzip's "streaming median").
class StreamingMedian5 {
 public:
  void reset() {
    std::fill(std::begin(v_), std::end(v_), 0);
    high_ = true;
  }
  std::int32_t get() const { return v_[2]; }
  void add(std::int32_t x) {
    // v_ stays sorted; `high_` alternates which end the next insertion pushes out
    if (high_) {
      if (x < v_[2]) {
        v_[4] = v_[3];
        v_[3] = v_[2];
        if (x < v_[0]) {
          v_[2] = v_[1];
          v_[1] = v_[0];
          v_[0] = x;
        } else if (x < v_[1]) {
          v_[2] = v_[1];
          v_[1] = x;
        } else {
          v_[2] = x;
        }
      } else {
        if (x < v_[3]) {
          v_[4] = v_[3];
          v_[3] = x;
        } else {
          v_[4] = x;
        }
        high_ = false;
      }
    } else {
      if (v_[2] < x) {
        v_[0] = v_[1];
        v_[1] = v_[2];
        if (v_[4] < x) {
          v_[2] = v_[3];
          v_[3] = v_[4];
          v_[4] = x;
        } else if (v_[3] < x) {
          v_[2] = v_[3];
          v_[3] = x;
        } else {
          v_[2] = x;
        }
      } else {
        if (v_[1] < x) {
          v_[0] = v_[1];
          v_[1] = x;
        } else {
          v_[0] = x;
        }
        high_ = true;
      }
    }
  }

 private:
  std::int32_t v_[5] = {0, 0, 0, 0, 0};
  bool high_ = true;
};

// Context of a (number of returns n, return number r) pair for POINT10, 3 bits each. Valid pairs
// (1 <= r <= n <= 5) get their own context 0..14; odd pairs share the rest.
constexpr std::uint8_t kReturnMapV2[8][8] = {
    {15, 14, 13, 12, 11, 10, 9, 8},  {14, 0, 1, 3, 6, 10, 10, 9},   {13, 1, 2, 4, 7, 11, 11, 10},
    {12, 3, 4, 5, 8, 12, 12, 11},    {11, 6, 7, 8, 9, 13, 13, 12},  {10, 10, 11, 12, 13, 14, 14, 13},
    {9, 10, 11, 12, 13, 14, 15, 14}, {8, 9, 10, 11, 12, 13, 14, 15}};

/// Penetration level |n - r| of a return, the context for Z.
inline std::uint32_t return_level_v2(std::uint32_t n, std::uint32_t r) { return n > r ? n - r : r - n; }

constexpr std::size_t kPoint10Size = 20;
constexpr std::size_t kGpsTimeSize = 8;
constexpr std::size_t kRgbSize = 6;

/// POINT10 v2: X, Y, Z, intensity, return/flag byte, classification, scan angle rank, user data,
/// point source id (20 bytes).
class Point10DecoderV2 {
 public:
  explicit Point10DecoderV2(ArithmeticDecoder& dec)
      : dec_(dec),
        changed_values_(64),
        scan_angle_rank_{SymbolModel(256), SymbolModel(256)},
        bit_byte_(256, 256),
        classification_(256, 256),
        user_data_(256, 256),
        ic_intensity_(16, 4),
        ic_point_source_(16),
        ic_dx_(32, 2),
        ic_dy_(32, 22),
        ic_z_(32, 20) {
    for (auto* ic : {&ic_intensity_, &ic_point_source_, &ic_dx_, &ic_dy_, &ic_z_}) ic->set_decoder(&dec_);
  }

  /// New chunk: `raw` is its first record, stored uncompressed.
  void init(const std::uint8_t* raw) {
    for (int i = 0; i < 16; ++i) {
      median_dx_[i].reset();
      median_dy_[i].reset();
      last_intensity_[i] = 0;
    }
    std::fill(std::begin(last_height_), std::end(last_height_), 0);
    changed_values_.reset();
    scan_angle_rank_[0].reset();
    scan_angle_rank_[1].reset();
    bit_byte_.reset();
    classification_.reset();
    user_data_.reset();
    for (auto* ic : {&ic_intensity_, &ic_point_source_, &ic_dx_, &ic_dy_, &ic_z_}) ic->reset();
    std::memcpy(last_, raw, kPoint10Size);
    last_[12] = last_[13] = 0;  // quirk: the encoder starts its intensity history at 0, not at point 0
  }

  void decode(std::uint8_t* out) {
    const std::uint32_t changed = dec_.decode_symbol(changed_values_);
    std::uint8_t& flags = last_[14];  // return number (3 bits), number of returns (3), scan dir, edge
    if (changed & 32) flags = static_cast<std::uint8_t>(dec_.decode_symbol(bit_byte_[flags]));
    const std::uint32_t r = flags & 7;
    const std::uint32_t n = (flags >> 3) & 7;
    const std::uint32_t m = kReturnMapV2[n][r];
    const std::uint32_t l = return_level_v2(n, r);
    if (changed) {
      if (changed & 16) {
        const auto intensity =
            static_cast<std::uint16_t>(ic_intensity_.decompress(last_intensity_[m], m < 3 ? m : 3));
        last_intensity_[m] = intensity;
      }
      store<std::uint16_t>(last_ + 12, last_intensity_[m]);
      if (changed & 8) last_[15] = static_cast<std::uint8_t>(dec_.decode_symbol(classification_[last_[15]]));
      if (changed & 4) {
        const std::uint32_t scan_direction = (flags >> 6) & 1;
        last_[16] = fold_u8(static_cast<std::int32_t>(dec_.decode_symbol(scan_angle_rank_[scan_direction])) +
                            last_[16]);
      }
      if (changed & 2) last_[17] = static_cast<std::uint8_t>(dec_.decode_symbol(user_data_[last_[17]]));
      if (changed & 1) {
        store<std::uint16_t>(last_ + 18, static_cast<std::uint16_t>(
                                             ic_point_source_.decompress(load<std::uint16_t>(last_ + 18))));
      }
    }
    // X and Y: diff against the median of recent diffs in the same return context
    const std::int32_t dx = ic_dx_.decompress(median_dx_[m].get(), n == 1);
    store<std::uint32_t>(last_ + 0, load<std::uint32_t>(last_ + 0) + static_cast<std::uint32_t>(dx));
    median_dx_[m].add(dx);
    std::uint32_t k_bits = ic_dx_.k();
    const std::int32_t dy =
        ic_dy_.decompress(median_dy_[m].get(), (n == 1) + (k_bits < 20 ? (k_bits & ~1u) : 20));
    store<std::uint32_t>(last_ + 4, load<std::uint32_t>(last_ + 4) + static_cast<std::uint32_t>(dy));
    median_dy_[m].add(dy);
    // Z: against the last Z at the same penetration level, context from how far X/Y moved
    k_bits = (ic_dx_.k() + ic_dy_.k()) / 2;
    const std::int32_t z = ic_z_.decompress(last_height_[l], (n == 1) + (k_bits < 18 ? (k_bits & ~1u) : 18));
    store<std::int32_t>(last_ + 8, z);
    last_height_[l] = z;
    std::memcpy(out, last_, kPoint10Size);
  }

 private:
  ArithmeticDecoder& dec_;
  std::uint8_t last_[kPoint10Size] = {};
  std::uint16_t last_intensity_[16] = {};
  StreamingMedian5 median_dx_[16];
  StreamingMedian5 median_dy_[16];
  std::int32_t last_height_[8] = {};
  SymbolModel changed_values_;
  SymbolModel scan_angle_rank_[2];
  LazySymbolModels bit_byte_;
  LazySymbolModels classification_;
  LazySymbolModels user_data_;
  IntegerDecompressor ic_intensity_;
  IntegerDecompressor ic_point_source_;
  IntegerDecompressor ic_dx_;
  IntegerDecompressor ic_dy_;
  IntegerDecompressor ic_z_;
};

// GPS time coding: a diff is predicted as a multiple of the last diff. Symbols of the "multi"
// model: 0 = unpredictable diff, 1..499 = multiplier, 500 = large multiplier, 501..510 = negative
// multipliers, then "unchanged" (v2 only), "full 64-bit value", and switches to one of the other
// three remembered sequences.
constexpr std::int32_t kGpsMulti = 500;
constexpr std::int32_t kGpsMultiMinus = -10;
constexpr std::uint32_t kGpsMaxSequenceSwitches = 4;  ///< a valid stream switches at most once per point

/// State of GPS time prediction: four interleaved time sequences (e.g. several scanner mirrors).
struct GpsTimeState {
  std::uint32_t last = 0;
  std::uint32_t next = 0;
  std::uint64_t time[4] = {};
  std::int32_t diff[4] = {};
  std::int32_t extreme_count[4] = {};

  void reset(std::uint64_t first) {
    last = next = 0;
    for (int i = 0; i < 4; ++i) {
      time[i] = 0;
      diff[i] = 0;
      extreme_count[i] = 0;
    }
    time[0] = first;
  }
};

// A time given in full: its upper 32 bits predicted from the last time's, the lower read raw; it starts
// the next of the four sequences.
inline void decode_full_gps_time(ArithmeticDecoder& dec, IntegerDecompressor& ic, GpsTimeState& s) {
  s.next = (s.next + 1) & 3;
  const auto high =
      static_cast<std::uint32_t>(ic.decompress(static_cast<std::int32_t>(s.time[s.last] >> 32), 8));
  s.time[s.next] = (static_cast<std::uint64_t>(high) << 32) | dec.read_int();
  s.last = s.next;
  s.diff[s.last] = 0;
  s.extreme_count[s.last] = 0;
}

/// Decodes one GPS time with the multiplier scheme shared by GPSTIME11 v2 and POINT14 v3. The two
/// versions number their symbols differently: `v3` drops the "unchanged" symbol of the multi model
/// (v3 codes "unchanged" in the changed-values bits) and shifts the zero-diff model by one.
inline void decode_gps_time(ArithmeticDecoder& dec, SymbolModel& multi_model, SymbolModel& zero_diff_model,
                            IntegerDecompressor& ic, GpsTimeState& s, bool v3) {
  const std::int32_t code_full = kGpsMulti - kGpsMultiMinus + (v3 ? 1 : 2);
  const std::int32_t unchanged = kGpsMulti - kGpsMultiMinus + 1;  // v2 only
  const std::int32_t zero_diff_base = v3 ? 0 : 1;                 // symbol of "32-bit diff"
  for (std::uint32_t attempt = 0; attempt < kGpsMaxSequenceSwitches; ++attempt) {
    if (s.diff[s.last] == 0) {  // last diff was 0: nothing to multiply
      const auto multi = static_cast<std::int32_t>(dec.decode_symbol(zero_diff_model));
      if (multi == zero_diff_base) {  // diff fits 32 bits
        s.diff[s.last] = ic.decompress(0, 0);
        s.time[s.last] += static_cast<std::uint64_t>(static_cast<std::int64_t>(s.diff[s.last]));
        s.extreme_count[s.last] = 0;
      } else if (multi == zero_diff_base + 1) {  // full value: upper 32 bits predicted, lower raw
        decode_full_gps_time(dec, ic, s);
      } else if (multi > zero_diff_base + 1) {  // switch to another sequence, then decode again
        s.last = (s.last + static_cast<std::uint32_t>(multi - zero_diff_base - 1)) & 3;
        continue;
      }
      return;  // v2 symbol 0: time unchanged
    }
    const auto multi = static_cast<std::int32_t>(dec.decode_symbol(multi_model));
    const auto last_diff = static_cast<std::uint32_t>(s.diff[s.last]);
    if (multi == 1) {
      s.time[s.last] +=
          static_cast<std::uint64_t>(static_cast<std::int64_t>(ic.decompress(s.diff[s.last], 1)));
      s.extreme_count[s.last] = 0;
      return;
    }
    if (multi < (v3 ? code_full : unchanged)) {
      std::int32_t diff;
      bool extreme = false;
      if (multi == 0) {
        diff = ic.decompress(0, 7);
        extreme = true;
      } else if (multi < kGpsMulti) {
        diff = ic.decompress(static_cast<std::int32_t>(static_cast<std::uint32_t>(multi) * last_diff),
                             multi < 10 ? 2 : 3);
      } else if (multi == kGpsMulti) {
        diff = ic.decompress(static_cast<std::int32_t>(static_cast<std::uint32_t>(kGpsMulti) * last_diff), 4);
        extreme = true;
      } else {
        const std::int32_t negative = kGpsMulti - multi;
        if (negative > kGpsMultiMinus) {
          diff =
              ic.decompress(static_cast<std::int32_t>(static_cast<std::uint32_t>(negative) * last_diff), 5);
        } else {
          diff = ic.decompress(
              static_cast<std::int32_t>(static_cast<std::uint32_t>(kGpsMultiMinus) * last_diff), 6);
          extreme = true;
        }
      }
      if (extreme && ++s.extreme_count[s.last] > 3) {  // a new regular diff after 4 outliers
        s.diff[s.last] = diff;
        s.extreme_count[s.last] = 0;
      }
      s.time[s.last] += static_cast<std::uint64_t>(static_cast<std::int64_t>(diff));
      return;
    }
    if (!v3 && multi == unchanged) return;
    if (multi == code_full) {
      decode_full_gps_time(dec, ic, s);
      return;
    }
    s.last = (s.last + static_cast<std::uint32_t>(multi - code_full)) & 3;  // switch sequence
  }
  throw_corrupt("GPS time switches sequence repeatedly");
}

/// GPSTIME11 v2: the 8-byte GPS time.
class GpsTimeDecoderV2 {
 public:
  explicit GpsTimeDecoderV2(ArithmeticDecoder& dec)
      : dec_(dec), multi_(kGpsMulti - kGpsMultiMinus + 6), zero_diff_(6), ic_(32, 9) {
    ic_.set_decoder(&dec_);
  }
  void init(const std::uint8_t* raw) {
    multi_.reset();
    zero_diff_.reset();
    ic_.reset();
    state_.reset(load<std::uint64_t>(raw));
  }
  void decode(std::uint8_t* out) {
    decode_gps_time(dec_, multi_, zero_diff_, ic_, state_, false);
    store<std::uint64_t>(out, state_.time[state_.last]);
  }

 private:
  ArithmeticDecoder& dec_;
  SymbolModel multi_;
  SymbolModel zero_diff_;
  IntegerDecompressor ic_;
  GpsTimeState state_;
};

/// Models of the RGB scheme shared by RGB12 v2 and RGB14 / RGBNIR14 v3.
struct RgbModels {
  SymbolModel byte_used{128};  ///< which of the 6 colour bytes changed, bit 6: G/B differ from R
  SymbolModel diff[6] = {SymbolModel(256), SymbolModel(256), SymbolModel(256),
                         SymbolModel(256), SymbolModel(256), SymbolModel(256)};
  void reset() {
    byte_used.reset();
    for (auto& m : diff) m.reset();
  }
};

/// Decodes R, G, B (low and high bytes separately); G and B are predicted from R's change.
inline void decode_rgb(ArithmeticDecoder& dec, RgbModels& m, const std::uint16_t last[3],
                       std::uint16_t rgb[3]) {
  const std::uint32_t sym = dec.decode_symbol(m.byte_used);
  auto corr = [&](int i) { return static_cast<std::int32_t>(dec.decode_symbol(m.diff[i])); };
  rgb[0] = (sym & 1) ? fold_u8(corr(0) + (last[0] & 0xFF)) : (last[0] & 0xFF);
  rgb[0] |=
      (sym & 2) ? static_cast<std::uint16_t>(fold_u8(corr(1) + (last[0] >> 8)) << 8) : (last[0] & 0xFF00);
  if (sym & (1 << 6)) {
    std::int32_t diff = (rgb[0] & 0xFF) - (last[0] & 0xFF);
    rgb[1] = (sym & 4) ? fold_u8(corr(2) + clamp_u8(diff + (last[1] & 0xFF))) : (last[1] & 0xFF);
    if (sym & 16) {
      diff = (diff + ((rgb[1] & 0xFF) - (last[1] & 0xFF))) / 2;
      rgb[2] = fold_u8(corr(4) + clamp_u8(diff + (last[2] & 0xFF)));
    } else {
      rgb[2] = last[2] & 0xFF;
    }
    diff = (rgb[0] >> 8) - (last[0] >> 8);
    rgb[1] |= (sym & 8) ? static_cast<std::uint16_t>(fold_u8(corr(3) + clamp_u8(diff + (last[1] >> 8))) << 8)
                        : (last[1] & 0xFF00);
    if (sym & 32) {
      diff = (diff + ((rgb[1] >> 8) - (last[1] >> 8))) / 2;
      rgb[2] |= static_cast<std::uint16_t>(fold_u8(corr(5) + clamp_u8(diff + (last[2] >> 8))) << 8);
    } else {
      rgb[2] |= last[2] & 0xFF00;
    }
  } else {  // grey: G and B equal R
    rgb[1] = rgb[0];
    rgb[2] = rgb[0];
  }
}

/// RGB12 v2: three 16-bit colour channels.
class RgbDecoderV2 {
 public:
  explicit RgbDecoderV2(ArithmeticDecoder& dec) : dec_(dec) {}
  void init(const std::uint8_t* raw) {
    models_.reset();
    for (int i = 0; i < 3; ++i) last_[i] = load<std::uint16_t>(raw + 2 * i);
  }
  void decode(std::uint8_t* out) {
    std::uint16_t rgb[3];
    decode_rgb(dec_, models_, last_, rgb);
    for (int i = 0; i < 3; ++i) {
      last_[i] = rgb[i];
      store<std::uint16_t>(out + 2 * i, rgb[i]);
    }
  }

 private:
  ArithmeticDecoder& dec_;
  RgbModels models_;
  std::uint16_t last_[3] = {};
};

/// BYTE v2: extra bytes, each coded as a difference to its previous value.
class ByteDecoderV2 {
 public:
  ByteDecoderV2(ArithmeticDecoder& dec, std::size_t count) : dec_(dec), last_(count) {
    models_.reserve(count);
    for (std::size_t i = 0; i < count; ++i) models_.emplace_back(256);
  }
  void init(const std::uint8_t* raw) {
    for (auto& m : models_) m.reset();
    std::memcpy(last_.data(), raw, last_.size());
  }
  void decode(std::uint8_t* out) {
    for (std::size_t i = 0; i < last_.size(); ++i) {
      last_[i] = fold_u8(last_[i] + static_cast<std::int32_t>(dec_.decode_symbol(models_[i])));
      out[i] = last_[i];
    }
  }

 private:
  ArithmeticDecoder& dec_;
  std::vector<SymbolModel> models_;
  std::vector<std::uint8_t> last_;
};

}  // namespace city3d::detail::laz
