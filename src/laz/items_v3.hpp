// LASzip version-3 item decoders (layered-chunked compressor 3): POINT14, RGB14, RGBNIR14 and
// BYTE14. Every field group has its own byte layer and arithmetic decoder, so empty layers (values
// that never change within the chunk) cost nothing. State is kept per scanner channel ("context").
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "laz/arithmetic_decoder.hpp"
#include "laz/items_v2.hpp"

namespace city3d::detail::laz {

/// One compressed layer of a chunk: its bytes (possibly none) and the decoder reading them.
struct Layer {
  const std::uint8_t* data = nullptr;
  std::uint32_t size = 0;
  ArithmeticDecoder dec;

  /// Starts decoding if the layer has bytes; an empty layer means "unchanged in this chunk".
  bool start() {
    if (size == 0) return false;
    dec.start(data, data + size);
    return true;
  }
};

constexpr std::size_t kPoint14Size = 30;
constexpr std::size_t kPoint14Layers =
    9;  ///< XY+returns, Z, class, flags, intensity, angle, user, source, time
constexpr std::uint32_t kScannerChannels = 4;

// Return-context map for 4-bit return numbers / counts: 16 x 16 pairs simplified to 6 contexts.
constexpr std::uint8_t kReturnMap6[16][16] = {
    {0, 1, 2, 3, 4, 5, 3, 4, 4, 5, 5, 5, 5, 5, 5, 5}, {1, 0, 1, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3},
    {2, 1, 2, 4, 4, 4, 4, 4, 4, 4, 4, 3, 3, 3, 3, 3}, {3, 3, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
    {4, 3, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4}, {5, 3, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
    {3, 3, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4}, {4, 3, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4},
    {4, 3, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4}, {5, 3, 4, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4},
    {5, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4}, {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 4, 4, 4},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 4, 4}, {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 4},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5}, {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5}};

/// Penetration level |n - r| capped at 7, the context for Z.
inline std::uint32_t return_level_v3(std::uint32_t n, std::uint32_t r) {
  const std::uint32_t d = n > r ? n - r : r - n;
  return d < 7 ? d : 7;
}

/// The fields of a point record of formats 6-10 (the first 30 bytes).
struct Point14 {
  std::int32_t x = 0, y = 0, z = 0;
  std::uint16_t intensity = 0;
  std::uint8_t return_number = 0, number_of_returns = 0;
  std::uint8_t classification_flags = 0, scanner_channel = 0, scan_direction = 0, edge_of_flight_line = 0;
  std::uint8_t classification = 0, user_data = 0;
  std::int16_t scan_angle = 0;
  std::uint16_t point_source_id = 0;
  std::uint64_t gps_time = 0;  ///< raw bits of the double
  bool gps_time_changed = false;

  void read(const std::uint8_t* p) {
    x = load<std::int32_t>(p);
    y = load<std::int32_t>(p + 4);
    z = load<std::int32_t>(p + 8);
    intensity = load<std::uint16_t>(p + 12);
    return_number = p[14] & 0x0F;
    number_of_returns = p[14] >> 4;
    classification_flags = p[15] & 0x0F;
    scanner_channel = (p[15] >> 4) & 3;
    scan_direction = (p[15] >> 6) & 1;
    edge_of_flight_line = p[15] >> 7;
    classification = p[16];
    user_data = p[17];
    scan_angle = load<std::int16_t>(p + 18);
    point_source_id = load<std::uint16_t>(p + 20);
    gps_time = load<std::uint64_t>(p + 22);
    gps_time_changed = false;
  }
  void write(std::uint8_t* p) const {
    store(p, x);
    store(p + 4, y);
    store(p + 8, z);
    store(p + 12, intensity);
    p[14] = static_cast<std::uint8_t>(return_number | (number_of_returns << 4));
    p[15] = static_cast<std::uint8_t>(classification_flags | (scanner_channel << 4) | (scan_direction << 6) |
                                      (edge_of_flight_line << 7));
    p[16] = classification;
    p[17] = user_data;
    store(p + 18, scan_angle);
    store(p + 20, point_source_id);
    store(p + 22, gps_time);
  }
};

/// POINT14 v3.
class Point14DecoderV3 {
 public:
  Point14DecoderV3() = default;

