// The option table of the `city3d` command: flag, value name, help, default (printed from a
// default-constructed RunOptions, so --help never lies about defaults), and how to apply a value.
#include "city3d/options.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <sstream>

#include "city3d/error.hpp"

namespace city3d {
namespace {

struct OptionSpec {
  const char* flag;        ///< "--footprints"
  const char* short_flag;  ///< "-f" or nullptr
  const char* value_name;  ///< "PATH", or nullptr for a switch
  const char* help;
  std::function<std::string(const RunOptions&)> show_default;  ///< empty string: no default shown
  std::function<void(RunOptions&, const std::string&)> apply;
};

double parse_double(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v))
    throw ConfigError("option " + flag + ": '" + text + "' is not a finite number");
  return v;
}

Box2 parse_bbox(const std::string& flag, const std::string& text) {
  std::vector<double> values;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) values.push_back(parse_double(flag, item));
  if (values.size() != 4 || values[0] > values[2] || values[1] > values[3])
    throw ConfigError("option " + flag + ": expected XMIN,YMIN,XMAX,YMAX with XMIN <= XMAX and YMIN <= YMAX, got '" +
                      text + "'");
  Box2 box;
  box.add({values[0], values[1]});
  box.add({values[2], values[3]});
  return box;
}

std::string quoted_or_none(const std::string& s) { return s.empty() ? "" : s; }

const std::vector<OptionSpec>& option_table() {
  static const std::vector<OptionSpec> table = {
      {"--footprints", "-f", "PATH",
       "footprint source: any OGR vector source (GeoPackage, Shapefile, GeoJSON, SQLite) or a City3D OBJ polygon file",
       nullptr, [](RunOptions& o, const std::string& v) { o.footprints = v; }},
      {"--layer", nullptr, "NAME", "footprint layer (default: the first layer with polygons)",
       [](const RunOptions& o) { return quoted_or_none(o.footprint.layer); },
       [](RunOptions& o, const std::string& v) { o.footprint.layer = v; }},
      {"--id-field", nullptr, "NAME", "footprint attribute holding the building id (default: the feature id, FID)",
       [](const RunOptions& o) { return quoted_or_none(o.footprint.id_field); },
       [](RunOptions& o, const std::string& v) { o.footprint.id_field = v; }},
      {"--where", nullptr, "SQL", "OGR attribute filter on the footprints, e.g. \"bouwjaar > 1900\"", nullptr,
       [](RunOptions& o, const std::string& v) { o.footprint.attribute_filter = v; }},
      {"--bbox", nullptr, "XMIN,YMIN,XMAX,YMAX", "keep only footprints intersecting this box (footprint CRS)", nullptr,
       [](RunOptions& o, const std::string& v) { o.footprint.bbox = parse_bbox("--bbox", v); }},
      {"--no-repair", nullptr, nullptr, "skip invalid footprints instead of repairing them with MakeValid", nullptr,
       [](RunOptions& o, const std::string&) { o.footprint.repair = false; }},
      {"--output", "-o", "DIR", "output folder (created when missing)",
       [](const RunOptions& o) { return o.output_dir; },
       [](RunOptions& o, const std::string& v) { o.output_dir = v; }},
      {"--format", nullptr, "obj|ply|ply-ascii", "model file format (ply = binary little-endian)",
       [](const RunOptions& o) { return o.format; },
       [](RunOptions& o, const std::string& v) {
         parse_mesh_format(v);  // validates
         o.format = v;
       }},
      {"--local-coordinates", nullptr, nullptr,
       "write local coordinates and record each building's origin, instead of world coordinates", nullptr,
       [](RunOptions& o, const std::string&) { o.local_coordinates = true; }},
      {"--verbose", "-v", nullptr, "more messages on stderr (repeat for debug)", nullptr,
       [](RunOptions& o, const std::string&) { o.verbosity = std::min(o.verbosity + 1, 3); }},
      {"--quiet", "-q", nullptr, "errors only", nullptr, [](RunOptions& o, const std::string&) { o.verbosity = 0; }},
      {"--help", "-h", nullptr, "print this help and exit", nullptr,
       [](RunOptions& o, const std::string&) { o.help = true; }},
      {"--version", nullptr, nullptr, "print the version and exit", nullptr,
       [](RunOptions& o, const std::string&) { o.version = true; }},
  };
  return table;
}

