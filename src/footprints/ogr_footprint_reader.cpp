// Footprints from any GDAL/OGR vector source (GeoPackage, Shapefile, GeoJSON, SQLite, ...), and the
// dispatch of read_footprints() / list_footprint_layers() between the OGR and OBJ readers.
#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_vsi.h>
#include <gdal.h>
#include <gdal_priv.h>
#include <ogr_geometry.h>
#include <ogr_spatialref.h>
#include <ogrsf_frmts.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/footprint_io.hpp"
#include "city3d/log.hpp"
#include "footprints/footprint_readers.hpp"

namespace city3d {
namespace detail {
namespace {

constexpr const char* kModule = "footprints: ";

void register_drivers_once() {
  static std::once_flag once;
  std::call_once(once, [] { GDALAllRegister(); });
}

/// While alive, GDAL's messages on this thread go to a quiet handler instead of stderr; we read
/// them back with CPLGetLastErrorMsg() and put them into our own messages. The handler stack is
/// thread-local in GDAL, so concurrent readers do not disturb each other.
class QuietGdalErrors {
 public:
  QuietGdalErrors() {
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
  }
  ~QuietGdalErrors() { CPLPopErrorHandler(); }
  QuietGdalErrors(const QuietGdalErrors&) = delete;
  QuietGdalErrors& operator=(const QuietGdalErrors&) = delete;
};

/// GDAL's last message on this thread, as " (GDAL: ...)", or empty.
std::string gdal_message() {
  const char* msg = CPLGetLastErrorMsg();
  if (msg == nullptr || *msg == '\0') return {};
  return std::string(" (GDAL: ") + msg + ")";
}

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& name : names) {
    if (!out.empty()) out += ", ";
    out += name;
  }
  return out.empty() ? "none" : out;
}

bool iequals(const std::string& a, const std::string& b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

bool path_exists(const std::string& path) {
  VSIStatBufL stat;
  return VSIStatExL(path.c_str(), &stat, VSI_STAT_EXISTS_FLAG) == 0;
}

GDALDatasetUniquePtr open_vector(const std::string& path) {
  register_drivers_once();
  CPLErrorReset();
  GDALDatasetUniquePtr dataset(GDALDataset::Open(
      path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY | GDAL_OF_VERBOSE_ERROR, nullptr, nullptr, nullptr));
  if (dataset) {
    // A Shapefile without its .dbf opens, with no attributes: its ids and fields are lost without a word.
    if (std::string(dataset->GetDriverName()) == "ESRI Shapefile" && path.size() > 4) {
      std::string stem = path.substr(0, path.size() - 4), extension = path.substr(path.size() - 4);
      std::transform(extension.begin(), extension.end(), extension.begin(),
                     [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
      if (extension == ".shp" && !path_exists(stem + ".dbf") && !path_exists(stem + ".DBF"))
        throw IoError(kModule + path + " has no " + stem +
                      ".dbf beside it: a Shapefile's attributes (its ids) are "
                      "there; give the .dbf too");
    }
    return dataset;
  }
  // Existence is checked after the attempt, not before: an OGR source need not be a local file
  // ("PG:dbname=...", "/vsizip/..."); VSIStatExL understands the /vsi prefixes too.
  if (!path_exists(path)) throw IoError(kModule + std::string("cannot open ") + path + ": no such file");
  throw IoError(kModule + std::string("cannot open ") + path + ": not a vector source" + gdal_message());
}

std::vector<std::string> layer_names(GDALDataset& dataset) {
  std::vector<std::string> names;
  for (OGRLayer* layer : dataset.GetLayers()) names.emplace_back(layer->GetName());
  return names;
}

bool is_polygonal(OGRwkbGeometryType type) {
  switch (wkbFlatten(type)) {
    case wkbPolygon:
    case wkbMultiPolygon:
    case wkbCurvePolygon:
    case wkbMultiSurface:
      return true;
    default:
      return false;
  }
}

/// A declared layer type that may still hold polygons (GeoJSON and CSV layers with mixed or
/// unknown geometry types declare "Unknown").
bool may_hold_polygons(OGRwkbGeometryType type) {
  const OGRwkbGeometryType flat = wkbFlatten(type);
  return is_polygonal(type) || flat == wkbUnknown || flat == wkbGeometryCollection;
}

/// True when some feature of the layer (with whatever filters are set) has a non-empty polygon.
bool layer_has_polygon_feature(OGRLayer& layer) {
  layer.ResetReading();
  for (const auto& feature : layer) {
    const OGRGeometry* geometry = feature->GetGeometryRef();
    if (geometry != nullptr && !geometry->IsEmpty() && is_polygonal(geometry->getGeometryType())) {
      layer.ResetReading();
      return true;
    }
  }
  layer.ResetReading();
  return false;
}

OGRLayer& select_layer(GDALDataset& dataset, const std::string& path, const std::string& name) {
  if (!name.empty()) {
    OGRLayer* layer = dataset.GetLayerByName(name.c_str());
    if (layer == nullptr) {
      throw IoError(kModule + std::string("no layer '") + name + "' in " + path +
                    " (layers: " + join(layer_names(dataset)) + ")");
    }
    return *layer;
  }
  if (dataset.GetLayerCount() == 0) throw IoError(kModule + path + " has no layers");
  // With one layer there is nothing to choose; whether it holds polygons is checked by the reader,
  // which then names the layer in its message.
  if (dataset.GetLayerCount() == 1) return *dataset.GetLayer(0);
  // Several polygon layers (a parcel layer beside the buildings, 3DBAG's pand beside its lod12_2d):
  // taking the first would model the wrong polygons without a word.
  // Empty ones (a template layer, one emptied by an edit) hold nothing to choose between.
  std::vector<OGRLayer*> polygonal;
  for (OGRLayer* layer : dataset.GetLayers())
    if (is_polygonal(layer->GetGeomType()) && layer->GetFeatureCount(TRUE) != 0) polygonal.push_back(layer);
  if (polygonal.size() > 1) {
    std::vector<std::string> names;
    for (OGRLayer* layer : polygonal) names.emplace_back(layer->GetName());
    throw ConfigError(kModule + path + " has " + std::to_string(polygonal.size()) + " polygon layers (" +
                      join(names) + "): give the footprints' with --layer");
  }
  if (polygonal.size() == 1) return *polygonal.front();
  for (OGRLayer* layer : dataset.GetLayers()) {
    if (may_hold_polygons(layer->GetGeomType()) && layer_has_polygon_feature(*layer)) return *layer;
  }
  throw IoError(kModule + std::string("no layer with polygon features in ") + path +
                " (layers: " + join(layer_names(dataset)) + ")");
}

std::string describe_srs(const OGRSpatialReference& srs);

/// The polygons' vertices as bytes that do not depend on where each ring starts, nor on the order of
/// the holes or of the parts: two features of the same shape give the same text.
std::string shape_bytes(const std::vector<Polygon2>& polygons) {
  const auto ring_bytes = [](const Ring2& ring) {
    const auto least = std::min_element(ring.begin(), ring.end(), [](const Point2& a, const Point2& b) {
      return a.x < b.x || (a.x == b.x && a.y < b.y);
    });
    Ring2 turned(least, ring.end());
    turned.insert(turned.end(), ring.begin(), least);
    return std::string(reinterpret_cast<const char*>(turned.data()), turned.size() * sizeof(Point2)) + '|';
  };
  std::vector<std::string> parts;
  for (const Polygon2& polygon : polygons) {
    std::vector<std::string> holes;
    for (const Ring2& hole : polygon.holes) holes.push_back(ring_bytes(hole));
    std::sort(holes.begin(), holes.end());
    std::string part = ring_bytes(polygon.outer);
    for (const std::string& h : holes) part += h;
    parts.push_back(part + '#');
  }
  std::sort(parts.begin(), parts.end());
  std::string all;
  for (const std::string& part : parts) all += part;
  return all;
}

/// "EPSG:n" when the layer's SRS carries or can be matched to an EPSG code, else its WKT, else "".
std::string describe_srs(OGRLayer& layer) {
  const OGRSpatialReference* srs = layer.GetSpatialRef();
  return srs == nullptr ? std::string() : describe_srs(*srs);
}

Ring2 ring_from_ogr(const OGRLinearRing& ring) {
  Ring2 out;
  out.reserve(static_cast<std::size_t>(ring.getNumPoints()));
  for (int i = 0; i < ring.getNumPoints(); ++i) out.push_back({ring.getX(i), ring.getY(i)});
  return out;
}

/// Polygons of a multipolygon, rings cleaned and oriented; degenerate polygons dropped.
std::vector<Polygon2> polygons_from_ogr(const OGRMultiPolygon& multi) {
  std::vector<Polygon2> polygons;
  for (const OGRPolygon* part : multi) {
    if (part == nullptr || part->IsEmpty()) continue;
    Polygon2 polygon;
    polygon.outer = ring_from_ogr(*part->getExteriorRing());
    for (int i = 0; i < part->getNumInteriorRings(); ++i) {
      polygon.holes.push_back(ring_from_ogr(*part->getInteriorRing(i)));
    }
    if (normalise_polygon(polygon)) polygons.push_back(std::move(polygon));
  }
  return polygons;
}

/// The polygonal parts of MakeValid's result (which may mix polygons, lines and points) as one
/// multipolygon. MakeValid's parts do not overlap, so collecting them needs no union.
std::unique_ptr<OGRMultiPolygon> polygonal_parts(std::unique_ptr<OGRGeometry> geometry) {
  auto multi = std::make_unique<OGRMultiPolygon>();
  if (!geometry) return multi;
  const OGRwkbGeometryType type = wkbFlatten(geometry->getGeometryType());
  if (type == wkbPolygon || type == wkbMultiPolygon) {
    OGRGeometry* forced = OGRGeometryFactory::forceToMultiPolygon(geometry.release());
    multi.reset(forced->toMultiPolygon());
    return multi;
  }
  if (type == wkbGeometryCollection) {
    for (const OGRGeometry* part : geometry->toGeometryCollection()) {
      const OGRwkbGeometryType part_type = wkbFlatten(part->getGeometryType());
      if (part_type == wkbPolygon) {
        multi->addGeometry(part);
      } else if (part_type == wkbMultiPolygon) {
        for (const OGRPolygon* polygon : part->toMultiPolygon()) multi->addGeometry(polygon);
      }
    }
  }
  return multi;
}

/// Checks a multipolygon with GEOS and repairs it with MakeValid when invalid (and `repair`).
RepairedPolygons repair_multipolygon(std::unique_ptr<OGRMultiPolygon> multi, bool repair) {
  RepairedPolygons outcome;
  CPLErrorReset();
  if (!multi->IsValid()) {
    // GEOS reports why a geometry is invalid through the error handler ("Self-intersection at or
    // near point 25 5"); our quiet handler keeps it as the last message.
    const char* why = CPLGetLastErrorMsg();
    const std::string problem =
        std::string("invalid polygon") + (why != nullptr && *why != '\0' ? std::string(": ") + why : "");
    if (!repair) {
      outcome.skip_reason = problem + " (repair disabled)";
      return outcome;
    }
    std::unique_ptr<OGRGeometry> repaired(multi->MakeValid());
    if (!repaired) {
      outcome.skip_reason = problem + ", repair failed" + gdal_message();
      return outcome;
    }
    multi = polygonal_parts(std::move(repaired));
    if (multi->IsEmpty()) {
      outcome.skip_reason = problem + ", repair left no polygon";
      return outcome;
    }
    outcome.repair_note = problem;
  }
  outcome.polygons = polygons_from_ogr(*multi);
  if (outcome.polygons.empty()) {
    outcome.skip_reason = "no polygon with 3 or more distinct vertices";
    outcome.repair_note.clear();
  }
  return outcome;
}

/// One feature's geometry: linearised, flattened to 2D, reprojected when `transform` is given,
/// then checked and repaired.
RepairedPolygons convert_geometry(const OGRGeometry& source, bool repair, OGRCoordinateTransformation* transform,
                                  const std::string& target_name) {
  std::unique_ptr<OGRGeometry> geometry(source.clone());
  // Curves (CurvePolygon, MultiSurface) are linearised with GDAL's default step of 4 degrees.
  if (geometry->hasCurveGeometry()) geometry.reset(geometry->getLinearGeometry());
  geometry->flattenTo2D();  // footprints are 2D; z (and m) would only confuse IsValid
  if (transform != nullptr && geometry->transform(transform) != OGRERR_NONE) {
    RepairedPolygons outcome;
    outcome.skip_reason = "cannot reproject to " + target_name + gdal_message();
    return outcome;
  }
  std::unique_ptr<OGRMultiPolygon> multi(
      OGRGeometryFactory::forceToMultiPolygon(geometry.release())->toMultiPolygon());
  return repair_multipolygon(std::move(multi), repair);
}

/// "EPSG:n" when `srs` carries or can be matched to an EPSG code, else its WKT.
std::string describe_srs(const OGRSpatialReference& srs) {
  std::unique_ptr<OGRSpatialReference> copy(srs.Clone());
  auto epsg = [&]() -> std::string {
    const char* authority = copy->GetAuthorityName(nullptr);
    const char* code = copy->GetAuthorityCode(nullptr);
    if (authority != nullptr && code != nullptr && iequals(authority, "EPSG")) return std::string("EPSG:") + code;
    return {};
  };
  std::string text = epsg();
  if (text.empty() && copy->AutoIdentifyEPSG() == OGRERR_NONE) text = epsg();
  if (!text.empty()) return text;
  char* wkt = nullptr;
  if (copy->exportToWkt(&wkt) == OGRERR_NONE && wkt != nullptr) text = wkt;
  CPLFree(wkt);
  return text;
}

/// A field's value as an id's text. OGR writes reals with 15 significant digits, which is not enough for
/// the 16-digit integers many sources keep in real fields (1234567890123456 and ...457 both read
/// "1.23456789012346e+15": distinct ids taken for duplicates); a whole number is written whole, any
/// other real with the fewest digits that read back as the same number.
std::string field_text(OGRFeature& feature, int index) {
  if (feature.GetFieldDefnRef(index)->GetType() != OFTReal) return feature.GetFieldAsString(index);
  const double v = feature.GetFieldAsDouble(index);
  char text[40];
  if (std::isfinite(v) && v == std::trunc(v) && std::fabs(v) < 9.2e18) {
    std::snprintf(text, sizeof text, "%.0f", v);
    return text;
  }
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, v);
    if (std::strtod(text, nullptr) == v) break;
  }
  return text;
}

/// Whether the layer declares a geographic CRS (degrees) while its coordinates reach beyond longitude
/// and latitude: a GeoJSON file without a "crs" member is WGS 84 by its standard, whatever it holds,
/// and a wrong .prj says degrees as easily. `extent` gets the layer's extent.
bool degrees_in_name_only(OGRLayer& layer, OGREnvelope& extent) {
  const OGRSpatialReference* srs = layer.GetSpatialRef();
  if (srs == nullptr || !srs->IsGeographic() || layer.GetExtent(&extent, TRUE) != OGRERR_NONE) return false;
  // Either axis order: what matters is that neither reads as degrees.
  const double a = std::max(std::fabs(extent.MinX), std::fabs(extent.MaxX));
  const double b = std::max(std::fabs(extent.MinY), std::fabs(extent.MaxY));
  return std::max(a, b) > 180.0 || std::min(a, b) > 90.0;
}

/// The transformation from the layer's CRS into `target` (the points' CRS), or nullptr when either
/// is unknown or they are the same. Updates set.srs / set.reprojected_from. Throws IoError when the
/// target cannot be understood or PROJ has no transformation between the two.
std::unique_ptr<OGRCoordinateTransformation> reprojection(OGRLayer& layer, const std::string& target_text,
                                                          const std::string& path, FootprintSet& set) {
  const OGRSpatialReference* layer_srs = layer.GetSpatialRef();
  if (target_text.empty() || layer_srs == nullptr || set.srs.empty()) return nullptr;  // none, or ignored
  OGRSpatialReference source(*layer_srs);
  OGRSpatialReference target;
  if (target.SetFromUserInput(target_text.c_str()) != OGRERR_NONE)
    throw IoError(kModule + std::string("cannot understand the point clouds' CRS '") + target_text.substr(0, 80) +
                  "'" + gdal_message());
  // x = easting / longitude, y = northing / latitude, whatever the CRS definition says.
  source.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  target.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  if (source.IsSame(&target)) return nullptr;
  std::unique_ptr<OGRCoordinateTransformation> transform(OGRCreateCoordinateTransformation(&source, &target));
  const std::string target_name = describe_srs(target);
  if (!transform)
    throw IoError(kModule + std::string("cannot reproject ") + path + " from " + set.srs.substr(0, 80) + " to " +
                  target_name.substr(0, 80) + " (the point clouds' CRS)" + gdal_message());
  set.reprojected_from = set.srs;
  set.srs = target_name;
  return transform;
}

/// A list field's value as the JSON array a list attribute holds.
AttributeList list_value(OGRFeature& feature, int i, OGRFieldType type) {
  nlohmann::json list = nlohmann::json::array();
  int count = 0;
  if (type == OFTIntegerList) {
    const int* v = feature.GetFieldAsIntegerList(i, &count);
    for (int k = 0; k < count; ++k) list.push_back(v[k]);
  } else if (type == OFTInteger64List) {
    const GIntBig* v = feature.GetFieldAsInteger64List(i, &count);
    for (int k = 0; k < count; ++k) list.push_back(static_cast<std::int64_t>(v[k]));
  } else if (type == OFTRealList) {
    const double* v = feature.GetFieldAsDoubleList(i, &count);
    for (int k = 0; k < count; ++k) list.push_back(std::isfinite(v[k]) ? nlohmann::json(v[k]) : nlohmann::json(nullptr));
  } else {
    char** v = feature.GetFieldAsStringList(i);
    for (; v && *v; ++v) list.push_back(std::string(*v));
  }
  return {list.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)};
}

bool intersects(const OGREnvelope& envelope, const Box2& box) {
  return !(envelope.MinX > box.max.x || envelope.MaxX < box.min.x || envelope.MinY > box.max.y ||
           envelope.MaxY < box.min.y);
}

}  // namespace

