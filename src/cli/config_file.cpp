// The TOML configuration file (--config) and its writer (--print-config), both driven by the option
// table: a key is a long option without "--", its type follows from the row (see option_table.hpp).
// Parsed with toml++, which gives every key and value its line for the messages.
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/options.hpp"
#include "cli/option_table.hpp"
#include "core/json_text.hpp"

namespace city3d {
namespace detail {
namespace {

enum class ValueType { boolean, array, number, string, number_or_string };

/// True when `text` is written as a bare TOML number that reads back as the same text: a decimal
/// integer within 64 bits or a finite float in the form number_text gives. Anything else ("\t3",
/// "0x1F", "1.50", an integer of 30 digits) is written as a quoted string, which any option taking
/// text accepts; a bare number that TOML refuses or rewrites would break the --print-config round trip.
bool is_number_text(const std::string& text) {
  if (text.empty() || text.size() > 64) return false;
  toml::table table;
  try {
    table = toml::parse("v = " + text);
  } catch (const toml::parse_error&) {
    return false;
  }
  const toml::node* node = table.get("v");
  if (node == nullptr || table.size() != 1) return false;
  if (node->is_integer()) return std::to_string(node->as_integer()->get()) == text;
  if (node->is_floating_point()) {
    const double v = node->as_floating_point()->get();
    return std::isfinite(v) && number_text(v) == text;
  }
  return false;
}

ValueType value_type(const OptionSpec& spec) {
  if (!spec.value_name) return ValueType::boolean;
  const std::string name = spec.value_name;
  if (name == "LIST" || name.find(',') != std::string::npos) return ValueType::array;
  const std::string d = spec.show ? spec.show(RunOptions{}) : std::string();
  if (d.empty()) return ValueType::number_or_string;
  return is_number_text(d) ? ValueType::number : ValueType::string;
}

const char* type_name(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a number";
    case toml::node_type::boolean: return "a boolean";
    case toml::node_type::array: return "an array";
    case toml::node_type::table: return "a table";
    default: return "a date or time";
  }
}

/// A TOML scalar as option text; false when it is no scalar of an accepted kind.
bool scalar_text(const toml::node& node, bool numbers, bool strings, std::string& text) {
  if (numbers && node.is_integer()) {
    text = std::to_string(node.as_integer()->get());
    return true;
  }
  if (numbers && node.is_floating_point()) {
    text = number_text(node.as_floating_point()->get());
    return true;
  }
  if (strings && node.is_string()) {
    text = node.as_string()->get();
    return true;
  }
  return false;
}

std::vector<ConfigEntry> read_table(const toml::table& table, const std::string& name) {
  std::vector<ConfigEntry> entries;
  std::vector<std::pair<long, std::string>> problems;  // by line: toml++ keeps keys sorted, not in file order
  for (const auto& [key_node, node] : table) {
    const std::string key(key_node.str());
    const long line = static_cast<long>(key_node.source().begin.line);
    const std::string where = "config: " + name + " line " + std::to_string(line) + ": ";
    const OptionSpec* spec = nullptr;
    for (const OptionSpec& s : option_table())
      if (in_config_file(s) && key == s.flag + 2) spec = &s;
    if (!spec) {
      std::string message = where + "unknown key '" + key + "'";
      if (node.is_table())
        message += " (a table: the file has no sections, every key is a long option without '--')";
      else if (const std::string near = closest_option(key, true); !near.empty())
        message += " (did you mean '" + near + "'?)";
      else
        message += " (keys are the long options without '--'; city3d --print-config lists them)";
      problems.emplace_back(line, message);
      continue;
    }
    const ValueType type = value_type(*spec);
    std::string text;
    bool ok = false;
    std::string expected;
    switch (type) {
      case ValueType::boolean:
        expected = "true or false";
        if (node.is_boolean()) {
          text = node.as_boolean()->get() ? "true" : "false";
          ok = true;
        }
        break;
      case ValueType::array:
        expected = "an array (e.g. [1, 2]) or a comma-separated string";
        if (const toml::array* array = node.as_array()) {
          ok = true;
          for (const toml::node& item : *array) {
            std::string part;
            if (!scalar_text(item, true, true, part)) {
              ok = false;
              expected = "an array of numbers or strings";
              break;
            }
            text += (text.empty() ? "" : ",") + part;
          }
        } else {
          ok = scalar_text(node, true, true, text);
        }
        break;
      case ValueType::number:
      case ValueType::string:
      case ValueType::number_or_string: {
        const bool numbers = type != ValueType::string, strings = type != ValueType::number;
        expected = !strings ? "a number" : !numbers ? "a string" : "a number or a string";
        ok = scalar_text(node, numbers, strings, text);
        break;
      }
    }
    if (!ok) {
      problems.emplace_back(line, where + key + " must be " + expected + ", not " + type_name(node));
      continue;
    }
    entries.push_back({spec, text, key, line});
  }
  std::sort(entries.begin(), entries.end(), [](const ConfigEntry& a, const ConfigEntry& b) { return a.line < b.line; });
  if (!problems.empty()) {
    std::stable_sort(problems.begin(), problems.end());
    std::string message;
    for (const auto& p : problems) message += (message.empty() ? "" : "\n") + p.second;
    throw ConfigError(message);
  }
  return entries;
}

/// A TOML basic string: quotes, backslashes and control characters escaped as JSON escapes them, and DEL.
std::string toml_quoted(const std::string& s) { return json_string(s, JsonEscapes::toml); }

std::string toml_value(const OptionSpec& spec, const std::string& text) {
  switch (value_type(spec)) {
    case ValueType::boolean: return text == "true" ? "true" : "false";
    case ValueType::array: {
      std::string out = "[";
      std::stringstream parts(text);
      std::string part;
      bool first = true;
      while (std::getline(parts, part, ',')) {
        out += (first ? "" : ", ") + (is_number_text(part) ? part : toml_quoted(part));
        first = false;
      }
      return out + "]";
    }
    case ValueType::number: return is_number_text(text) ? text : toml_quoted(text);
    case ValueType::number_or_string: return is_number_text(text) ? text : toml_quoted(text);
    case ValueType::string: return toml_quoted(text);
  }
  return toml_quoted(text);
}

/// What a commented-out key without a value shows: the value's name in the value's TOML shape.
std::string placeholder(const OptionSpec& spec) {
  const std::string name = spec.value_name;
  switch (value_type(spec)) {
    case ValueType::array: {
      std::string out = "[";
      for (const char c : name) out += c == ',' ? std::string(", ") : std::string(1, c);
      return out + "]";
    }
    case ValueType::string: return "\"" + name + "\"";
    case ValueType::number_or_string: return name.size() <= 3 ? name : "\"" + name + "\"";  // Z, DEG; "PATH"
    default: return name;
  }
}

/// `text` as comment lines of at most about 100 characters.
std::string comment(const std::string& text) {
  std::string out, line = "#";
  std::stringstream words(text);
  std::string word;
  while (words >> word) {
    if (line.size() + 1 + word.size() > 100 && line.size() > 1) {
      out += line + "\n";
      line = "#";
    }
    line += " " + word;
  }
  return out + line + "\n";
}

}  // namespace

std::vector<ConfigEntry> read_config_text(const std::string& text, const std::string& name) {
  toml::table table;
  try {
    table = toml::parse(text, name);
  } catch (const toml::parse_error& e) {
    const auto& begin = e.source().begin;
    throw ConfigError("config: " + name + " line " + std::to_string(begin.line) + " column " + std::to_string(begin.column) +
                      ": " + std::string(e.description()));
  }
  return read_table(table, name);
}

std::vector<ConfigEntry> read_config_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw ConfigError("config: " + path + " is a folder, not a TOML file (city3d --print-config writes one)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError("config: cannot open " + path + ": no such file or not readable");
  std::stringstream text;
  text << in.rdbuf();
  if (in.bad()) throw ConfigError("config: cannot read " + path);
  return read_config_text(text.str(), path);
}

}  // namespace detail

