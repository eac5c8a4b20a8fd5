// LASzip version-1 item decoders (files from LASzip 1.x, usually with the non-chunked compressor 1):
// POINT10, GPSTIME11, RGB12 and BYTE. Simpler predictors than v2, same arithmetic coder.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include "laz/arithmetic_decoder.hpp"
#include "laz/items_v2.hpp"

namespace city3d::detail::laz {

/// Median of three values.
inline std::int32_t median3(const std::int32_t v[3]) {
  if (v[0] < v[1]) {
    if (v[1] < v[2]) return v[1];
    return v[0] < v[2] ? v[2] : v[0];
  }
  if (v[0] < v[2]) return v[0];
  return v[1] < v[2] ? v[2] : v[1];
}

/// POINT10 v1: X/Y predicted by the median of the last three diffs, Z from the last Z.
class Point10DecoderV1 {
 public:
  explicit Point10DecoderV1(ArithmeticDecoder& dec)
      : dec_(dec),
        changed_values_(64),
        bit_byte_(256, 256),
        classification_(256, 256),
        user_data_(256, 256),
        ic_dx_(32),
        ic_dy_(32, 20),
        ic_z_(32, 20),
        ic_intensity_(16),
        ic_scan_angle_rank_(8, 2),
        ic_point_source_(16) {
    for (auto* ic : {&ic_dx_, &ic_dy_, &ic_z_, &ic_intensity_, &ic_scan_angle_rank_, &ic_point_source_})
      ic->set_decoder(&dec_);
  }

  void init(const std::uint8_t* raw) {
    for (int i = 0; i < 3; ++i) last_dx_[i] = last_dy_[i] = 0;
    next_diff_ = 0;
    for (auto* ic : {&ic_dx_, &ic_dy_, &ic_z_, &ic_intensity_, &ic_scan_angle_rank_, &ic_point_source_})
      ic->reset();
    changed_values_.reset();
    bit_byte_.reset();
    classification_.reset();
    user_data_.reset();
    std::memcpy(last_, raw, kPoint10Size);
  }

  void decode(std::uint8_t* out) {
    std::uint8_t item[kPoint10Size];
    std::memcpy(item, last_, kPoint10Size);
    const std::int32_t dx = ic_dx_.decompress(median3(last_dx_));
    store<std::uint32_t>(item, load<std::uint32_t>(item) + static_cast<std::uint32_t>(dx));
    std::uint32_t k_bits = ic_dx_.k();  // how far X moved selects the Y and Z contexts
    const std::int32_t dy = ic_dy_.decompress(median3(last_dy_), k_bits < 19 ? k_bits : 19);
    store<std::uint32_t>(item + 4, load<std::uint32_t>(item + 4) + static_cast<std::uint32_t>(dy));
    k_bits = (k_bits + ic_dy_.k()) / 2;
    store<std::int32_t>(item + 8, ic_z_.decompress(load<std::int32_t>(last_ + 8), k_bits < 19 ? k_bits : 19));

    const std::uint32_t changed = dec_.decode_symbol(changed_values_);
    if (changed & 32)
      store<std::uint16_t>(
          item + 12, static_cast<std::uint16_t>(ic_intensity_.decompress(load<std::uint16_t>(last_ + 12))));
    if (changed & 16) item[14] = static_cast<std::uint8_t>(dec_.decode_symbol(bit_byte_[last_[14]]));
    if (changed & 8) item[15] = static_cast<std::uint8_t>(dec_.decode_symbol(classification_[last_[15]]));
    if (changed & 4)
      item[16] = static_cast<std::uint8_t>(ic_scan_angle_rank_.decompress(last_[16], k_bits < 3));
    if (changed & 2) item[17] = static_cast<std::uint8_t>(dec_.decode_symbol(user_data_[last_[17]]));
    if (changed & 1) {
      store<std::uint16_t>(item + 18, static_cast<std::uint16_t>(
                                          ic_point_source_.decompress(load<std::uint16_t>(last_ + 18))));
    }
    last_dx_[next_diff_] = dx;
    last_dy_[next_diff_] = dy;
    next_diff_ = next_diff_ == 2 ? 0 : next_diff_ + 1;
    std::memcpy(last_, item, kPoint10Size);
    std::memcpy(out, item, kPoint10Size);
  }

