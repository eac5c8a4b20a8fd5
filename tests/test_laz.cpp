// Tests of the LASzip decoder: every LAS/LAZ pair in shared/data/laz decodes to the exact bytes of
// its .las twin, the AHN3 tiles decode, and every deliberately broken file is rejected cleanly.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "city3d/error.hpp"
#include "laz/laz_decoder.hpp"

namespace {

namespace fs = std::filesystem;
using city3d::IoError;
using city3d::detail::LaszipVlr;
using city3d::detail::LazDecoder;
using city3d::detail::LazLayout;

const std::string kLazDir = std::string(CITY3D_SHARED_DATA) + "/laz";
const std::string kAhnDir = std::string(CITY3D_SHARED_DATA) + "/ahn3_delft";

std::vector<std::uint8_t> read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("test: cannot open " + path);
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), {});
}

template <typename T>
T field(const std::vector<std::uint8_t>& bytes, std::size_t offset) {
  if (offset + sizeof(T) > bytes.size()) throw std::runtime_error("test: header field past end of file");
  T v;
  std::memcpy(&v, bytes.data() + offset, sizeof v);
  return v;
}

/// The few LAS header fields the decoder needs, read the way the LAS reader will.
struct LasHeader {
  std::uint8_t version_minor = 0;
  std::uint16_t header_size = 0;
  std::uint32_t point_data_offset = 0;
  std::uint32_t vlr_count = 0;
  std::uint8_t point_format_byte = 0;
  std::uint16_t record_length = 0;
  std::uint64_t point_count = 0;
};

LasHeader read_header(const std::vector<std::uint8_t>& bytes) {
  LasHeader h;
  h.version_minor = field<std::uint8_t>(bytes, 25);
  h.header_size = field<std::uint16_t>(bytes, 94);
  h.point_data_offset = field<std::uint32_t>(bytes, 96);
  h.vlr_count = field<std::uint32_t>(bytes, 100);
  h.point_format_byte = field<std::uint8_t>(bytes, 104);
  h.record_length = field<std::uint16_t>(bytes, 105);
  h.point_count = field<std::uint32_t>(bytes, 107);
  if (h.version_minor >= 4 && h.header_size >= 255) h.point_count = field<std::uint64_t>(bytes, 247);
  return h;
}

/// Walks the VLRs after the header and parses the LASzip one, if any.
std::optional<LaszipVlr> find_laszip_vlr(const std::vector<std::uint8_t>& bytes, const LasHeader& h,
                                         const std::string& path) {
  constexpr std::size_t kVlrHeaderSize = 54;
  std::size_t at = h.header_size;
  for (std::uint32_t i = 0; i < h.vlr_count; ++i) {
    if (at + kVlrHeaderSize > bytes.size()) throw std::runtime_error("test: VLR header past end of file");
    const std::string user_id(reinterpret_cast<const char*>(bytes.data() + at + 2),
                              strnlen(reinterpret_cast<const char*>(bytes.data() + at + 2), 16));
    const auto record_id = field<std::uint16_t>(bytes, at + 18);
    const auto length = field<std::uint16_t>(bytes, at + 20);
    if (at + kVlrHeaderSize + length > bytes.size()) throw std::runtime_error("test: VLR past end of file");
    if (user_id == "laszip encoded" && record_id == 22204) {
      return city3d::detail::parse_laszip_vlr(bytes.data() + at + kVlrHeaderSize, length, path);
    }
    at += kVlrHeaderSize + length;
  }
  return std::nullopt;
}

/// A decoder over a LAZ file, with the header it was made from.
struct OpenedLaz {
  LasHeader header;
  std::unique_ptr<LazDecoder> decoder;
};

OpenedLaz open_laz(const std::string& path) {
  const auto bytes = read_file(path);
  const LasHeader h = read_header(bytes);
  const auto vlr = find_laszip_vlr(bytes, h, path);
  city3d::detail::check_laszip_vlr_present(vlr.has_value(), h.point_format_byte, path);
  if (!vlr) throw std::runtime_error("test: " + path + " is not compressed");
  LazLayout layout;
  layout.path = path;
  layout.point_data_offset = h.point_data_offset;
  layout.point_count = h.point_count;
  layout.record_length = h.record_length;
  layout.point_format = h.point_format_byte & 0x3F;
  layout.file_size = bytes.size();
  return {h, std::make_unique<LazDecoder>(*vlr, layout)};
}