RepairedPolygons check_and_repair(const std::vector<Polygon2>& polygons, bool repair) {
  QuietGdalErrors quiet;
  auto multi = std::make_unique<OGRMultiPolygon>();
  auto ring_of = [](const Ring2& ring) {
    auto r = std::make_unique<OGRLinearRing>();
    for (const Point2& p : ring) r->addPoint(p.x, p.y);
    if (!ring.empty()) r->addPoint(ring.front().x, ring.front().y);  // OGR rings are closed
    return r;
  };
  for (const Polygon2& p : polygons) {
    OGRPolygon polygon;
    polygon.addRingDirectly(ring_of(p.outer).release());
    for (const Ring2& hole : p.holes) polygon.addRingDirectly(ring_of(hole).release());
    multi->addGeometry(&polygon);
  }
  return repair_multipolygon(std::move(multi), repair);
}

std::vector<FieldSummary> summarise_ogr_fields(const std::string& path, const FootprintReadOptions& options,
                                               std::size_t max_features, std::size_t& features) {
  QuietGdalErrors quiet;
  GDALDatasetUniquePtr dataset = open_vector(path);
  OGRLayer& layer = select_layer(*dataset, path, options.layer);
  OGRFeatureDefn* definition = layer.GetLayerDefn();
  std::vector<FieldSummary> fields(static_cast<std::size_t>(definition->GetFieldCount()));
  std::vector<std::unordered_set<std::string>> seen(fields.size());
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const OGRFieldDefn* field = definition->GetFieldDefn(static_cast<int>(i));
    fields[i].name = field->GetNameRef();
    fields[i].type = OGRFieldDefn::GetFieldTypeName(field->GetType());
  }
  if (!options.attribute_filter.empty() && layer.SetAttributeFilter(options.attribute_filter.c_str()) != OGRERR_NONE)
    throw IoError(kModule + std::string("bad attribute filter '") + options.attribute_filter + "' on " + path);
  features = 0;
  layer.ResetReading();
  for (OGRFeatureUniquePtr feature(layer.GetNextFeature()); feature && features < max_features;
       feature.reset(layer.GetNextFeature())) {
    ++features;
    for (std::size_t i = 0; i < fields.size(); ++i) {
      if (!feature->IsFieldSetAndNotNull(static_cast<int>(i))) continue;
      ++fields[i].values;
      if (seen[i].insert(field_text(*feature, static_cast<int>(i))).second) ++fields[i].distinct;
    }
  }
  return fields;
}