const char* const kCommands[][2] = {
    {"info", "FILE...          what point-cloud files (LAS, LAZ, PLY) and footprint sources hold"},
};

}  // namespace

RunOptions parse_command_line(int argc, const char* const* argv) {
  RunOptions options;
  std::vector<std::string> problems;
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg.size() > 1 && arg[0] == '-') {
      std::string value;
      bool has_inline_value = false;
      if (const auto eq = arg.find('='); arg.rfind("--", 0) == 0 && eq != std::string::npos) {
        value = arg.substr(eq + 1);
        arg = arg.substr(0, eq);
        has_inline_value = true;
      }
      const OptionSpec* spec = nullptr;
      for (const OptionSpec& s : option_table())
        if (arg == s.flag || (s.short_flag && arg == s.short_flag)) spec = &s;
      if (!spec) {
        problems.push_back("unknown option '" + arg + "' (see city3d --help)");
        continue;
      }
      if (spec->value_name && !has_inline_value) {
        if (i + 1 >= argc) {
          problems.push_back("option " + arg + " needs a value (" + spec->value_name + ")");
          continue;
        }
        value = argv[++i];
      } else if (!spec->value_name && has_inline_value) {
        problems.push_back("option " + arg + " takes no value");
        continue;
      }
      try {
        spec->apply(options, value);
      } catch (const ConfigError& e) {
        problems.push_back(e.what());
      }
    } else if (options.command.empty()) {
      bool known = false;
      for (const auto& c : kCommands) known = known || arg == c[0];
      if (!known) problems.push_back("unknown command '" + arg + "' (commands: info; see city3d --help)");
      options.command = arg;
    } else {
      options.inputs.push_back(arg);
    }
  }
  if (!options.help && !options.version && problems.empty()) {
    if (options.command.empty()) problems.push_back("no command given (see city3d --help)");
    if (options.command == "info" && options.inputs.empty()) problems.push_back("info: no file given");
  }
  if (!problems.empty()) {
    std::string message;
    for (const std::string& p : problems) message += (message.empty() ? "" : "\n") + p;
    throw ConfigError(message);
  }
  return options;
}

std::string help_text() {
  std::ostringstream out;
  out << "city3d " << CITY3D_VERSION
      << ": compact, watertight LoD2 building models from airborne LiDAR and footprints\n\n"
      << "usage: city3d COMMAND [options] [inputs]\n\ncommands:\n";
  for (const auto& c : kCommands) out << "  " << c[0] << " " << c[1] << "\n";
  out << "\noptions:\n";
  const RunOptions defaults;
  for (const OptionSpec& s : option_table()) {
    std::string left = "  ";
    left += s.short_flag ? std::string(s.short_flag) + ", " : "    ";
    left += s.flag;
    if (s.value_name) left += std::string(" ") + s.value_name;
    out << left;
    if (left.size() < 34)
      out << std::string(34 - left.size(), ' ');
    else
      out << "\n" << std::string(34, ' ');
    out << s.help;
    if (s.show_default) {
      const std::string d = s.show_default(defaults);
      out << " [default: " << (d.empty() ? "none" : d) << "]";
    }
    out << "\n";
  }
  out << "\nexit codes:\n"
      << "  0  the run finished\n"
      << "  1  the run could not go on: unreadable or invalid input, unwritable output\n"
      << "  2  bad command line: unknown command or option, bad value\n"
      << "  3  internal error (a bug; please report it)\n";
  return out.str();
}

}  // namespace city3d
