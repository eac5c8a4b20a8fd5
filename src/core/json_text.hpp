// The one writer of quoted strings for the JSON the library writes by hand (CityJSON, whose byte
// layout is the point: cityjson_writer.cpp) and for the TOML of --config's written-back file, whose
// basic strings escape the same way; and numbers with their trailing zeros trimmed. report.json and
// report.html's data are made with nlohmann. Private to the library.
#pragma once

#include <string>
#include <string_view>

namespace city3d::detail {

/// What a quoted string escapes beyond '"' and '\\' (always written \" and \\). The outputs differ
/// and each must stay byte for byte as it was, so every writer names its own: they differ in the
/// few printable characters their context forbids.
enum class JsonEscapes {
  /// CityJSON (cityjson_writer.cpp): \n, \r and \t by their short forms, other control characters
  /// (below 0x20) as \u00XX.
  short_controls,
  /// A TOML basic string (cli/config_file.cpp): as short_controls, and DEL (0x7f) as \u007f, which
  /// TOML does not allow as it is.
  toml,
};

/// Appends `text` in double quotes to `out`, escaped as `escapes` says; every other byte, UTF-8
/// sequences included, is copied as it is.
void append_json_string(std::string& out, std::string_view text, JsonEscapes escapes);

/// `text` in double quotes, escaped as `escapes` says (as append_json_string).
std::string json_string(std::string_view text, JsonEscapes escapes);

/// Appends finite `v` rounded to `decimals` decimals (printf's "%.*f"), then without its trailing zeros
/// and point ("12.50" -> "12.5", "3.000" -> "3"), and "-0" as "0".
void append_trimmed_number(std::string& out, double v, int decimals);

}  // namespace city3d::detail