/// Decodes every record of a LAZ file, `batch` records per call.
std::vector<std::uint8_t> decode_laz(const std::string& path, std::size_t batch = 1u << 30) {
  const OpenedLaz laz = open_laz(path);
  const LasHeader& h = laz.header;
  LazDecoder& decoder = *laz.decoder;
  std::vector<std::uint8_t> out;
  std::vector<std::uint8_t> buffer(std::min<std::uint64_t>(batch, h.point_count + 1) * h.record_length);
  const std::size_t max_calls = h.point_count / std::max<std::size_t>(batch, 1) + 3;  // never loop forever
  for (std::size_t call = 0; call < max_calls; ++call) {
    const std::size_t n = decoder.decode(buffer.data(), buffer.size() / h.record_length);
    if (n == 0) return out;
    out.insert(out.end(), buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(n * h.record_length));
  }
  throw std::runtime_error("test: decoder of " + path + " did not stop");
}

/// The point block of an uncompressed LAS file.
std::vector<std::uint8_t> las_point_block(const std::string& path) {
  const auto bytes = read_file(path);
  const LasHeader h = read_header(bytes);
  const std::uint64_t size = h.point_count * h.record_length;
  if (h.point_data_offset + size > bytes.size())
    throw std::runtime_error("test: " + path + " point block truncated");
  return std::vector<std::uint8_t>(bytes.begin() + h.point_data_offset,
                                   bytes.begin() + static_cast<std::ptrdiff_t>(h.point_data_offset + size));
}

/// Index of the first differing record, for readable failures.
std::string first_difference(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b,
                             std::size_t record_length) {
  if (a.size() != b.size()) return "sizes " + std::to_string(a.size()) + " vs " + std::to_string(b.size());
  const auto mismatch = std::mismatch(a.begin(), a.end(), b.begin());
  if (mismatch.first == a.end()) return "identical";
  const auto byte = static_cast<std::size_t>(mismatch.first - a.begin());
  return "record " + std::to_string(byte / record_length) + " byte " + std::to_string(byte % record_length);
}

void expect_identical(const std::string& laz, const std::string& las, std::size_t batch = 1u << 30) {
  const auto decoded = decode_laz(laz, batch);
  const auto expected = las_point_block(las);
  const auto record_length = read_header(read_file(las)).record_length;
  EXPECT_TRUE(decoded == expected) << laz << ": " << first_difference(decoded, expected, record_length);
}

/// Case names, in manifest order: the LAS/LAZ pairs, not the broken files.
std::vector<std::string> manifest_case_names() {
  if (!fs::exists(kLazDir + "/manifest.json")) return {};  // no ../shared/data: the LazManifest test says so
  const auto bytes = read_file(kLazDir + "/manifest.json");
  const nlohmann::json manifest = nlohmann::json::parse(bytes.begin(), bytes.end());
  std::vector<std::string> names;
  for (const nlohmann::json& pair : manifest.at("pairs")) names.push_back(pair.at("name").get<std::string>());
  return names;
}

/// Cases this decoder does not read yet, with the reason.
const std::map<std::string, std::string> kSkippedCases = {};

class LazCase : public ::testing::TestWithParam<std::string> {};

TEST_P(LazCase, decodes_byte_identically_to_its_las_twin) {
  const std::string name = GetParam();
  const auto skipped = kSkippedCases.find(name);
  if (skipped != kSkippedCases.end()) GTEST_SKIP() << name << ": " << skipped->second;
  expect_identical(kLazDir + "/cases/" + name + ".laz", kLazDir + "/cases/" + name + ".las");
}

INSTANTIATE_TEST_SUITE_P(Manifest, LazCase, ::testing::ValuesIn(manifest_case_names()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string s = info.param;
                           std::replace(s.begin(), s.end(), '-', '_');
                           return s;
                         });

TEST(LazManifest, lists_every_pair_in_the_cases_directory) {
  const auto names = manifest_case_names();
  const std::set<std::string> listed(names.begin(), names.end());
  std::set<std::string> on_disk;
  for (const auto& entry : fs::directory_iterator(kLazDir + "/cases")) {
    if (entry.path().extension() == ".laz") on_disk.insert(entry.path().stem().string());
  }
  EXPECT_EQ(listed, on_disk);
  EXPECT_EQ(names.size(), 26u);
}