  /// Layer sizes in the chunk header order.
  static constexpr std::size_t layer_count() { return kPoint14Layers; }

  /// New chunk: `raw` is the uncompressed first record; `layers` the nine layers. Returns the
  /// scanner channel, the context every other item starts from.
  std::uint32_t init(const std::uint8_t* raw, Layer* layers) {
    layers_ = layers;
    static const char* const kLabels[kPoint14Layers] = {
        "XY layer",         "Z layer",         "classification layer", "flags layer",   "intensity layer",
        "scan angle layer", "user data layer", "point source layer",   "GPS time layer"};
    for (std::size_t i = 0; i < kPoint14Layers; ++i) layers_[i].dec.set_label(kLabels[i]);
    layers_[0].start();  // XY layer: always present, decoded for every point
    for (std::size_t i = 1; i < kPoint14Layers; ++i) changed_[i] = layers_[i].start();
    for (auto& c : contexts_)
      if (c) c->unused = true;
    Point14 first;
    first.read(raw);
    current_ = first.scanner_channel;
    activate(current_, first);
    return current_;
  }

  /// Decodes one point into `out` (30 bytes) and returns its scanner channel.
  std::uint32_t decode(std::uint8_t* out) {
    Context* c = contexts_[current_].get();
    ArithmeticDecoder& xy = layers_[0].dec;
    Point14* last = &c->last;
    // context of the previous return: single / first / last / intermediate, plus "time changed"
    std::uint32_t lpr =
        (last->return_number == 1 ? 1u : 0u) + (last->return_number >= last->number_of_returns ? 2u : 0u);
    lpr += last->gps_time_changed ? 4u : 0u;
    const std::uint32_t changed = xy.decode_symbol(c->changed_values[lpr]);
    if (changed & (1 << 6)) {  // scanner channel changed: coded as (new - old - 1) mod 4
      const std::uint32_t channel = (current_ + xy.decode_symbol(c->scanner_channel) + 1) % kScannerChannels;
      if (!contexts_[channel] || contexts_[channel]->unused)
        activate(channel, *last);  // seed from the old context
      current_ = channel;
      c = contexts_[current_].get();
      last = &c->last;
      last->scanner_channel = static_cast<std::uint8_t>(channel);
    }
    const bool point_source_change = changed & (1 << 5);
    const bool gps_time_change = changed & (1 << 4);
    const bool scan_angle_change = changed & (1 << 3);

    const std::uint32_t last_n = last->number_of_returns;
    const std::uint32_t last_r = last->return_number;
    std::uint32_t n = last_n;
    if (changed & (1 << 2)) {
      n = xy.decode_symbol(c->number_of_returns[last_n]);
      last->number_of_returns = static_cast<std::uint8_t>(n);
    }
    std::uint32_t r = last_r;
    switch (changed & 3) {
      case 0:
        break;
      case 1:
        r = (last_r + 1) % 16;
        break;
      case 2:
        r = (last_r + 15) % 16;
        break;
      default:  // a jump of more than one return
        if (gps_time_change)
          r = xy.decode_symbol(c->return_number[last_r]);
        else
          r = (last_r + xy.decode_symbol(c->return_number_gps_same) + 2) % 16;
        break;
    }
    last->return_number = static_cast<std::uint8_t>(r);

    const std::uint32_t m = kReturnMap6[n][r];
    const std::uint32_t l = return_level_v3(n, r);
    // current return: first (1), last (2), single (3) or intermediate (0)
    const std::uint32_t cpr = (r == 1 ? 1u : 0u) + (r >= n ? 2u : 0u);
    const std::uint32_t median_index = (m << 1) | (gps_time_change ? 1u : 0u);

    const std::int32_t dx = c->ic_dx.decompress(c->median_dx[median_index].get(), n == 1);
    last->x = static_cast<std::int32_t>(static_cast<std::uint32_t>(last->x) + static_cast<std::uint32_t>(dx));
    c->median_dx[median_index].add(dx);
    std::uint32_t k_bits = c->ic_dx.k();
    const std::int32_t dy =
        c->ic_dy.decompress(c->median_dy[median_index].get(), (n == 1) + (k_bits < 20 ? (k_bits & ~1u) : 20));
    last->y = static_cast<std::int32_t>(static_cast<std::uint32_t>(last->y) + static_cast<std::uint32_t>(dy));
    c->median_dy[median_index].add(dy);

    if (changed_[1]) {  // Z
      k_bits = (c->ic_dx.k() + c->ic_dy.k()) / 2;
      last->z = c->ic_z.decompress(c->last_z[l], (n == 1) + (k_bits < 18 ? (k_bits & ~1u) : 18));
      c->last_z[l] = last->z;
    }
    if (changed_[2]) {  // classification: context is the old class (5 bits) and "single return"
      const std::uint32_t ccc = ((last->classification & 0x1Fu) << 1) + (cpr == 3 ? 1u : 0u);
      last->classification = static_cast<std::uint8_t>(layers_[2].dec.decode_symbol(c->classification[ccc]));
    }
    if (changed_[3]) {  // flags: edge, scan direction, 4 classification flags
      const std::uint32_t old_flags =
          (last->edge_of_flight_line << 5) | (last->scan_direction << 4) | last->classification_flags;
      const std::uint32_t flags = layers_[3].dec.decode_symbol(c->flags[old_flags]);
      last->edge_of_flight_line = (flags >> 5) & 1;
      last->scan_direction = (flags >> 4) & 1;
      last->classification_flags = flags & 0x0F;
    }
    if (changed_[4]) {
      const std::uint32_t i = (cpr << 1) | (gps_time_change ? 1u : 0u);
      c->last_intensity[i] =
          static_cast<std::uint16_t>(c->ic_intensity.decompress(c->last_intensity[i], cpr));
      last->intensity = c->last_intensity[i];
    }
    if (changed_[5] && scan_angle_change) {
      last->scan_angle =
          static_cast<std::int16_t>(c->ic_scan_angle.decompress(last->scan_angle, gps_time_change));
    }
    if (changed_[6]) {
      last->user_data =
          static_cast<std::uint8_t>(layers_[6].dec.decode_symbol(c->user_data[last->user_data / 4]));
    }
    if (changed_[7] && point_source_change) {
      last->point_source_id =
          static_cast<std::uint16_t>(c->ic_point_source.decompress(last->point_source_id));
    }
    if (changed_[8] && gps_time_change) {
      decode_gps_time(layers_[8].dec, c->gps_multi, c->gps_zero_diff, c->ic_gps_time, c->gps, true);
      last->gps_time = c->gps.time[c->gps.last];
    }
    last->write(out);
    last->gps_time_changed = gps_time_change;
    return current_;
  }