std::string run_parameters_json(const RunOptions& options) {
  // What does not change the outputs (where they go, how fast, what is said), and the inputs, which
  // the outputs record apart (the footprint source, its layer and id field).
  static const char* const kLeftOut[] = {"footprints", "layer",  "id-field",  "output",      "jobs",
                                         "no-resume",  "block-size", "group-area", "shard",   "strict",
                                         "residuals",  "progress",   "no-progress", "verbose", "quiet",
                                         "debug",      "profile"};
  nlohmann::ordered_json parameters = nlohmann::ordered_json::object();
  for (const detail::OptionSpec& spec : detail::option_table()) {
    if (!detail::in_config_file(spec)) continue;
    const std::string key = spec.flag + 2;
    if (std::find(std::begin(kLeftOut), std::end(kLeftOut), key) != std::end(kLeftOut)) continue;
    const std::string value = spec.show ? spec.show(options) : std::string();
    // Typed as the configuration file types it: a switch is a boolean, a list an array, a number a
    // number; an option without a value is null.
    const auto scalar = [](const std::string& text, bool numbers) {
      if (numbers && detail::is_number_text(text)) return nlohmann::ordered_json::parse(text);
      return nlohmann::ordered_json(text);
    };
    switch (detail::value_type(spec)) {
      case detail::ValueType::boolean: parameters[key] = value == "true"; break;
      case detail::ValueType::array: {
        nlohmann::ordered_json items = nlohmann::ordered_json::array();
        std::stringstream list(value);
        // --lod's levels stay text ("1.2"): they are names, not numbers.
        for (std::string item; std::getline(list, item, ',');) items.push_back(scalar(item, key != "lod"));
        parameters[key] = value.empty() ? nlohmann::ordered_json(nullptr) : items;
        break;
      }
      case detail::ValueType::number: parameters[key] = scalar(value, true); break;
      default: parameters[key] = value.empty() ? nlohmann::ordered_json(nullptr) : scalar(value, false);
    }
  }
  return parameters.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string config_text(const RunOptions& options) {
  std::ostringstream out;
  out << "# city3d " << CITY3D_VERSION << " configuration: every option of `city3d --help`, keys without '--'.\n"
      << "# Read with `city3d COMMAND --config FILE.toml`; options on the command line override these.\n"
      << "# Commented-out keys have no value (their default is in the comment above them).\n";
  for (const detail::OptionSpec& spec : detail::option_table()) {
    if (!detail::in_config_file(spec)) continue;
    const std::string key = spec.flag + 2;
    const std::string value = spec.show ? spec.show(options) : std::string();
    out << "\n" << detail::comment(std::string(spec.help) + " (" + spec.flag +
                                   (spec.value_name ? std::string(" ") + spec.value_name : std::string()) + ")");
    if (spec.value_name && value.empty())
      out << "# " << key << " = " << detail::placeholder(spec) << "\n";
    else
      out << key << " = " << detail::toml_value(spec, value) << "\n";
  }
  return out.str();
}

}  // namespace city3d