 private:
  ArithmeticDecoder& dec_;
  std::uint8_t last_[kPoint10Size] = {};
  std::int32_t last_dx_[3] = {};
  std::int32_t last_dy_[3] = {};
  int next_diff_ = 0;
  SymbolModel changed_values_;
  LazySymbolModels bit_byte_;
  LazySymbolModels classification_;
  LazySymbolModels user_data_;
  IntegerDecompressor ic_dx_;
  IntegerDecompressor ic_dy_;
  IntegerDecompressor ic_z_;
  IntegerDecompressor ic_intensity_;
  IntegerDecompressor ic_scan_angle_rank_;
  IntegerDecompressor ic_point_source_;
};

// GPS time v1: symbols of the multi model are multipliers of the last diff up to 509, then "full
// 64-bit value" (510) and "unchanged" (511).
constexpr std::uint32_t kGpsMultiMaxV1 = 512;

/// GPSTIME11 v1.
class GpsTimeDecoderV1 {
 public:
  explicit GpsTimeDecoderV1(ArithmeticDecoder& dec)
      : dec_(dec), multi_(kGpsMultiMaxV1), zero_diff_(3), ic_(32, 6) {
    ic_.set_decoder(&dec_);
  }
  void init(const std::uint8_t* raw) {
    multi_.reset();
    zero_diff_.reset();
    ic_.reset();
    last_diff_ = 0;
    extreme_count_ = 0;
    time_ = load<std::uint64_t>(raw);
  }
  void decode(std::uint8_t* out) {
    if (last_diff_ == 0) {
      const std::uint32_t multi = dec_.decode_symbol(zero_diff_);
      if (multi == 1) {  // 32-bit diff
        last_diff_ = ic_.decompress(0, 0);
        time_ += static_cast<std::uint64_t>(static_cast<std::int64_t>(last_diff_));
      } else if (multi == 2) {  // full value
        time_ = read_int64();
      }
    } else {
      const std::uint32_t multi = dec_.decode_symbol(multi_);
      const auto last = static_cast<std::uint32_t>(last_diff_);
      if (multi < kGpsMultiMaxV1 - 2) {
        std::int32_t diff;
        if (multi == 1) {
          diff = ic_.decompress(last_diff_, 1);
          last_diff_ = diff;
          extreme_count_ = 0;
        } else if (multi == 0) {
          diff = ic_.decompress(last_diff_ / 4, 2);
          if (++extreme_count_ > 3) {
            last_diff_ = diff;
            extreme_count_ = 0;
          }
        } else {
          const auto predicted = static_cast<std::int32_t>(multi * last);
          diff = ic_.decompress(predicted, multi < 10 ? 3 : (multi < 50 ? 4 : 5));
          if (multi == kGpsMultiMaxV1 - 3 && ++extreme_count_ > 3) {
            last_diff_ = diff;
            extreme_count_ = 0;
          }
        }
        time_ += static_cast<std::uint64_t>(static_cast<std::int64_t>(diff));
      } else if (multi == kGpsMultiMaxV1 - 2) {
        time_ = read_int64();
      }
    }
    store<std::uint64_t>(out, time_);
  }

 private:
  std::uint64_t read_int64() {
    const std::uint64_t low = dec_.read_int();
    const std::uint64_t high = dec_.read_int();
    return (high << 32) | low;
  }

  ArithmeticDecoder& dec_;
  SymbolModel multi_;
  SymbolModel zero_diff_;
  IntegerDecompressor ic_;
  std::int32_t last_diff_ = 0;
  std::int32_t extreme_count_ = 0;
  std::uint64_t time_ = 0;
};

/// RGB12 v1: each colour byte that changed is coded against its previous value.
class RgbDecoderV1 {
 public:
  explicit RgbDecoderV1(ArithmeticDecoder& dec) : dec_(dec), byte_used_(64), ic_(8, 6) {
    ic_.set_decoder(&dec_);
  }
  void init(const std::uint8_t* raw) {
    byte_used_.reset();
    ic_.reset();
    std::memcpy(last_, raw, kRgbSize);
  }
  void decode(std::uint8_t* out) {
    const std::uint32_t sym = dec_.decode_symbol(byte_used_);
    for (std::uint32_t i = 0; i < kRgbSize; ++i) {  // bytes in file order: R low, R high, G low, ...
      if (sym & (1u << i)) last_[i] = static_cast<std::uint8_t>(ic_.decompress(last_[i], i));
    }
    std::memcpy(out, last_, kRgbSize);
  }

 private:
  ArithmeticDecoder& dec_;
  SymbolModel byte_used_;
  IntegerDecompressor ic_;
  std::uint8_t last_[kRgbSize] = {};
};

/// BYTE v1: each extra byte coded against its previous value, one context per byte.
class ByteDecoderV1 {
 public:
  ByteDecoderV1(ArithmeticDecoder& dec, std::size_t count)
      : dec_(dec), ic_(8, static_cast<std::uint32_t>(count)), last_(count) {
    ic_.set_decoder(&dec_);
  }
  void init(const std::uint8_t* raw) {
    ic_.reset();
    std::memcpy(last_.data(), raw, last_.size());
  }
  void decode(std::uint8_t* out) {
    for (std::size_t i = 0; i < last_.size(); ++i) {
      last_[i] = static_cast<std::uint8_t>(ic_.decompress(last_[i], static_cast<std::uint32_t>(i)));
    }
    std::memcpy(out, last_.data(), last_.size());
  }

 private:
  ArithmeticDecoder& dec_;
  IntegerDecompressor ic_;
  std::vector<std::uint8_t> last_;
};

}  // namespace city3d::detail::laz