TEST(LazAhn3, cropped_tile_1_decodes_its_640510_records_byte_identically) {
  const auto decoded = decode_laz(kAhnDir + "/ahn3_cropped_1.laz");
  EXPECT_EQ(decoded.size(), 640510u * 28u);
  expect_identical(kAhnDir + "/ahn3_cropped_1.laz", kAhnDir + "/ahn3_cropped_1.las");
}

TEST(LazAhn3, cropped_tile_2_decodes_its_208432_records_byte_identically) {
  const auto decoded = decode_laz(kAhnDir + "/ahn3_cropped_2.laz");
  EXPECT_EQ(decoded.size(), 208432u * 28u);
  expect_identical(kAhnDir + "/ahn3_cropped_2.laz", kAhnDir + "/ahn3_cropped_2.las");
}

TEST(LazStreaming, decoding_in_calls_of_1000_records_gives_the_same_bytes_as_one_call) {
  for (const std::string name : {"las12_pf3_autzen_trim_3chunks", "las12_pf3_varchunk", "las14_pf6_varchunk",
                                 "las14_pf7_copc_varchunk_real", "las14_pf8_eb3_real_1chunk"}) {
    const std::string laz = kLazDir + "/cases/" + name + ".laz";
    EXPECT_EQ(decode_laz(laz, 1000), decode_laz(laz)) << name;
  }
  EXPECT_EQ(decode_laz(kAhnDir + "/ahn3_cropped_2.laz", 1000),
            las_point_block(kAhnDir + "/ahn3_cropped_2.las"));
}

TEST(LazStreaming, decoding_one_record_per_call_crosses_chunk_boundaries) {
  const std::string laz = kLazDir + "/cases/las14_pf6_varchunk.laz";
  EXPECT_EQ(decode_laz(laz, 1), las_point_block(kLazDir + "/cases/las14_pf6_varchunk.las"));
}

/// Decodes a LAZ file with decode_chunk() on `threads` threads at once, each taking every
/// threads-th chunk from the last to the first, so chunks finish in no particular order.
std::vector<std::uint8_t> decode_laz_by_chunks(const std::string& path, unsigned threads) {
  const OpenedLaz laz = open_laz(path);
  const LazDecoder& decoder = *laz.decoder;
  const std::size_t record = laz.header.record_length;
  std::vector<std::size_t> first_record(decoder.chunk_count() + 1, 0);
  for (std::size_t i = 0; i < decoder.chunk_count(); ++i)
    first_record[i + 1] = first_record[i] + decoder.chunk_points(i);
  std::vector<std::uint8_t> out(first_record.back() * record);
  std::vector<std::string> errors(threads);
  std::vector<std::thread> workers;
  for (unsigned t = 0; t < threads; ++t) {
    workers.emplace_back([&, t] {
      try {
        for (std::size_t i = decoder.chunk_count(); i-- > 0;)
          if (i % threads == t) decoder.decode_chunk(i, out.data() + first_record[i] * record);
      } catch (const IoError& e) {
        errors[t] = e.what();
      }
    });
  }
  for (auto& w : workers) w.join();
  for (const auto& e : errors)
    if (!e.empty()) throw IoError(e);
  return out;
}

TEST(LazChunks, every_case_decodes_byte_identically_chunk_by_chunk_on_1_2_and_4_threads) {
  for (const auto& name : manifest_case_names()) {
    const std::string laz = kLazDir + "/cases/" + name + ".laz";
    const auto expected = las_point_block(kLazDir + "/cases/" + name + ".las");
    for (const unsigned threads : {1u, 2u, 4u})
      EXPECT_TRUE(decode_laz_by_chunks(laz, threads) == expected) << name << " on " << threads << " threads";
  }
}

TEST(LazChunks, both_ahn3_tiles_decode_byte_identically_chunk_by_chunk_on_1_2_and_4_threads) {
  for (const std::string tile : {"ahn3_cropped_1", "ahn3_cropped_2"}) {
    const auto expected = las_point_block(kAhnDir + "/" + tile + ".las");
    for (const unsigned threads : {1u, 2u, 4u}) {
      EXPECT_TRUE(decode_laz_by_chunks(kAhnDir + "/" + tile + ".laz", threads) == expected)
          << tile << " on " << threads << " threads";
    }
  }
}