std::vector<std::string> list_ogr_layers(const std::string& path) {
  QuietGdalErrors quiet;
  GDALDatasetUniquePtr dataset = open_vector(path);
  return layer_names(*dataset);
}

FootprintSet read_ogr_footprints(const std::string& path, const FootprintReadOptions& options,
                                 const FootprintReadMode& mode) {
  const auto warn = [&mode](const std::string& message) { mode.quiet ? log_debug(message) : log_warning(message); };
  QuietGdalErrors quiet;
  GDALDatasetUniquePtr dataset = open_vector(path);
  OGRLayer& layer = select_layer(*dataset, path, options.layer);
  const std::string where = path + " layer '" + layer.GetName() + "'";

  if (const OGRFeatureDefn* columns = layer.GetLayerDefn(); columns->GetGeomFieldCount() > 1) {
    // A CSV with two WKT columns, a table with an envelope beside the footprint: say which is read.
    std::string names;
    for (int i = 0; i < columns->GetGeomFieldCount(); ++i)
      names += std::string(i ? ", " : "") + columns->GetGeomFieldDefn(i)->GetNameRef();
    warn(kModule + where + " has " + std::to_string(columns->GetGeomFieldCount()) + " geometry columns (" +
         names + "): the first, " + columns->GetGeomFieldDefn(0)->GetNameRef() +
         ", is read as the footprints (make a layer of the one meant, e.g. ogr2ogr -select)");
  }

  FootprintSet set;
  set.path = path;
  set.driver = dataset->GetDriver() != nullptr ? dataset->GetDriver()->GetDescription() : "";
  set.layer = layer.GetName();
  set.srs = describe_srs(layer);
  if (OGREnvelope extent; degrees_in_name_only(layer, extent)) {
    if (!mode.quiet) {
      char reach[160];
      std::snprintf(reach, sizeof reach, "x %.3f .. %.3f, y %.3f .. %.3f", extent.MinX, extent.MaxX,
                    extent.MinY, extent.MaxY);
      log_warning(
          kModule + path + " declares " + set.srs.substr(0, 80) +
          (set.driver == "GeoJSON"
               ? " (degrees; a GeoJSON file without a \"crs\" member is WGS 84 by its standard)"
               : " (degrees)") +
          " but its coordinates reach " + reach +
          ", which are no degrees: that CRS is ignored, the footprints taken to be in the point clouds' (or "
          "--crs)");
    }
    set.srs.clear();
  }
  std::unique_ptr<OGRCoordinateTransformation> transform = reprojection(layer, options.target_srs, path, set);
  if (transform && !mode.quiet)
    log_warning(kModule + path + " is in " + set.reprojected_from.substr(0, 80) + ", the point clouds in " +
                set.srs.substr(0, 80) + ": footprints reprojected");

  if (!may_hold_polygons(layer.GetGeomType())) {
    throw IoError(kModule + where + " has no polygon features (geometry type " +
                  OGRGeometryTypeToName(layer.GetGeomType()) + ")");
  }

  // The id field: an attribute, or the feature id when none is named or when the name is the
  // layer's FID column ("fid" in GeoPackage, "ogc_fid" in SQLite), which is not an attribute.
  int id_index = -1;
  const std::string fid_column = layer.GetFIDColumn() != nullptr ? layer.GetFIDColumn() : "";
  OGRFeatureDefn* definition = layer.GetLayerDefn();
  const bool use_fid =
      options.id_field.empty() ||
      (definition->GetFieldIndex(options.id_field.c_str()) < 0 &&
       (iequals(options.id_field, "FID") || (!fid_column.empty() && iequals(options.id_field, fid_column))));
  if (!use_fid) {
    id_index = definition->GetFieldIndex(options.id_field.c_str());
    if (id_index < 0) {
      std::vector<std::string> fields;
      for (int i = 0; i < definition->GetFieldCount(); ++i) {
        fields.emplace_back(definition->GetFieldDefn(i)->GetNameRef());
      }
      throw IoError(kModule + std::string("no field '") + options.id_field + "' in " + where +
                    " (fields: " + join(fields) + ")");
    }
  }
  set.id_field = use_fid ? "FID" : options.id_field;

  // The optional ground-height field: a numeric attribute that overrides the floor height.
  int ground_index = -1;
  if (!options.ground_field.empty()) {
    ground_index = definition->GetFieldIndex(options.ground_field.c_str());
    if (ground_index < 0) {
      std::vector<std::string> fields;
      for (int i = 0; i < definition->GetFieldCount(); ++i) fields.emplace_back(definition->GetFieldDefn(i)->GetNameRef());
      throw IoError(kModule + std::string("no field '") + options.ground_field + "' in " + where + " (fields: " +
                    join(fields) + ")");
    }
    // Heights are numbers: a date or a list would be read as some number (2014 of "2014-07-09").
    const OGRFieldType type = definition->GetFieldDefn(ground_index)->GetType();
    if (type != OFTInteger && type != OFTInteger64 && type != OFTReal && type != OFTString)
      throw IoError(kModule + std::string("field '") + options.ground_field + "' of " + where + " holds " +
                    OGRFieldDefn::GetFieldTypeName(type) + " values, not heights (--ground-field)");
  }

  if (!options.attribute_filter.empty()) {
    CPLErrorReset();
    // Some drivers (GeoPackage, SQLite) accept any filter here and only fail when the SQL is
    // prepared, on the first read; reading one feature makes both kinds fail in the same place.
    bool bad_filter = layer.SetAttributeFilter(options.attribute_filter.c_str()) != OGRERR_NONE;
    if (!bad_filter) {
      layer.ResetReading();
      const OGRFeatureUniquePtr probe(layer.GetNextFeature());
      bad_filter = !probe && CPLGetLastErrorType() == CE_Failure;
    }
    if (bad_filter) {
      throw IoError(kModule + std::string("bad attribute filter '") + options.attribute_filter + "' on " +
                    where + gdal_message());
    }
  }
  // OGR's spatial filter lets the driver use its index (GeoPackage R-tree, SpatiaLite); some
  // drivers apply it only approximately, and with GEOS OGR may drop a feature whose envelope
  // meets the box while its polygon does not, so each envelope is checked against the box below.
  // With reprojection the box is in the points' CRS, OGR's filter in the layer's: the box goes
  // back through the inverse transformation (its edges densified), each envelope forward.
  if (options.bbox) {
    const Box2& box = *options.bbox;
    double min_x = box.min.x, min_y = box.min.y, max_x = box.max.x, max_y = box.max.y;
    bool filter = true;
    if (transform) {
      std::unique_ptr<OGRCoordinateTransformation> back(transform->GetInverse());
      filter = back && back->TransformBounds(box.min.x, box.min.y, box.max.x, box.max.y, &min_x, &min_y, &max_x,
                                             &max_y, 21);
    }
    if (filter) layer.SetSpatialFilterRect(min_x, min_y, max_x, max_y);
  }

  std::unordered_map<BuildingId, std::int64_t> first_fid_of_id;
  std::size_t polygon_features = 0;
  // Duplicated ids are told after the read: when most ids are, the field is no id (one error, not a
  // warning per feature).
  std::vector<std::string> duplicate_warnings;
  std::string first_duplicate;
  // The same polygon under two ids (a feature copied, a layer appended to part of itself) made two
  // models in one place: the first feature keeps it. Each shape is kept as the hash of its
  // shape_bytes with the first holder's fid and id (two shapes of one hash, at odds of 2^-64, would
  // be taken for one).
  std::unordered_map<std::size_t, std::pair<std::int64_t, BuildingId>> first_of_shape;
  std::size_t ground_numbers = 0, ground_not_numbers = 0;  // --ground-field values read, and not heights
  std::string first_not_number;
  auto skip = [&](const BuildingId& id, const std::string& reason) {
    warn(kModule + std::string("skipped ") + id + " in " + where + ": " + reason);
    set.skipped.push_back({id, reason});
  };

  layer.ResetReading();
  while (true) {
    CPLErrorReset();
    OGRFeatureUniquePtr feature(layer.GetNextFeature());
    if (!feature) {
      // A driver that fails half-way (corrupt file) ends the iteration early with a CE_Failure.
      if (CPLGetLastErrorType() == CE_Failure) {
        // A filter the driver splices into its own SQL ("1=1 --" comments the rest of it out) fails only
        // here.
        const std::string filter =
            options.attribute_filter.empty() ? "" : " with --where \"" + options.attribute_filter + "\"";
        throw IoError(kModule + std::string("error while reading ") + where + filter + gdal_message());
      }
      break;
    }
    const std::int64_t fid = feature->GetFID();
    const OGRGeometry* geometry = feature->GetGeometryRef();
    if (options.bbox && geometry != nullptr && !geometry->IsEmpty()) {
      OGREnvelope envelope;
      geometry->getEnvelope(&envelope);
      if (transform && !transform->TransformBounds(envelope.MinX, envelope.MinY, envelope.MaxX, envelope.MaxY,
                                                   &envelope.MinX, &envelope.MinY, &envelope.MaxX, &envelope.MaxY, 21))
        continue;  // cannot be placed in the points' CRS: the scan reports it
      if (!intersects(envelope, *options.bbox)) continue;
    }
    ++set.feature_count;

    const std::string fid_text = "fid " + std::to_string(fid);
    BuildingId id;
    if (use_fid) {
      id = std::to_string(fid);
    } else if (!feature->IsFieldSetAndNotNull(id_index)) {
      skip(fid_text, "no id (field '" + options.id_field + "' is null)");
      continue;
    } else {
      id = field_text(*feature, id_index);
      if (id.find_first_not_of(" \t\r\n") == std::string::npos) {
        skip(fid_text,
             "no id (field '" + options.id_field + "' is " + (id.empty() ? "empty" : "blank") + ")");
        continue;
      }
    }

    if (geometry == nullptr) {
      skip(id, "no geometry");
      continue;
    }
    if (geometry->IsEmpty()) {
      skip(id, "empty geometry");
      continue;
    }
    if (!is_polygonal(geometry->getGeometryType())) {
      skip(id, std::string("not a polygon (") + OGRGeometryTypeToName(geometry->getGeometryType()) + ")");
      continue;
    }
    ++polygon_features;

    // The first feature with an id owns it, even when that feature is skipped for its geometry:
    // a later feature silently taking its place would hide the problem.
    const auto [first, inserted] =
        mode.keep_duplicates ? std::make_pair(first_fid_of_id.end(), true) : first_fid_of_id.emplace(id, fid);
    if (!inserted) {
      const std::string reason =
          "duplicated id (first at fid " + std::to_string(first->second) + ", this is " + fid_text + ")";
      duplicate_warnings.push_back(kModule + std::string("skipped ") + id + " in " + where + ": " + reason);
      if (first_duplicate.empty())
        first_duplicate = "'" + id + "' at fid " + std::to_string(first->second) + " and again at " + fid_text;
      set.skipped.push_back({id, reason});
      continue;
    }

    RepairedPolygons outcome = convert_geometry(*geometry, options.repair, transform.get(), set.srs);
    if (outcome.polygons.empty()) {
      skip(id, outcome.skip_reason);
      continue;
    }
    if (const std::string too_big = extent_problem(outcome.polygons, options.max_extent); !too_big.empty()) {
      skip(id, too_big);
      continue;
    }
    if (!mode.keep_duplicates) {
      const auto [shape, new_shape] = first_of_shape.emplace(
          std::hash<std::string>{}(shape_bytes(outcome.polygons)), std::make_pair(fid, id));
      if (!new_shape) {
        skip(id, "the same polygon as " + shape->second.second + " (fid " +
                     std::to_string(shape->second.first) + ", this is " + fid_text + ")");
        continue;
      }
    }
    if (!outcome.repair_note.empty()) {
      ++set.repaired;
      warn(kModule + std::string("repaired ") + id + " in " + where + ": " + outcome.repair_note);
    }
    Footprint footprint;
    footprint.id = std::move(id);
    footprint.fid = fid;
    footprint.polygons = std::move(outcome.polygons);
    // Every attribute with its type, so that outputs carry them unchanged (64-bit ids intact).
    for (int i = 0; i < definition->GetFieldCount(); ++i) {
      const OGRFieldDefn* field = definition->GetFieldDefn(i);
      AttributeValue value;
      if (feature->IsFieldSetAndNotNull(i)) {
        switch (field->GetType()) {
          case OFTInteger:
            value = field->GetSubType() == OFSTBoolean ? AttributeValue{feature->GetFieldAsInteger(i) != 0}
                                                       : AttributeValue{std::int64_t{feature->GetFieldAsInteger(i)}};
            break;
          case OFTInteger64: value = std::int64_t{feature->GetFieldAsInteger64(i)}; break;
          case OFTReal: value = feature->GetFieldAsDouble(i); break;
          // Lists stay lists (a GeoJSON array), not OGR's text "(3:1,2,3)".
          case OFTIntegerList:
          case OFTInteger64List:
          case OFTRealList:
          case OFTStringList: value = list_value(*feature, i, field->GetType()); break;
          default: value = std::string(feature->GetFieldAsString(i)); break;
        }
      }
      footprint.attributes.emplace_back(field->GetNameRef(), std::move(value));
    }
    if (ground_index >= 0 && feature->IsFieldSetAndNotNull(ground_index)) {
      // A text field's value must be a number as a whole ("2014-07-09" is not).
      const char* text = feature->GetFieldAsString(ground_index);
      char* end = nullptr;
      const double z = definition->GetFieldDefn(ground_index)->GetType() == OFTString
                           ? std::strtod(text, &end)
                           : feature->GetFieldAsDouble(ground_index);
      const bool whole =
          end == nullptr || (end != text && std::string(end).find_first_not_of(" \t") == std::string::npos);
      if (std::isfinite(z) && whole) {
        footprint.ground_z = z;
        ++ground_numbers;
      } else if (ground_not_numbers++ == 0) {
        first_not_number = "'" + std::string(text) + "' at " + footprint.id;
      }
    }
    if (!outcome.repair_note.empty()) footprint.note = "footprint repaired with MakeValid: " + outcome.repair_note;
    const bool has_hole = std::any_of(footprint.polygons.begin(), footprint.polygons.end(),
                                      [](const Polygon2& p) { return !p.holes.empty(); });
    if (has_hole) ++set.with_holes;
    if (mode.sink)
      (*mode.sink)(std::move(footprint));
    else
      set.footprints.push_back(std::move(footprint));
  }

  // An id field that repeats for more than half of the features is no id (a height class: 159 of
  // Delft's 160 footprints share rel_hoogte 0): an error naming the fields that are unique. A few
  // duplicated ids are the source's own mistakes: those features are skipped with a warning each.
  if (duplicate_warnings.size() * 2 > set.feature_count) {
    constexpr std::size_t kFieldSample = 20000;
    std::size_t read = 0;
    std::string unique;
    for (const FieldSummary& f : summarise_ogr_fields(path, options, kFieldSample, read))
      if (f.unique(read)) unique += (unique.empty() ? "" : ", ") + f.name;
    const std::string field = use_fid ? "the feature id (FID)" : "--id-field " + options.id_field;
    throw IoError(kModule + field + " is not an id of " + where + ": " + std::to_string(duplicate_warnings.size()) +
                  " of its " + std::to_string(set.feature_count) + " features repeat an earlier one's value (the first: " +
                  first_duplicate + "); " +
                  (unique.empty() ? std::string("no field has a value of its own for every feature")
                                  : "fields with a value of its own for every feature" +
                                        std::string(read == kFieldSample ? " (of the first " + std::to_string(read) + ")" : "") +
                                        ": " + unique));
  }
  for (const std::string& message : duplicate_warnings) warn(message);
  if (ground_not_numbers > 0) {
    const std::string what = "field '" + options.ground_field + "' of " + where + " holds " +
                             std::to_string(ground_not_numbers) +
                             " values that are no heights (the first: " + first_not_number + ")";
    if (ground_numbers == 0) throw IoError(kModule + what + " and none that is one (--ground-field)");
    warn(kModule + what + ": those footprints' ground is measured from the points");
  }

  // No polygon at all: an error when the unfiltered layer has none either; an empty selection
  // (filters that match nothing) is a valid result.
  if (polygon_features == 0) {
    layer.SetAttributeFilter(nullptr);
    layer.SetSpatialFilter(nullptr);
    if (!layer_has_polygon_feature(layer)) {
      throw IoError(kModule + where + " has no polygon features");
    }
    if (set.feature_count == 0) set.unfiltered_count = static_cast<std::size_t>(std::max<GIntBig>(0, layer.GetFeatureCount()));
  }
  const std::string summary = kModule + std::to_string(set.feature_count - set.skipped.size()) +
                              " footprints from " + where + " (" + std::to_string(set.skipped.size()) + " skipped, " +
                              std::to_string(set.repaired) + " repaired)";
  mode.quiet ? log_debug(summary) : log_info(summary);
  return set;
}

}  // namespace detail

