// The option table of the `city3d` command: flag, value name, help, default (printed from a
// default-constructed RunOptions, so --help never lies about defaults), and how to apply a value.
#include "city3d/options.hpp"

#include <cerrno>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <sstream>

#include "city3d/error.hpp"
#include "cli/option_table.hpp"
#include "batch/input_check.hpp"

namespace city3d {
namespace detail {
namespace {

double parse_double(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  // strtod also reads hexadecimal ("0x10"): a number here is decimal.
  if (text.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v) ||
      text.find_first_of("xX") != std::string::npos)
    throw ConfigError("option " + flag + ": '" + text + "' is not a finite number");
  return v;
}

double parse_share(const std::string& flag, const std::string& text) {
  const double v = parse_double(flag, text);
  if (!(v >= 0 && v <= 1)) throw ConfigError("option " + flag + ": '" + text + "' is not a share (0-1)");
  return v;
}

double parse_non_negative(const std::string& flag, const std::string& text) {
  const double v = parse_double(flag, text);
  if (v < 0) throw ConfigError("option " + flag + ": '" + text + "' is negative");
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

std::string yes_no(bool b) { return b ? "true" : "false"; }

std::string bbox_text(const std::optional<Box2>& box) {
  if (!box) return "";
  return number_text(box->min.x) + "," + number_text(box->min.y) + "," + number_text(box->max.x) + "," +
         number_text(box->max.y);
}

int parse_int(const std::string& flag, const std::string& text, int min_value) {
  const double v = parse_double(flag, text);
  if (v != std::floor(v) || v < min_value || v > 1e6)
    throw ConfigError("option " + flag + ": '" + text + "' is not an integer >= " + std::to_string(min_value));
  return static_cast<int>(v);
}

std::vector<std::uint8_t> parse_classes(const std::string& flag, const std::string& text) {
  std::vector<std::uint8_t> classes;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const double v = parse_double(flag, item);
    if (v != std::floor(v) || v < 0 || v > 255)
      throw ConfigError("option " + flag + ": '" + item + "' is not a LAS class (0-255)");
    classes.push_back(static_cast<std::uint8_t>(v));
  }
  if (classes.empty()) throw ConfigError("option " + flag + ": no class given");
  return classes;
}

void parse_shard(const std::string& text, int& shard, int& shards) {
  const std::size_t slash = text.find('/');
  int k = 0, n = 0;
  try {
    if (slash != std::string::npos) {
      k = parse_int("--shard", text.substr(0, slash), 1);
      n = parse_int("--shard", text.substr(slash + 1), 1);
    }
  } catch (const ConfigError&) {
    k = n = 0;
  }
  if (k < 1 || n < 1 || k > n)
    throw ConfigError("option --shard: expected K/N with 1 <= K <= N, got '" + text + "'");
  shard = k;
  shards = n;
}

std::string classes_text(const std::vector<std::uint8_t>& classes) {
  std::string s;
  for (std::uint8_t c : classes) s += (s.empty() ? "" : ",") + std::to_string(c);
  return s;
}

}  // namespace

const std::vector<OptionSpec>& option_table() {
  using O = RunOptions;
  using V = const std::string&;
  static const std::vector<OptionSpec> table = {
      // Footprints.
      {"--footprints", "-f", "PATH",
       "footprint source: any OGR vector source (GeoPackage, Shapefile, GeoJSON, SQLite) or a City3D OBJ "
       "polygon "
       "file; without it every point-cloud file is one building",
       [](const O& o) { return o.batch.footprints; }, [](O& o, V v) { o.batch.footprints = v; }},
      {"--layer", nullptr, "NAME", "footprint layer (default: the first layer with polygons)",
       [](const O& o) { return o.batch.footprint.layer; }, [](O& o, V v) { o.batch.footprint.layer = v; }},
      {"--id-field", nullptr, "NAME",
       "footprint attribute holding the building id (default: the feature id, FID)",
       [](const O& o) { return o.batch.footprint.id_field; },
       [](O& o, V v) { o.batch.footprint.id_field = v; }},
      {"--where", nullptr, "SQL", "OGR attribute filter on the footprints, e.g. \"bouwjaar > 1900\"",
       [](const O& o) { return o.batch.footprint.attribute_filter; },
       [](O& o, V v) { o.batch.footprint.attribute_filter = v; }},
      {"--bbox", nullptr, "XMIN,YMIN,XMAX,YMAX",
       "keep only footprints intersecting this box (footprint CRS; the points' CRS when the footprints are "
       "reprojected)",
       [](const O& o) { return bbox_text(o.batch.footprint.bbox); },
       [](O& o, V v) { o.batch.footprint.bbox = parse_bbox("--bbox", v); }},
      {"--ground-field", nullptr, "NAME",
       "footprint attribute with the floor height (world z); overrides the ground "
       "points where set",
       [](const O& o) { return o.batch.footprint.ground_field; },
       [](O& o, V v) { o.batch.footprint.ground_field = v; }},
      {"--max-footprint-size", nullptr, "M",
       "skip footprints wider or longer than this, metres (no building is; "
       "one such footprint would take every point of the tiles)",
       [](const O& o) { return number_text(o.batch.footprint.max_extent); },
       [](O& o, V v) {
         const double m = parse_double("--max-footprint-size", v);
         if (!(m > 0))
           throw ConfigError("option --max-footprint-size: '" + v + "' is not a size > 0 (metres)");
         o.batch.footprint.max_extent = m;
       }},
      {"--no-repair", nullptr, nullptr, "skip invalid footprints instead of repairing them with MakeValid",
       [](const O& o) { return yes_no(!o.batch.footprint.repair); },
       [](O& o, V) { o.batch.footprint.repair = false; }},
      // Cropping and heights.
      {"--building-classes", nullptr, "LIST", "LAS classes of building points (comma-separated)",
       [](const O& o) { return classes_text(o.batch.crop.building_classes); },
       [](O& o, V v) { o.batch.crop.building_classes = parse_classes("--building-classes", v); }},
      {"--ground-class", nullptr, "N", "LAS class of ground points",
       [](const O& o) { return std::to_string(o.batch.crop.ground_class); },
       [](O& o, V v) { o.batch.crop.ground_class = parse_classes("--ground-class", v).front(); }},
      {"--ignore-classes", nullptr, nullptr,
       "every point inside a footprint is a building point, every point outside them near one a ground point",
       [](const O& o) { return yes_no(o.batch.crop.use_classes == ClassUse::never); },
       [](O& o, V) { o.batch.crop.use_classes = ClassUse::never; }},
      {"--ground-buffer", nullptr, "M",
       "ground points within this distance of a footprint give its floor height",
       [](const O& o) { return number_text(o.batch.crop.ground_buffer); },
       [](O& o, V v) { o.batch.crop.ground_buffer = parse_double("--ground-buffer", v); }},
      {"--ground-percentile", nullptr, "P", "percentile (0-100) of the ground points' z taken as the floor",
       [](const O& o) { return number_text(o.batch.crop.ground_percentile); },
       [](O& o, V v) { o.batch.crop.ground_percentile = parse_double("--ground-percentile", v); }},
      {"--ground-z", nullptr, "Z", "floor height for single-building clouds (default: their lowest point)",
       [](const O& o) { return o.batch.ground_z ? number_text(*o.batch.ground_z) : std::string(); },
       [](O& o, V v) { o.batch.ground_z = parse_double("--ground-z", v); }},
      {"--min-coverage", nullptr, "SHARE",
       "a building with less of its footprint's area inside the tiles' extents is 'partial', not ok (a tile "
       "missing at a seam); less of its cells with points gives a note; 0: never",
       [](const O& o) { return number_text(o.batch.min_coverage); },
       [](O& o, V v) { o.batch.min_coverage = parse_share("--min-coverage", v); }},
      {"--min-building-coverage", nullptr, "SHARE",
       "a building whose points lie in less of its footprint's cells with points (the rest hold only other "
       "classes: a tile whose buildings are not classified, a footprint larger than the building) is "
       "'partial'; less than --min-coverage gives a note; 0: never",
       [](const O& o) { return number_text(o.batch.min_building_coverage); },
       [](O& o, V v) { o.batch.min_building_coverage = parse_share("--min-building-coverage", v); }},
      {"--crs", nullptr, "CRS",
       "the CRS of the point clouds' coordinates and heights, e.g. EPSG:7415 (RD New + NAP height: AHN) or "
       "EPSG:28992+5709; default: what the point clouds record, else the footprints' (with a warning)",
       [](const O& o) { return o.batch.crs; },
       [](O& o, V v) {
         detail::CrsFacts facts;
         try {
           facts = detail::crs_facts(v);
         } catch (const ConfigError& e) {
           throw ConfigError("option --crs: " + std::string(e.what()).substr(std::string("crs: ").size()));
         }
         if (facts.geographic)
           throw ConfigError("option --crs: '" + v + "' is geographic (degrees); city3d needs projected coordinates "
                             "in metres");
         o.batch.crs = v;
       }},
      {"--roof-percentile", nullptr, "P", "LoD1 roof height: percentile (0-100) of the building points' z",
       [](const O& o) { return number_text(o.batch.reconstruction.lod1.roof_percentile); },
       [](O& o, V v) { o.batch.reconstruction.lod1.roof_percentile = parse_double("--roof-percentile", v); }},
      // Reconstruction (the paper's parameters; see ../shared/spec/city3d_paper.tex).
      {"--lod", nullptr, "LIST",
       "levels of detail, comma-separated: 1.2 (one block), 1.3 (a block per roof-height cluster), 2.2 (the "
       "reconstructed roof), or all for the three; CityJSON holds each, OBJ/PLY the highest; 1.2 alone makes "
       "blocks without LoD2",
       [](const O& o) { return lod_set_text(o.batch.reconstruction.lods); },
       [](O& o, V v) {
         // "2" is not read as 2.2 (LoD2 has four refinements; city3d makes one of them): say which.
         std::stringstream items(v);
         for (std::string item; std::getline(items, item, ',');)
           if (item != "1.2" && item != "1.3" && item != "2.2" && item != "all")
             throw ConfigError("option --lod: '" + item + "' is not a level city3d makes: 1.2, 1.3 or 2.2" +
                               (item == "2" || item == "2.0" ? " (LoD2 here is 2.2)" : item == "1" || item == "1.0" ? " (LoD1 here is 1.2 or 1.3)" : "") +
                               "; give a comma-separated list, e.g. 1.2,2.2");
         o.batch.reconstruction.lods = parse_lod_set(v);
         o.batch.reconstruction.max_level =
             o.batch.reconstruction.lods.lod22 || o.batch.reconstruction.lods.lod13 ? ModelLevel::lod22 : ModelLevel::lod12;
       }},
      {"--scale", nullptr, "M",
       "CityJSON transform scale, and the grid every model is rounded to and checked for validity on: 0.0001 "
       "(0.1 mm, as OBJ/PLY), 0.001 (millimetres) or 0.01 (centimetres)",
       [](const O& o) { return number_text(o.batch.reconstruction.output_grid); },
       [](O& o, V v) {
         const double s = parse_double("--scale", v);
         if (s != 0.0001 && s != 0.001 && s != 0.01)
           throw ConfigError("option --scale: '" + v + "' is not 0.0001, 0.001 or 0.01");
         o.batch.reconstruction.output_grid = s;
       }},
      {"--min-points", nullptr, "N", "region growing: points per roof plane",
       [](const O& o) { return std::to_string(o.batch.reconstruction.planes.min_points); },
       [](O& o, V v) { o.batch.reconstruction.planes.min_points = parse_int("--min-points", v, 3); }},
      {"--plane-distance", nullptr, "M", "region growing: point-to-plane distance",
       [](const O& o) { return number_text(o.batch.reconstruction.planes.max_distance); },
       [](O& o, V v) { o.batch.reconstruction.planes.max_distance = parse_double("--plane-distance", v); }},
      {"--plane-angle", nullptr, "DEG", "region growing: normal deviation",
       [](const O& o) { return number_text(o.batch.reconstruction.planes.max_angle); },
       [](O& o, V v) { o.batch.reconstruction.planes.max_angle = parse_double("--plane-angle", v); }},
      {"--step-height", nullptr, "M",
       "step lines: height step between two roof planes that makes an inner wall where their points meet; 0 "
       "= no step lines",
       [](const O& o) {
         const auto& st = o.batch.reconstruction.step_lines;
         return number_text(st.enabled ? st.min_step : 0.0);
       },
       [](O& o, V v) {
         const double h = parse_double("--step-height", v);
         if (h < 0.0)
           throw ConfigError("--step-height: " + std::string(v) + " is negative (give 0 for no step lines)");
         o.batch.reconstruction.step_lines.enabled = h > 0.0;
         if (h > 0.0) o.batch.reconstruction.step_lines.min_step = h;
       }},
      {"--resolution", nullptr, "M",
       "heightmap resolution r, 0.05 to 2 m; 0 = from the point density (0.20 m at AHN3 density)",
       [](const O& o) { return number_text(o.batch.reconstruction.heightmap.resolution); },
       [](O& o, V v) { o.batch.reconstruction.heightmap.resolution = parse_double("--resolution", v); }},
      {"--eps-d", nullptr, "M", "polylines: Hausdorff distance bound eps_d",
       [](const O& o) { return number_text(o.batch.reconstruction.polylines.max_hausdorff); },
       [](O& o, V v) { o.batch.reconstruction.polylines.max_hausdorff = parse_double("--eps-d", v); }},
      {"--eps-c", nullptr, "X", "polylines: transport cost tolerance eps_c",
       [](const O& o) { return number_text(o.batch.reconstruction.polylines.max_cost); },
       [](O& o, V v) { o.batch.reconstruction.polylines.max_cost = parse_double("--eps-c", v); }},
      {"--snap-angle", nullptr, "DEG", "regularisation: near-parallel / near-orthogonal threshold",
       [](const O& o) { return number_text(o.batch.reconstruction.regularise.angle_threshold); },
       [](O& o, V v) {
         o.batch.reconstruction.regularise.angle_threshold = parse_double("--snap-angle", v);
       }},
      {"--walls", nullptr, "auto|footprint|inferred|detected",
       "vertical planes: footprint edges + inferred inner walls, all inferred, or detected wall planes",
       [](const O& o) {
         const WallMode m = o.batch.reconstruction.walls.mode;
         return std::string(m == WallMode::automatic ? "auto" : m == WallMode::footprint ? "footprint"
                            : m == WallMode::inferred ? "inferred" : "detected");
       },
       [](O& o, V v) {
         WallMode& m = o.batch.reconstruction.walls.mode;
         if (v == "auto")
           m = WallMode::automatic;
         else if (v == "footprint")
           m = WallMode::footprint;
         else if (v == "inferred")
           m = WallMode::inferred;
         else if (v == "detected")
           m = WallMode::detected;
         else
           throw ConfigError("option --walls: '" + v + "' is not auto, footprint, inferred or detected");
       }},
      {"--lambda-data", nullptr, "W", "weight of the data-fitting term",
       [](const O& o) { return number_text(o.batch.reconstruction.selection.lambda_data); },
       [](O& o, V v) { o.batch.reconstruction.selection.lambda_data = parse_double("--lambda-data", v); }},
      {"--lambda-complexity", nullptr, "W", "weight of the model-complexity term",
       [](const O& o) { return number_text(o.batch.reconstruction.selection.lambda_complexity); },
       [](O& o, V v) {
         o.batch.reconstruction.selection.lambda_complexity = parse_double("--lambda-complexity", v);
       }},
      {"--lambda-roof", nullptr, "W", "weight of the roof-preference term",
       [](const O& o) { return number_text(o.batch.reconstruction.selection.lambda_roof); },
       [](O& o, V v) { o.batch.reconstruction.selection.lambda_roof = parse_double("--lambda-roof", v); }},
      {"--lambda-unsupported", nullptr, "W",
       "weight of surface no point supports (m2 more than 1 m above the highest point within 1.5 m in plan)",
       [](const O& o) { return number_text(o.batch.reconstruction.selection.lambda_unsupported); },
       [](O& o, V v) {
         o.batch.reconstruction.selection.lambda_unsupported = parse_double("--lambda-unsupported", v);
       }},
      {"--solver", nullptr, "auto|glpk|cbc",
       "integer-program solver (auto: GLPK, then CBC where GLPK stops at its node limit)",
       [](const O& o) { return o.batch.reconstruction.selection.solver; },
       [](O& o, V v) {
         if (v != "auto" && v != "glpk" && v != "cbc")
           throw ConfigError("option --solver: '" + v + "' is not auto, glpk or cbc");
         o.batch.reconstruction.selection.solver = v;
       }},
      {"--node-limit", nullptr, "N",
       "deterministic work limit of the integer programs: branch-and-bound nodes per "
       "program (the search keeps the best selection found when it stops there; the report says so)",
       [](const O& o) { return std::to_string(o.batch.reconstruction.selection.node_limit); },
       [](O& o, V v) { o.batch.reconstruction.selection.node_limit = parse_int("--node-limit", v, 1); }},
      {"--exact-variables", nullptr, "N",
       "integer programs of more variables than this are solved by windows "
       "from the start (deterministic, not proven optimal; the report says so)",
       [](const O& o) { return std::to_string(o.batch.reconstruction.selection.max_exact_variables); },
       [](O& o, V v) {
         o.batch.reconstruction.selection.max_exact_variables = static_cast<std::size_t>(parse_int("--exact-variables", v, 1));
       }},
      {"--window-variables", nullptr, "N", "variables per window of a program solved by windows",
       [](const O& o) { return std::to_string(o.batch.reconstruction.selection.window_variables); },
       [](O& o, V v) {
         o.batch.reconstruction.selection.window_variables = static_cast<std::size_t>(parse_int("--window-variables", v, 2));
       }},
      {"--max-footprint-vertices", nullptr, "N",
       "footprints of more vertices are simplified (tolerance from 0.01 m, "
       "doubled until they fit; the report says so)",
       [](const O& o) { return std::to_string(o.batch.reconstruction.max_footprint_vertices); },
       [](O& o, V v) {
         o.batch.reconstruction.max_footprint_vertices = static_cast<std::size_t>(parse_int("--max-footprint-vertices", v, 3));
       }},
      {"--retry-share", nullptr, "F",
       "a LoD2 model leaving more than this share of the building's points farther "
       "than 1 m from it is rebuilt with variants (smaller roof planes, a wider outline, roofs for the "
       "points left "
       "out, without the face prior, "
       "half the complexity weight), and one that explains more points and fits them better is kept (the "
       "report "
       "says so); 1: never",
       [](const O& o) { return number_text(o.batch.reconstruction.retry_unexplained_share); },
       [](O& o, V v) { o.batch.reconstruction.retry_unexplained_share = parse_double("--retry-share", v); }},
      {"--retry-unsupported", nullptr, "M2",
       "a LoD2 model with more than this much surface no point supports "
       "(m2 more than 1 m above the highest point within 1.5 m in plan) is rebuilt with the same variants, "
       "and one "
       "more faithful both ways is kept (the report says so)",
       [](const O& o) { return number_text(o.batch.reconstruction.retry_unsupported_area); },
       [](O& o, V v) {
         o.batch.reconstruction.retry_unsupported_area = parse_double("--retry-unsupported", v);
       }},
      {"--time-limit", nullptr, "S",
       "opt-in wall-clock safety net per building for LoD2, seconds (then it falls back); "
       "0: none, the default. When it fires, the output depends on the machine and its load",
       [](const O& o) { return number_text(o.batch.reconstruction.time_limit); },
       [](O& o, V v) { o.batch.reconstruction.time_limit = parse_double("--time-limit", v); }},
      {"--debug", nullptr, "DIR",
       "write each building's intermediate results (planes, heightmap, edges, "
       "polylines, walls, candidate faces, models rejected as invalid) into DIR/<id>/",
       [](const O& o) { return o.batch.reconstruction.debug_dir; },
       [](O& o, V v) { o.batch.reconstruction.debug_dir = v; }},
      // Output.
      {"--output", "-o", "DIR", "output folder (created when missing)",
       [](const O& o) { return o.batch.output_dir; },
       [](O& o, V v) {
         if (std::string(v).empty()) throw ConfigError("--output: the output folder name is empty");
         o.batch.output_dir = v;
       }},
      {"--format", nullptr, "obj|ply|ply-ascii", "model file format (ply = binary little-endian)",
       [](const O& o) { return o.format; },
       [](O& o, V v) {
         o.batch.format = parse_mesh_format(v);
         o.format = v;
       }},
      {"--no-model-files", nullptr, nullptr, "do not write models/<id>.<format> per building",
       [](const O& o) { return yes_no(!o.batch.per_building_files); },
       [](O& o, V) { o.batch.per_building_files = false; }},
      {"--merged", nullptr, nullptr, "also write every building into one models.<format> file",
       [](const O& o) { return yes_no(o.batch.merged_file); }, [](O& o, V) { o.batch.merged_file = true; }},
      {"--no-cityjson", nullptr, nullptr, "do not write buildings.city.json",
       [](const O& o) { return yes_no(!o.batch.cityjson); }, [](O& o, V) { o.batch.cityjson = false; }},
      {"--cityjsonseq", nullptr, nullptr,
       "also write buildings.city.jsonl (CityJSONSeq, one building per line)",
       [](const O& o) { return yes_no(o.batch.cityjson_seq); }, [](O& o, V) { o.batch.cityjson_seq = true; }},
      {"--gpkg", nullptr, nullptr,
       "also write buildings.gpkg: the footprints with every report attribute, and each level's roof parts "
       "(lod12_2d, ...) and 3D models (lod12_3d, ...) as 3DBAG's",
       [](const O& o) { return yes_no(o.batch.gpkg); }, [](O& o, V) { o.batch.gpkg = true; }},
      {"--3dtiles", nullptr, nullptr,
       "also write 3dtiles/: a 3D Tiles 1.1 tileset (LoD1.2 far, LoD2.2 near, ids and attributes as "
       "EXT_structural_metadata) for CesiumJS and other web viewers",
       [](const O& o) { return yes_no(o.batch.tiles3d); }, [](O& o, V) { o.batch.tiles3d = true; }},
      {"--no-html", nullptr, nullptr, "do not write report.html (the run overview)",
       [](const O& o) { return yes_no(!o.batch.html); }, [](O& o, V) { o.batch.html = false; }},
      {"--timings", nullptr, nullptr,
       "add each building's seconds to its CityJSON attributes (output then differs "
       "from run to run)",
       [](const O& o) { return yes_no(o.batch.timings_in_cityjson); },
       [](O& o, V) { o.batch.timings_in_cityjson = true; }},
      {"--local-coordinates", nullptr, nullptr,
       "write local coordinates and record each building's origin, instead of world coordinates",
       [](const O& o) { return yes_no(o.batch.local_coordinates); },
       [](O& o, V) { o.batch.local_coordinates = true; }},
      // Run.
      {"--jobs", "-j", "N",
       "buildings reconstructed in parallel, and the run's records read back in parallel for its overall "
       "files (merge too); output is identical for any N",
       [](const O& o) { return std::to_string(o.batch.threads); },
       [](O& o, V v) { o.batch.threads = parse_int("--jobs", v, 1); }},
      {"--no-resume", nullptr, nullptr,
       "recompute every building, even those an interrupted earlier run into the same folder finished",
       [](const O& o) { return yes_no(!o.batch.resume); }, [](O& o, V) { o.batch.resume = false; }},
      {"--block-size", nullptr, "M",
       "footprints are processed in square blocks of this size: shards are made of them and cropping passes "
       "group them (0 = all at once; the output is the same)",
       [](const O& o) { return number_text(o.batch.block_size); },
       [](O& o, V v) { o.batch.block_size = parse_non_negative("--block-size", v); }},
      {"--group-area", nullptr, "M2",
       "consecutive blocks are cropped together, one read of their tiles, up to this much footprint area "
       "(memory follows it; 0 = one block at a time; the output is the same)",
       [](const O& o) { return number_text(o.batch.group_area); },
       [](O& o, V v) { o.batch.group_area = parse_non_negative("--group-area", v); }},
      {"--shard", nullptr, "K/N",
       "reconstruct only shard K of N (consecutive blocks in tile order, balanced by footprint area) into "
       "the "
       "output folder; "
       "`city3d merge` combines the N folders",
       [](const O& o) {
         return o.batch.shards > 0 ? std::to_string(o.batch.shard) + "/" + std::to_string(o.batch.shards)
                                   : std::string();
       },
       [](O& o, V v) { parse_shard(v, o.batch.shard, o.batch.shards); }},
      {"--strict", nullptr, nullptr,
       "exit with code 4 when any building failed or is partial, 5 when more than half share one problem",
       [](const O& o) { return yes_no(o.strict); }, [](O& o, V) { o.strict = true; }},
      {"--residuals", nullptr, "PATH",
       "evaluate: also write every point's distance to the model as CSV (x,y,z,distance)",
       [](const O& o) { return o.residuals; }, [](O& o, V v) { o.residuals = v; }},
      {"--progress", nullptr, nullptr, "progress on stderr even when it is not a terminal",
       [](const O& o) { return yes_no(o.progress == 1); }, [](O& o, V) { o.progress = 1; }},
      {"--no-progress", nullptr, nullptr, "no progress line",
       [](const O& o) { return yes_no(o.progress == 0); }, [](O& o, V) { o.progress = 0; }},
      {"--profile", nullptr, nullptr,
       "at the end of a run, the CPU seconds of each reconstruction stage summed over the buildings it "
       "reconstructed, on stderr (bench/stage_profile.py sums runs)",
       [](const O& o) { return yes_no(o.profile); }, [](O& o, V) { o.profile = true; }},
      {"--verbose", "-v", nullptr, "more messages on stderr (repeat for debug)",
       [](const O& o) { return yes_no(o.verbosity >= 2); },
       [](O& o, V) { o.verbosity = std::min(o.verbosity + 1, 3); }},
      {"--quiet", "-q", nullptr, "errors only", [](const O& o) { return yes_no(o.verbosity == 0); },
       [](O& o, V) { o.verbosity = 0; }},
      {"--config", nullptr, "FILE.toml",
       "read options from a TOML file (keys are the long options without '--'; city3d --print-config writes "
       "one); options given on the command line override it",
       [](const O& o) { return o.config_path; }, [](O& o, V v) { o.config_path = v; }},
      {"--print-config", nullptr, nullptr,
       "print every option as TOML with its effective value (the defaults, a --config file, the command "
       "line) "
       "and exit",
       [](const O& o) { return yes_no(o.print_config); }, [](O& o, V) { o.print_config = true; }},
      {"--help", "-h", nullptr, "print this help and exit", [](const O& o) { return yes_no(o.help); },
       [](O& o, V) { o.help = true; }},
      {"--version", nullptr, nullptr, "print the version and exit",
       [](const O& o) { return yes_no(o.version); }, [](O& o, V) { o.version = true; }},
  };
  return table;
}

namespace {

/// Levenshtein distance, for "did you mean".
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

}  // namespace

std::string closest_option(const std::string& key, bool config_file) {
  std::string best;
  // A third of the key's letters may differ (one for short keys): "id_field" -> "id-field".
  std::size_t best_distance = std::max<std::size_t>(1, key.size() / 3) + 1;
  for (const OptionSpec& spec : option_table()) {
    if (config_file && !in_config_file(spec)) continue;
    const std::string candidate = spec.flag + 2;
    const std::size_t d = edit_distance(key, candidate);
    if (d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  }
  return best;
}

bool in_config_file(const OptionSpec& spec) {
  const std::string flag = spec.flag;
  return flag != "--help" && flag != "--version" && flag != "--config" && flag != "--print-config";
}

std::string number_text(double v) {
  // The fewest significant digits that read back to the same double: 0.34, not 0.34000000000000002.
  // Zero is "0" whatever its sign: TOML reads "-0" as the integer 0, so --print-config would not read
  // back as it was written (found by the config fuzzer: lambda-data = -0.0).
  if (v == 0) v = 0.0;
  char buf[40];
  for (int digits = 6; digits <= 17; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

}  // namespace detail

namespace {

using detail::OptionSpec;
using detail::option_table;

const char* const kCommands[][2] = {
    {"reconstruct", "CLOUD... [-f FOOTPRINTS]  models of every footprint (or of every single-building cloud)"},
    {"evaluate", "MODEL.obj POINTS         RMSE of points to a model, face count, validity"},
    {"info", "FILE...                        what point-cloud files (LAS, LAZ, PLY) and footprint sources hold"},
    {"merge", "SHARD_DIR... -o DIR            combine the folders of every shard (--shard K/N) of a run"},
    {"help", "                               this text (as --help)"},
};

/// One option as given on the command line, before it is applied.
struct GivenOption {
  const OptionSpec* spec;
  std::string flag;   ///< as typed ("-j", "--jobs")
  std::string value;  ///< for a switch: "true" or "false" ("--strict=false" undoes a config file's "strict = true")
};

/// Applies one option, turning the option's own error into a problem line.
void apply_option(RunOptions& options, const OptionSpec& spec, const std::string& value, const std::string& where,
                  std::vector<std::string>& problems) {
  if (!spec.value_name && value == "false") return;  // a switch not given
  try {
    spec.apply(options, value);
  } catch (const ConfigError& e) {
    std::string message = e.what();
    // "option --jobs: 'x' is not ..." from a file reads "<file> line 3: jobs: 'x' is not ...".
    const std::string prefix = std::string("option ") + spec.flag + ": ";
    if (!where.empty() && message.rfind(prefix, 0) == 0) message = std::string(spec.flag + 2) + ": " + message.substr(prefix.size());
    problems.push_back(where.empty() ? message : where + ": " + message);
  }
}

}  // namespace

RunOptions parse_command_line(int argc, const char* const* argv) {
  RunOptions options;
  std::vector<std::string> problems;
  std::vector<GivenOption> given;
  std::vector<std::string> positional;
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
      // -vv, -vvv: -v repeated, as the help says.
      if (arg.size() > 2 && arg[1] == 'v' && arg.find_first_not_of('v', 1) == std::string::npos) {
        for (std::size_t k = 1; k < arg.size(); ++k)
          for (const OptionSpec& s : option_table())
            if (s.short_flag && std::string(s.short_flag) == "-v") given.push_back({&s, "-v", "true"});
        continue;
      }
      const OptionSpec* spec = nullptr;
      for (const OptionSpec& s : option_table())
        if (arg == s.flag || (s.short_flag && arg == s.short_flag)) spec = &s;
      // A short option with its value attached ("-j2", "-oout").
      if (!spec && arg.size() > 2 && arg[1] != '-')
        for (const OptionSpec& s : option_table())
          if (s.short_flag && s.value_name && arg.compare(0, 2, s.short_flag) == 0) {
            spec = &s;
            value = arg.substr(2);
            has_inline_value = true;
            arg = arg.substr(0, 2);
          }
      if (!spec) {
        const std::string near = arg.rfind("--", 0) == 0 ? detail::closest_option(arg.substr(2), false) : "";
        problems.push_back("unknown option '" + arg + "'" + (near.empty() ? "" : " (did you mean '--" + near + "'?)") +
                           " (see city3d --help)");
        continue;
      }
      if (spec->value_name && !has_inline_value) {
        if (i + 1 >= argc) {
          problems.push_back("option " + arg + " needs a value (" + spec->value_name + ")");
          continue;
        }
        value = argv[++i];
      } else if (!spec->value_name) {
        if (!has_inline_value) {
          value = "true";
        } else if (value != "true" && value != "false") {
          problems.push_back("option " + arg + " takes no value (or =true / =false)");
          continue;
        }
      }
      given.push_back({spec, arg, value});
    } else {
      positional.push_back(arg);
    }
  }

  // An option given twice takes its last value, as in most tools, except where the two values would
  // be two sets of buildings: the run models one footprint layer, and a second -f, --layer, --where or
  // --bbox used to leave the first one's buildings out without a word.
  for (const char* flag : {"--footprints", "--layer", "--where", "--bbox"}) {
    std::vector<std::string> values;
    for (const GivenOption& g : given)
      if (std::string(g.spec->flag) == flag &&
          std::find(values.begin(), values.end(), g.value) == values.end())
        values.push_back(g.value);
    if (values.size() < 2) continue;
    std::string listed;
    for (const std::string& v : values) listed += (listed.empty() ? "'" : ", '") + v + "'";
    problems.push_back(
        std::string(flag) + " given " + std::to_string(values.size()) + " times (" + listed +
        "): a run models one footprint layer and one selection of it (merge the layers first, e.g. "
        "with ogr2ogr -append, or run once per layer, each into a folder of its own)");
  }

  // The configuration file first, then the command line over it: an option given on the command
  // line replaces the file's value (and "--switch=false" the file's "switch = true").
  std::string config_path;
  for (const GivenOption& g : given)
    if (std::string(g.spec->flag) == "--config") config_path = g.value;
  std::vector<detail::ConfigEntry> config_entries;  // those not overridden
  if (!config_path.empty()) {
    try {
      for (const detail::ConfigEntry& entry : detail::read_config_file(config_path)) {
        const bool overridden = std::any_of(given.begin(), given.end(),
                                            [&](const GivenOption& g) { return g.spec == entry.spec; });
        if (overridden) continue;
        apply_option(options, *entry.spec, entry.value, "config: " + config_path + " line " + std::to_string(entry.line),
                     problems);
        config_entries.push_back(entry);
      }
    } catch (const ConfigError& e) {
      problems.push_back(e.what());
    }
  }
  for (const GivenOption& g : given) apply_option(options, *g.spec, g.value, "", problems);

  // Values that are fine one by one but out of range for a stage: the stage's message, and which
  // option (flag, or file, line and key) set the value it refuses.
  if (problems.empty()) {
    auto stages_accept = [](const RunOptions& o) {
      try {
        o.batch.reconstruction.validate();
        o.batch.crop.validate();
        return std::string();
      } catch (const ConfigError& e) {
        return std::string(e.what());
      }
    };
    const std::string refused = stages_accept(options);
    if (!refused.empty()) {
      std::vector<std::string> culprits;
      auto probe = [&](const OptionSpec& spec, const std::string& value, const std::string& name) {
        RunOptions alone;
        std::vector<std::string> ignored;
        apply_option(alone, spec, value, "", ignored);
        if (ignored.empty() && !stages_accept(alone).empty()) culprits.push_back(name);
      };
      for (const detail::ConfigEntry& entry : config_entries) probe(*entry.spec, entry.value, "config: " + config_path + " line " + std::to_string(entry.line) + ": " + entry.key);
      for (const GivenOption& g : given) probe(*g.spec, g.value, "option " + g.flag);
      std::string from;
      for (const std::string& c : culprits) from += (from.empty() ? " (set by " : "; ") + c;
      problems.push_back(refused + (from.empty() ? "" : from + ")"));
    }
  }

  for (const std::string& arg : positional) {
    if (options.command.empty()) {
      bool known = false;
      for (const auto& c : kCommands) known = known || arg == c[0];
      if (!known)
        problems.push_back("unknown command '" + arg + "' (commands: reconstruct, evaluate, info, merge, help; see city3d --help)");
      options.command = arg;
    } else {
      options.inputs.push_back(arg);
    }
  }
  if (options.command == "help") options.help = true;
  if (!options.help && !options.version && !options.print_config && problems.empty()) {
    if (options.command.empty()) problems.push_back("no command given (see city3d --help)");
    if (options.command == "info" && options.inputs.empty()) problems.push_back("info: no file given");
    if (options.command == "evaluate" && options.inputs.size() != 2)
      problems.push_back("evaluate: give a model (OBJ) and a point cloud");
    if (!options.residuals.empty() && options.command != "evaluate")
      problems.push_back("option --residuals belongs to the evaluate command");
    if (options.command == "reconstruct" && options.inputs.empty())
      problems.push_back("reconstruct: no point-cloud file or folder given");
    if (options.command == "merge" && options.inputs.empty()) problems.push_back("merge: no shard folder given");
    if (options.command != "reconstruct" && options.batch.shards > 0)
      problems.push_back("option --shard belongs to the reconstruct command");
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
    // Switches are off by default; a value without a default says so in its help.
    if (s.value_name && s.show) {
      const std::string d = s.show(defaults);
      if (!d.empty()) out << " [default: " << d << "]";
    }
    out << "\n";
  }
  out << "\nexit codes: (docs/MESSAGES.md explains them and every warning)\n"
      << "  0    the run finished and built something (some buildings may have failed: see the report)\n"
      << "  1    the run could not go on: unreadable or invalid input, an id field that is not an id, a filter\n"
      << "       that leaves no footprint, unwritable output; or it finished but built nothing (see the report)\n"
      << "  2    bad command line or --config file: unknown command or option, bad value\n"
      << "  3    internal error (a bug; please report it)\n"
      << "  4    --strict: the run finished but some buildings failed or are partial\n"
      << "  5    --strict: more than half of the buildings share one problem (the last lines name it)\n"
      << "  130  interrupted (Ctrl-C; 143 SIGTERM): the same command resumes\n";
  return out.str();
}

}  // namespace city3d