TEST(LazChunks, chunk_points_add_up_to_the_header_count) {
  const OpenedLaz tile = open_laz(kAhnDir + "/ahn3_cropped_1.laz");
  ASSERT_EQ(tile.decoder->chunk_count(), 13u);  // 640510 points in chunks of 50000
  std::uint64_t total = 0;
  for (std::size_t i = 0; i < tile.decoder->chunk_count(); ++i) total += tile.decoder->chunk_points(i);
  EXPECT_EQ(total, 640510u);
  EXPECT_EQ(tile.decoder->chunk_points(12), 40510u);
  EXPECT_EQ(open_laz(kLazDir + "/cases/las12_pf3_simple_compressor1_v1.laz").decoder->chunk_count(), 1u);
  EXPECT_EQ(open_laz(kLazDir + "/cases/las14_pf7_zero_points.laz").decoder->chunk_count(), 0u);
}

/// Copies a LAZ case to a temporary file with one byte flipped in the middle of chunk `chunk`.
std::string corrupt_copy(const std::string& name, std::size_t chunk) {
  const std::string source = kLazDir + "/cases/" + name + ".laz";
  auto bytes = read_file(source);
  const OpenedLaz laz = open_laz(source);
  std::vector<std::uint8_t> intact(laz.decoder->chunk_points(chunk) * laz.header.record_length);
  laz.decoder->decode_chunk(chunk, intact.data());  // the chunk decodes before the damage
  const fs::path dir = fs::temp_directory_path() / ("city3d_laz_chunks_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / (name + "_chunk" + std::to_string(chunk) + ".laz")).string();
  // equal chunks of similar size: the middle of chunk k lies near (k + 0.5) / count of the data
  // (the test below checks that the error names the chunk)
  const std::size_t data_start = laz.header.point_data_offset + 8;
  const std::size_t data_end = bytes.size() - 64;
  const std::size_t at =
      data_start + (data_end - data_start) * (2 * chunk + 1) / (2 * laz.decoder->chunk_count());
  for (std::size_t i = 0; i < 16; ++i) bytes[at + i] ^= 0x5A;
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  return path;
}

TEST(LazChunks, a_corrupt_chunk_gives_the_same_error_chunk_by_chunk_as_streaming) {
  const std::string path = corrupt_copy("las14_pf6_rand_20k_chunk5000", 2);
  std::string streaming, chunked;
  try {
    decode_laz(path, 1000);
  } catch (const IoError& e) {
    streaming = e.what();
  }
  try {
    decode_laz_by_chunks(path, 4);
  } catch (const IoError& e) {
    chunked = e.what();
  }
  fs::remove_all(fs::path(path).parent_path());
  EXPECT_NE(streaming.find("chunk 2 of 4"), std::string::npos) << streaming;
  EXPECT_NE(streaming.find("las14_pf6_rand_20k_chunk5000_chunk2.laz"), std::string::npos) << streaming;
  EXPECT_EQ(chunked, streaming);
}

/// Decoding `file` must end in an IoError naming the file and containing every word of `words`.
void expect_rejected(const std::string& file, const std::vector<std::string>& words) {
  const std::string path = kLazDir + "/broken/" + file;
  try {
    decode_laz(path, 1000);
    ADD_FAILURE() << file << " was decoded without an error";
  } catch (const IoError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(file), std::string::npos) << message;
    for (const auto& word : words)
      EXPECT_NE(message.find(word), std::string::npos) << "'" << word << "' not in: " << message;
    // chunk by chunk on four threads: the same error
    try {
      decode_laz_by_chunks(path, 4);
      ADD_FAILURE() << file << " was decoded chunk by chunk without an error";
    } catch (const IoError& chunked) {
      EXPECT_EQ(std::string(chunked.what()), message);
    }
  }
}

TEST(LazBroken, rejects_a_v2_file_truncated_mid_chunk) {
  expect_rejected("broken_truncated_v2_midchunk.laz", {"bad chunk table", "out of range"});
}

TEST(LazBroken, rejects_a_v3_file_truncated_mid_chunk) {
  expect_rejected("broken_truncated_v3_midchunk.laz", {"bad chunk table", "out of range"});
}

TEST(LazBroken, rejects_a_chunk_table_pointer_past_the_end_of_the_file) {
  expect_rejected("broken_chunktable_ptr_past_eof.laz", {"bad chunk table", "1039794", "out of range"});
}