 private:
  /// Everything LASzip keeps per scanner channel.
  struct Context {
    explicit Context(Layer* layers)
        : changed_values{SymbolModel(128), SymbolModel(128), SymbolModel(128), SymbolModel(128),
                         SymbolModel(128), SymbolModel(128), SymbolModel(128), SymbolModel(128)} {
      ic_dx.set_decoder(&layers[0].dec);
      ic_dy.set_decoder(&layers[0].dec);
      ic_z.set_decoder(&layers[1].dec);
      ic_intensity.set_decoder(&layers[4].dec);
      ic_scan_angle.set_decoder(&layers[5].dec);
      ic_point_source.set_decoder(&layers[7].dec);
      ic_gps_time.set_decoder(&layers[8].dec);
    }
    bool unused = true;
    Point14 last;
    std::uint16_t last_intensity[8] = {};
    StreamingMedian5 median_dx[12];
    StreamingMedian5 median_dy[12];
    std::int32_t last_z[8] = {};
    SymbolModel changed_values[8];
    SymbolModel scanner_channel{3};
    LazySymbolModels number_of_returns{16, 16};
    LazySymbolModels return_number{16, 16};
    SymbolModel return_number_gps_same{13};
    IntegerDecompressor ic_dx{32, 2};
    IntegerDecompressor ic_dy{32, 22};
    IntegerDecompressor ic_z{32, 20};
    LazySymbolModels classification{64, 256};
    LazySymbolModels flags{64, 64};
    LazySymbolModels user_data{64, 256};
    IntegerDecompressor ic_intensity{16, 4};
    IntegerDecompressor ic_scan_angle{16, 2};
    IntegerDecompressor ic_point_source{16};
    SymbolModel gps_multi{static_cast<std::uint32_t>(kGpsMulti - kGpsMultiMinus + 5)};
    SymbolModel gps_zero_diff{5};
    IntegerDecompressor ic_gps_time{32, 9};
    GpsTimeState gps;
  };