SimplifiedFootprint simplify_footprint(const std::vector<Polygon2>& polygons, std::size_t max_vertices) {
  const auto count = [](const std::vector<Polygon2>& ps) {
    std::size_t n = 0;
    for (const Polygon2& p : ps) {
      n += p.outer.size();
      for (const Ring2& h : p.holes) n += h.size();
    }
    return n;
  };
  SimplifiedFootprint out;
  out.vertices_before = out.vertices_after = count(polygons);
  if (out.vertices_before <= max_vertices) {
    out.polygons = polygons;
    return out;
  }
  detail::QuietGdalErrors quiet;
  OGRMultiPolygon multi;
  Box2 box;
  const auto ring_of = [&box](const Ring2& ring) {
    auto r = std::make_unique<OGRLinearRing>();
    for (const Point2& v : ring) {
      r->addPoint(v.x, v.y);
      box.add(v);
    }
    if (!ring.empty()) r->addPoint(ring.front().x, ring.front().y);  // OGR rings are closed
    return r.release();
  };
  for (const Polygon2& p : polygons) {
    OGRPolygon polygon;
    polygon.addRingDirectly(ring_of(p.outer));
    for (const Ring2& hole : p.holes) polygon.addRingDirectly(ring_of(hole));
    multi.addGeometry(&polygon);
  }
  const double size = box.empty() ? 0.0 : std::max(box.max.x - box.min.x, box.max.y - box.min.y);
  for (double tolerance = 0.01; tolerance <= size; tolerance *= 2) {
    std::unique_ptr<OGRGeometry> simple(multi.SimplifyPreserveTopology(tolerance));
    if (!simple) continue;
    OGRGeometry* forced = OGRGeometryFactory::forceToMultiPolygon(simple.release());
    std::unique_ptr<OGRMultiPolygon> result(forced->toMultiPolygon());
    std::vector<Polygon2> simplified = detail::polygons_from_ogr(*result);
    const std::size_t n = count(simplified);
    if (simplified.empty() || n > max_vertices) continue;
    out.polygons = std::move(simplified);
    out.vertices_after = n;
    out.tolerance = tolerance;
    return out;
  }
  throw ReconstructionError(ReconstructionStage::footprint, "" + std::to_string(out.vertices_before) +
                            " vertices could not be simplified to " + std::to_string(max_vertices));
}

}  // namespace city3d