TEST(LazBroken, rejects_a_missing_chunk_table) {
  expect_rejected("broken_chunktable_missing.laz", {"chunk table missing", "interrupted"});
}

TEST(LazBroken, rejects_the_compression_bit_without_a_laszip_vlr) {
  expect_rejected("broken_no_laszip_vlr.laz", {"compression bit", "no LASzip VLR"});
}

TEST(LazBroken, rejects_corrupt_v2_bytes_naming_the_chunk) {
  expect_rejected("broken_corrupt_v2_bytes.laz", {"chunk 0 of 1", "corrupt or truncated data"});
}

TEST(LazBroken, rejects_corrupt_v3_bytes_naming_the_chunk) {
  expect_rejected("broken_corrupt_v3_bytes.laz", {"chunk 0 of 1", " layer (", "corrupt or truncated data"});
}

TEST(LazBroken, rejects_a_point_count_larger_than_the_data) {
  expect_rejected("broken_point_count_exceeds.laz", {"chunk 0 of 1", "corrupt or truncated data"});
}

TEST(LazBroken, rejects_an_item_size_that_does_not_fit_the_item_or_the_record_length) {
  // RGB12 was changed from 6 to 8 bytes: the fixed item size is checked before the sum (36 vs 34)
  expect_rejected("broken_item_size_mismatch.laz", {"RGB12 has size 8", "expected 6"});
}

TEST(LazBroken, every_broken_file_has_a_test) {
  std::set<std::string> on_disk;
  for (const auto& entry : fs::directory_iterator(kLazDir + "/broken")) {
    if (entry.path().extension() == ".laz") on_disk.insert(entry.path().filename().string());
  }
  EXPECT_EQ(on_disk.size(), 9u);
}

/// Flips random bytes after the header of a valid file, many times over: every outcome must be
/// either the full point count or an IoError (no crash, no hang, no other exception).
void expect_mutations_handled(const std::string& name, std::uint32_t seed, int rounds,
                              bool expect_rejections = true) {
  const std::string source = kLazDir + "/cases/" + name + ".laz";
  const auto original = read_file(source);
  const LasHeader h = read_header(original);
  const fs::path dir = fs::temp_directory_path() / ("city3d_laz_mutations_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / (name + ".laz")).string();
  std::uint32_t state = seed;
  auto next = [&state] {  // xorshift32: fixed sequence, independent of the standard library
    state ^= state << 13;
    state ^= state >> 17;
    state ^= state << 5;
    return state;
  };
  int rejected = 0;
  for (int round = 0; round < rounds; ++round) {
    auto bytes = original;
    const std::size_t span = bytes.size() - h.point_data_offset;
    const int flips = 1 + static_cast<int>(next() % 8);
    for (int f = 0; f < flips; ++f)
      bytes[h.point_data_offset + next() % span] ^= static_cast<std::uint8_t>(1 + next() % 255);
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    try {
      const auto decoded = decode_laz(path, 1000);
      EXPECT_EQ(decoded.size(), h.point_count * h.record_length) << name << " round " << round;
    } catch (const IoError& e) {
      ++rejected;
      EXPECT_NE(std::string(e.what()).find(name + ".laz"), std::string::npos) << e.what();
    }
  }
  fs::remove_all(dir);
  if (expect_rejections) EXPECT_GT(rejected, 0) << name << ": no mutation was detected";
}

TEST(LazRobustness, random_byte_flips_in_v2_data_end_in_points_or_an_error) {
  expect_mutations_handled("las12_pf3_varchunk", 12345u, 150);
  expect_mutations_handled("las12_pf3_extrabytes27", 777u, 100);
}

TEST(LazRobustness, random_byte_flips_in_a_compressor_1_stream_end_in_points_or_an_error) {
  // compressor 1 has no chunk sizes to check against, so damage may go undetected: only "no crash"
  expect_mutations_handled("las12_pf3_simple_compressor1_v1", 2024u, 100, false);
}

TEST(LazRobustness, random_byte_flips_in_v3_data_end_in_points_or_an_error) {
  expect_mutations_handled("las14_pf7_copc_varchunk_real", 4242u, 150);
  expect_mutations_handled("las14_pf6_rand_20k_chunk5000", 99u, 40);
  expect_mutations_handled("las14_pf8_eb3_real_1chunk", 31337u, 40);
}

TEST(LazLayoutCheck, rejects_items_that_do_not_match_the_point_format) {
  const std::string path = kLazDir + "/cases/las12_pf3_simple.laz";
  const auto bytes = read_file(path);
  const LasHeader h = read_header(bytes);
  const auto vlr = find_laszip_vlr(bytes, h, path);
  ASSERT_TRUE(vlr.has_value());
  LazLayout layout;
  layout.path = path;
  layout.point_data_offset = h.point_data_offset;
  layout.point_count = h.point_count;
  layout.record_length = h.record_length;
  layout.point_format = 1;  // the file is PF3: POINT10 + GPSTIME11 + RGB12 = 34 bytes, PF1 has 28
  try {
    LazDecoder decoder(*vlr, layout);
    ADD_FAILURE() << "accepted PF3 items for point format 1";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("34-byte points but point format 1 has 28 bytes"), std::string::npos)
        << e.what();
  }
}