  /// Resets (creating if needed) the context of `channel`, seeded with `seed` as its last point.
  void activate(std::uint32_t channel, const Point14& seed) {
    if (!contexts_[channel]) contexts_[channel] = std::make_unique<Context>(layers_);
    Context& c = *contexts_[channel];
    for (auto& m : c.changed_values) m.reset();
    c.scanner_channel.reset();
    c.number_of_returns.reset();
    c.return_number.reset();
    c.return_number_gps_same.reset();
    c.ic_dx.reset();
    c.ic_dy.reset();
    for (int i = 0; i < 12; ++i) {
      c.median_dx[i].reset();
      c.median_dy[i].reset();
    }
    c.ic_z.reset();
    for (auto& z : c.last_z) z = seed.z;
    c.classification.reset();
    c.flags.reset();
    c.user_data.reset();
    c.ic_intensity.reset();
    for (auto& i : c.last_intensity) i = seed.intensity;
    c.ic_scan_angle.reset();
    c.ic_point_source.reset();
    c.gps_multi.reset();
    c.gps_zero_diff.reset();
    c.ic_gps_time.reset();
    c.gps.reset(seed.gps_time);
    c.last = seed;
    c.last.gps_time_changed = false;
    c.unused = false;
  }

  Layer* layers_ = nullptr;
  bool changed_[kPoint14Layers] = {};
  std::uint32_t current_ = 0;
  std::array<std::unique_ptr<Context>, kScannerChannels> contexts_;
};

/// RGB14 v3 (6 bytes) and RGBNIR14 v3 (8 bytes: RGB plus near infrared in its own layer).
class RgbNirDecoderV3 {
 public:
  explicit RgbNirDecoderV3(bool nir) : nir_(nir) {}
  std::size_t layer_count() const { return nir_ ? 2 : 1; }

  void init(const std::uint8_t* raw, Layer* layers, std::uint32_t context) {
    layers_ = layers;
    layers_[0].dec.set_label("RGB layer");
    if (nir_) layers_[1].dec.set_label("NIR layer");
    changed_rgb_ = layers_[0].start();
    changed_nir_ = nir_ && layers_[1].start();
    for (auto& c : contexts_)
      if (c) c->unused = true;
    std::uint16_t seed[4] = {};
    for (std::size_t i = 0; i < (nir_ ? 4u : 3u); ++i) seed[i] = load<std::uint16_t>(raw + 2 * i);
    current_ = context;
    activate(current_, seed);
  }

  void decode(std::uint8_t* out, std::uint32_t context) {
    std::uint16_t* last = contexts_[current_]->last;
    if (context != current_) {
      current_ = context;
      if (!contexts_[current_] || contexts_[current_]->unused) {
        activate(current_, last);
        last = contexts_[current_]->last;
      }
      // quirk: switching to a context already in use keeps writing the previous context's last
      // values (LASzip's encoder does the same, so the streams agree)
    }
    Context& c = *contexts_[current_];
    std::uint16_t value[4];
    if (changed_rgb_) {
      decode_rgb(layers_[0].dec, c.rgb, last, value);
      for (int i = 0; i < 3; ++i) last[i] = value[i];
    } else {
      for (int i = 0; i < 3; ++i) value[i] = last[i];
    }
    if (nir_) {
      if (changed_nir_) {
        ArithmeticDecoder& dec = layers_[1].dec;
        const std::uint32_t sym = dec.decode_symbol(c.nir_bytes_used);
        std::uint16_t v =
            (sym & 1)
                ? fold_u8(static_cast<std::int32_t>(dec.decode_symbol(c.nir_diff[0])) + (last[3] & 0xFF))
                : (last[3] & 0xFF);
        v |= (sym & 2)
                 ? static_cast<std::uint16_t>(
                       fold_u8(static_cast<std::int32_t>(dec.decode_symbol(c.nir_diff[1])) + (last[3] >> 8))
                       << 8)
                 : (last[3] & 0xFF00);
        last[3] = v;
      }
      value[3] = last[3];
    }
    for (std::size_t i = 0; i < (nir_ ? 4u : 3u); ++i) store(out + 2 * i, value[i]);
  }

 private:
  struct Context {
    bool unused = true;
    std::uint16_t last[4] = {};
    RgbModels rgb;
    SymbolModel nir_bytes_used{4};
    SymbolModel nir_diff[2] = {SymbolModel(256), SymbolModel(256)};
  };

  void activate(std::uint32_t context, const std::uint16_t* seed) {
    if (!contexts_[context]) contexts_[context] = std::make_unique<Context>();
    Context& c = *contexts_[context];
    c.rgb.reset();
    c.nir_bytes_used.reset();
    c.nir_diff[0].reset();
    c.nir_diff[1].reset();
    std::uint16_t copy[4];
    std::memcpy(copy, seed, sizeof copy);  // seed may alias another context's values
    std::memcpy(c.last, copy, sizeof copy);
    c.unused = false;
  }

  bool nir_;
  Layer* layers_ = nullptr;
  bool changed_rgb_ = false;
  bool changed_nir_ = false;
  std::uint32_t current_ = 0;
  std::array<std::unique_ptr<Context>, kScannerChannels> contexts_;
};

/// BYTE14 v3: extra bytes, one layer per byte.
class ByteDecoderV3 {
 public:
  explicit ByteDecoderV3(std::size_t count) : count_(count), changed_(count) {}
  std::size_t layer_count() const { return count_; }

  void init(const std::uint8_t* raw, Layer* layers, std::uint32_t context) {
    layers_ = layers;
    for (std::size_t i = 0; i < count_; ++i) {
      layers_[i].dec.set_label("extra byte layer");
      changed_[i] = layers_[i].start();
    }
    for (auto& c : contexts_)
      if (c) c->unused = true;
    current_ = context;
    activate(current_, raw);
  }

  void decode(std::uint8_t* out, std::uint32_t context) {
    std::uint8_t* last = contexts_[current_]->last.data();
    if (context != current_) {
      current_ = context;
      if (!contexts_[current_] || contexts_[current_]->unused) {
        activate(current_, last);
        last = contexts_[current_]->last.data();
      }
      // same quirk as RGB14: an already used context keeps the previous context's last bytes
    }
    Context& c = *contexts_[current_];
    for (std::size_t i = 0; i < count_; ++i) {
      if (changed_[i])
        last[i] = fold_u8(last[i] + static_cast<std::int32_t>(layers_[i].dec.decode_symbol(c.models[i])));
      out[i] = last[i];
    }
  }

 private:
  struct Context {
    explicit Context(std::size_t count) : last(count) {
      models.reserve(count);
      for (std::size_t i = 0; i < count; ++i) models.emplace_back(256);
    }
    bool unused = true;
    std::vector<std::uint8_t> last;
    std::vector<SymbolModel> models;
  };

  void activate(std::uint32_t context, const std::uint8_t* seed) {
    if (!contexts_[context]) contexts_[context] = std::make_unique<Context>(count_);
    Context& c = *contexts_[context];
    for (auto& m : c.models) m.reset();
    if (c.last.data() != seed) std::memmove(c.last.data(), seed, count_);
    c.unused = false;
  }

  std::size_t count_;
  std::vector<char> changed_;
  Layer* layers_ = nullptr;
  std::uint32_t current_ = 0;
  std::array<std::unique_ptr<Context>, kScannerChannels> contexts_;
};

}  // namespace city3d::detail::laz