/// A LASzip VLR payload with the given items (type, size, version).
std::vector<std::uint8_t> make_vlr(std::uint16_t compressor, const std::vector<LaszipVlr::Item>& items) {
  std::vector<std::uint8_t> v(34 + 6 * items.size(), 0);
  auto put16 = [&](std::size_t at, std::uint16_t x) { std::memcpy(v.data() + at, &x, 2); };
  put16(0, compressor);
  const std::uint32_t chunk_size = 50000;
  std::memcpy(v.data() + 12, &chunk_size, 4);
  put16(32, static_cast<std::uint16_t>(items.size()));
  for (std::size_t i = 0; i < items.size(); ++i) {
    put16(34 + 6 * i, items[i].type);
    put16(36 + 6 * i, items[i].size);
    put16(38 + 6 * i, items[i].version);
  }
  return v;
}

TEST(LazVlr, parses_compressor_chunk_size_and_items) {
  const auto bytes = make_vlr(2, {{6, 20, 2}, {7, 8, 2}});
  const LaszipVlr vlr = city3d::detail::parse_laszip_vlr(bytes.data(), bytes.size(), "x.laz");
  EXPECT_EQ(vlr.compressor, 2);
  EXPECT_EQ(vlr.chunk_size, 50000u);
  ASSERT_EQ(vlr.items.size(), 2u);
  EXPECT_EQ(vlr.items[1].type, 7);
  EXPECT_EQ(vlr.items[1].size, 8);
  EXPECT_EQ(vlr.items[1].version, 2);
}

TEST(LazVlr, rejects_an_unknown_item_type_naming_the_file) {
  const auto bytes = make_vlr(2, {{6, 20, 2}, {99, 4, 2}});
  try {
    city3d::detail::parse_laszip_vlr(bytes.data(), bytes.size(), "tile.laz");
    ADD_FAILURE() << "accepted item type 99";
  } catch (const IoError& e) {
    EXPECT_STREQ(e.what(), "laz: tile.laz: unknown item type 99 version 2 in LASzip VLR");
  }
}

TEST(LazVlr, rejects_a_size_that_does_not_match_the_item_count) {
  auto bytes = make_vlr(2, {{6, 20, 2}});
  bytes.push_back(0);
  EXPECT_THROW(city3d::detail::parse_laszip_vlr(bytes.data(), bytes.size(), "tile.laz"), IoError);
}

TEST(LazVlr, rejects_an_unknown_compressor_and_a_wrong_fixed_item_size) {
  const auto compressor = make_vlr(7, {{6, 20, 2}});
  EXPECT_THROW(city3d::detail::parse_laszip_vlr(compressor.data(), compressor.size(), "t.laz"), IoError);
  const auto size = make_vlr(2, {{6, 22, 2}});
  EXPECT_THROW(city3d::detail::parse_laszip_vlr(size.data(), size.size(), "t.laz"), IoError);
}

TEST(LazVlr, compression_bit_check_accepts_uncompressed_files_without_a_vlr) {
  EXPECT_NO_THROW(city3d::detail::check_laszip_vlr_present(false, 3, "plain.las"));
  EXPECT_THROW(city3d::detail::check_laszip_vlr_present(false, 0x83, "tile.laz"), IoError);
  EXPECT_NO_THROW(city3d::detail::check_laszip_vlr_present(true, 0x83, "tile.laz"));
}

}  // namespace
