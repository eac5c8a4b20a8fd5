// GeoPackage output through OGR, laid out as 3DBAG's: the footprints with every report attribute
// (layer `buildings`, 3DBAG's `pand`), and for each level of detail its roof parts in plan view with
// heights, slope and azimuth (`lod12_2d`, `lod13_2d`, `lod22_2d`) and its models as MultiPolygonZ
// (`lod12_3d`, `lod13_3d`, `lod22_3d`); `roof_parts` (earlier versions' LoD2.2 roof parts) is a view
// of `lod22_2d`.
#include <cpl_conv.h>
#include <gdal_priv.h>
#include <ogrsf_frmts.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/run_outputs.hpp"
#include "core/mesh_faces.hpp"
#include "reports/report.hpp"

namespace city3d {
namespace {


// The field type that holds every value a name takes: integers stay 64-bit integers, integers
// mixed with numbers become reals, anything mixed with text becomes text.
enum class Kind { none, boolean, integer, real, text, list };

Kind kind_of(const AttributeValue& v) {
  if (std::holds_alternative<bool>(v)) return Kind::boolean;
  if (std::holds_alternative<std::int64_t>(v)) return Kind::integer;
  if (std::holds_alternative<double>(v)) return Kind::real;
  if (std::holds_alternative<std::string>(v)) return Kind::text;
  if (std::holds_alternative<AttributeList>(v)) return Kind::list;
  return Kind::none;
}

Kind join(Kind a, Kind b) {
  if (a == Kind::none) return b;
  if (b == Kind::none || a == b) return a;
  if (a == Kind::text || b == Kind::text) return Kind::text;
  if ((a == Kind::integer && b == Kind::real) || (a == Kind::real && b == Kind::integer)) return Kind::real;
  return Kind::text;  // boolean with a number
}

std::string as_text(const AttributeValue& v) {
  if (const bool* b = std::get_if<bool>(&v)) return *b ? "true" : "false";
  if (const std::int64_t* i = std::get_if<std::int64_t>(&v)) return std::to_string(*i);
  if (const double* d = std::get_if<double>(&v)) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", *d);
    return buf;
  }
  if (const std::string* s = std::get_if<std::string>(&v)) return *s;
  if (const AttributeList* l = std::get_if<AttributeList>(&v)) return l->json;
  return "";
}

void set_field(OGRFeature& feature, int index, Kind kind, const AttributeValue& v) {
  if (std::holds_alternative<std::monostate>(v)) {
    feature.SetFieldNull(index);
    return;
  }
  switch (kind) {
    case Kind::boolean: feature.SetField(index, std::get<bool>(v) ? 1 : 0); break;
    case Kind::integer: feature.SetField(index, static_cast<GIntBig>(std::get<std::int64_t>(v))); break;
    case Kind::real:
      feature.SetField(index, std::holds_alternative<double>(v) ? std::get<double>(v)
                                                               : static_cast<double>(std::get<std::int64_t>(v)));
      break;
    default: feature.SetField(index, as_text(v).c_str()); break;
  }
}

OGRMultiPolygon footprint_geometry(const std::vector<Polygon2>& polygons) {
  OGRMultiPolygon multi;
  for (const Polygon2& p : polygons) {
    OGRPolygon polygon;
    const auto add_ring = [&polygon](const Ring2& ring) {
      OGRLinearRing r;
      for (const Point2& v : ring) r.addPoint(v.x, v.y);
      if (!ring.empty()) r.addPoint(ring.front().x, ring.front().y);
      polygon.addRing(&r);
    };
    add_ring(p.outer);
    for (const Ring2& h : p.holes) add_ring(h);
    multi.addGeometry(&polygon);
  }
  return multi;
}

// A number rounded to 1/`per` (heights to the millimetre: 1000), or null when not finite.
void set_rounded(OGRFeature& feature, int index, double v, double per) {
  if (std::isfinite(v)) feature.SetField(index, std::round(v * per) / per);
  else feature.SetFieldNull(index);
}

// One roof face in plan view: its polygon, lowest / highest / mean vertex height (world z), slope
// and azimuth (degrees; azimuth clockwise from north towards the downhill side) and plan area.
struct RoofPart {
  bool valid = false;
  OGRPolygon plan;
  double lowest = INFINITY, highest = -INFINITY, mean = 0, slope = 0, azimuth = 0, area = 0;
};

RoofPart roof_part(const BuildingModel& m, const std::vector<std::uint32_t>& face) {
  RoofPart p;
  const auto [nx, ny, nz] = detail::newell_normal(m.mesh.vertices, face);
  double sum = 0;
  OGRLinearRing ring;
  for (std::size_t k = 0; k < face.size(); ++k) {
    const Point3& a = m.mesh.vertices[face[k]];
    const double z = a.z + m.origin.z;
    p.lowest = std::min(p.lowest, z), p.highest = std::max(p.highest, z), sum += z;
    ring.addPoint(a.x + m.origin.x, a.y + m.origin.y);
  }
  ring.closeRings();
  const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
  if (!(len > 0)) return p;
  p.valid = true;
  p.plan.addRing(&ring);
  p.mean = sum / face.size();
  p.slope = std::acos(std::min(1.0, std::fabs(nz) / len)) * 180.0 / kPi;
  // The horizontal part of the normal points downhill; azimuth clockwise from north (+y).
  p.azimuth = std::atan2(nx, ny) * 180.0 / kPi;
  if (p.azimuth < 0) p.azimuth += 360.0;
  p.area = std::fabs(nz) / 2;
  return p;
}

// RAII for the dataset and the config options that make the file deterministic.
struct DatasetCloser {
  void operator()(GDALDataset* ds) const { GDALClose(ds); }
};

}  // namespace

void write_gpkg(const std::string& path, const OverviewSource& records, const std::string& crs) {
  GDALAllRegister();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GPKG");
  if (!driver) throw IoError("gpkg: GDAL has no GPKG driver; cannot write " + path);
  // GDAL wants the .gpkg extension on the temporary file too.
  const std::string temp = path + ".part.gpkg";
  std::remove(temp.c_str());
  // A fixed timestamp in gpkg_contents keeps identical runs byte-identical.
  CPLSetThreadLocalConfigOption("OGR_CURRENT_DATE", "2000-01-01T00:00:00.000Z");
  struct ResetDate {
    ~ResetDate() { CPLSetThreadLocalConfigOption("OGR_CURRENT_DATE", nullptr); }
  } reset_date;
  std::unique_ptr<GDALDataset, DatasetCloser> ds(driver->Create(temp.c_str(), 0, 0, 0, GDT_Unknown, nullptr));
  if (!ds) throw IoError("gpkg: cannot create " + temp + ": " + CPLGetLastErrorMsg());
  OGRSpatialReference srs;
  OGRSpatialReference* srs_ptr = nullptr;
  if (!crs.empty() && srs.SetFromUserInput(crs.c_str()) == OGRERR_NONE) {
    srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    srs_ptr = &srs;
  }
  const auto fail = [&](const std::string& what) {
    ds.reset();
    std::remove(temp.c_str());
    throw IoError("gpkg: " + what + " in " + path + ": " + CPLGetLastErrorMsg());
  };

  // Layer `buildings`: the union of all records' attribute names, in first-seen order (a first pass
  // over the records, without their models).
  std::vector<std::string> names;
  std::map<std::string, Kind> kinds;
  for (std::size_t k = 0; k < records.size(); ++k) {
    const OverviewRecord r = records.at(k, false);
    for (const auto& [name, value] : detail::output_attributes(r.report, r.footprint_attributes, false)) {
      const auto [it, fresh] = kinds.emplace(name, Kind::none);
      if (fresh) names.push_back(name);
      it->second = join(it->second, kind_of(value));
    }
  }
  OGRLayer* buildings = ds->CreateLayer("buildings", srs_ptr, wkbMultiPolygon, nullptr);
  if (!buildings) fail("cannot create layer buildings");
  // The id first, as a text field: it is the CityObject id of the building.
  {
    OGRFieldDefn id("id", OFTString);
    if (buildings->CreateField(&id) != OGRERR_NONE) fail("cannot create field id");
  }
  std::map<std::string, int> index_of;
  for (const std::string& name : names) {
    const Kind k = kinds[name];
    OGRFieldDefn field(name.c_str(), k == Kind::integer ? OFTInteger64
                                     : k == Kind::real  ? OFTReal
                                     : k == Kind::boolean ? OFTInteger
                                                          : OFTString);
    if (k == Kind::boolean) field.SetSubType(OFSTBoolean);
    if (k == Kind::list) field.SetSubType(OFSTJSON);  // GeoPackage has no list type: its JSON text
    if (buildings->CreateField(&field) != OGRERR_NONE) fail("cannot create field " + name);
  }
  for (int i = 0; i < buildings->GetLayerDefn()->GetFieldCount(); ++i)
    index_of[buildings->GetLayerDefn()->GetFieldDefn(i)->GetNameRef()] = i;
  if (ds->StartTransaction() != OGRERR_NONE) fail("cannot start a transaction");
  for (std::size_t k = 0; k < records.size(); ++k) {
    const OverviewRecord r = records.at(k, false);
    OGRFeature feature(buildings->GetLayerDefn());
    feature.SetField(0, r.report.id.c_str());
    for (const auto& [name, value] : detail::output_attributes(r.report, r.footprint_attributes, false))
      set_field(feature, index_of.at(name), kinds[name], value);
    if (!r.footprint.empty()) {
      OGRMultiPolygon geometry = footprint_geometry(r.footprint);
      feature.SetGeometry(&geometry);
    }
    if (buildings->CreateFeature(&feature) != OGRERR_NONE) fail("cannot write building " + r.report.id);
  }
  if (ds->CommitTransaction() != OGRERR_NONE) fail("cannot commit the buildings");

  // The levels of detail: for each, `lodXX_2d`, its roof faces in plan view, and `lodXX_3d`, each
  // building's model as one MultiPolygonZ, both from one more pass over the records (every level of
  // one record at a time), all six layers filled in one transaction.
  struct LevelLayers {
    const char* lod;
    OGRLayer* plan = nullptr;
    OGRLayer* solid = nullptr;
  };
  LevelLayers levels[] = {{"1.2"}, {"1.3"}, {"2.2"}};
  const std::pair<const char*, OGRFieldType> plan_fields[] = {
      {"building_id", OFTString}, {"part", OFTInteger},   {"b3_h_maaiveld", OFTReal}, {"h_min", OFTReal},
      {"h_max", OFTReal},         {"h_mean", OFTReal},    {"slope", OFTReal},         {"azimuth", OFTReal},
      {"area", OFTReal}};
  const std::pair<const char*, OGRFieldType> solid_fields[] = {
      {"id", OFTString},     {"status", OFTString}, {"b3_h_maaiveld", OFTReal}, {"h_max", OFTReal},
      {"volume", OFTReal},   {"rmse", OFTReal},     {"val3dity", OFTString},    {"surfaces", OFTString}};
  for (LevelLayers& level : levels) {
    std::string name = std::string("lod") + level.lod[0] + level.lod[2];
    level.plan = ds->CreateLayer((name + "_2d").c_str(), srs_ptr, wkbPolygon, nullptr);
    level.solid = ds->CreateLayer((name + "_3d").c_str(), srs_ptr, wkbMultiPolygon25D, nullptr);
    if (!level.plan || !level.solid) fail("cannot create the layers of LoD" + std::string(level.lod));
    for (const auto& [field_name, type] : plan_fields) {
      OGRFieldDefn field(field_name, type);
      if (level.plan->CreateField(&field) != OGRERR_NONE) fail(std::string("cannot create field ") + field_name);
    }
    for (const auto& [field_name, type] : solid_fields) {
      OGRFieldDefn field(field_name, type);
      if (std::strcmp(field_name, "val3dity") == 0 || std::strcmp(field_name, "surfaces") == 0)
        field.SetSubType(OFSTJSON);
      if (level.solid->CreateField(&field) != OGRERR_NONE) fail(std::string("cannot create field ") + field_name);
    }
  }
  if (ds->StartTransaction() != OGRERR_NONE) fail("cannot start a transaction");
  for (std::size_t k = 0; k < records.size(); ++k) {
    const OverviewRecord r = records.at(k, true);
    const double ground = r.report.ground_z;
    for (const CityGeometry& g : r.lods) {
      const LevelLayers* level = nullptr;
      for (const LevelLayers& l : levels)
        if (g.lod == l.lod) level = &l;
      if (!level) continue;
      const BuildingModel& m = g.model;
      const std::vector<SurfaceType> types = surface_types(m);
      // Roof parts in plan.
      int part = 0;
      for (std::size_t f = 0; f < m.mesh.faces.size(); ++f) {
        if (types[f] != SurfaceType::roof) continue;
        const RoofPart p = roof_part(m, m.mesh.faces[f]);
        if (!p.valid) continue;
        OGRFeature feature(level->plan->GetLayerDefn());
        feature.SetField(0, r.report.id.c_str());
        feature.SetField(1, part++);
        set_rounded(feature, 2, ground, 1000);
        feature.SetField(3, std::round(p.lowest * 1000) / 1000);
        feature.SetField(4, std::round(p.highest * 1000) / 1000);
        feature.SetField(5, std::round(p.mean * 1000) / 1000);
        feature.SetField(6, std::round(p.slope * 100) / 100);
        if (p.slope < 0.01) feature.SetFieldNull(7);
        else feature.SetField(7, std::round(p.azimuth * 100) / 100);
        feature.SetField(8, std::round(p.area * 100) / 100);
        feature.SetGeometry(&p.plan);
        if (level->plan->CreateFeature(&feature) != OGRERR_NONE)
          fail("cannot write a roof part of " + r.report.id + " (LoD" + g.lod + ")");
      }
      // The model: one polygon per face, grounds first, then walls, then roofs, each polygon's
      // semantic type in `surfaces` (a MultiPolygonZ cannot carry them itself).
      OGRMultiPolygon solid;
      std::string surfaces = "[";
      double top = -INFINITY;
      for (const SurfaceType wanted : {SurfaceType::ground, SurfaceType::wall, SurfaceType::roof}) {
        for (std::size_t f = 0; f < m.mesh.faces.size(); ++f) {
          if (types[f] != wanted) continue;
          OGRLinearRing ring;
          for (std::uint32_t v : m.mesh.faces[f]) {
            const Point3& a = m.mesh.vertices[v];
            ring.addPoint(a.x + m.origin.x, a.y + m.origin.y, a.z + m.origin.z);
            top = std::max(top, a.z + m.origin.z);
          }
          ring.closeRings();
          OGRPolygon polygon;
          polygon.addRing(&ring);
          solid.addGeometry(&polygon);
          surfaces += std::string(surfaces.size() > 1 ? "," : "") + "\"" + surface_type_name(wanted) + "\"";
        }
      }
      surfaces += "]";
      OGRFeature feature(level->solid->GetLayerDefn());
      feature.SetField(0, r.report.id.c_str());
      feature.SetField(1, status_name(r.report.status));
      set_rounded(feature, 2, ground, 1000);
      set_rounded(feature, 3, top, 1000);
      const bool lod12 = g.lod == "1.2", lod13 = g.lod == "1.3";
      set_rounded(feature, 4, lod12 ? r.report.volume_lod12 : lod13 ? r.report.volume_lod13 : r.report.volume_lod22, 100);
      set_rounded(feature, 5, lod12 ? r.report.rmse_lod12 : lod13 ? r.report.rmse_lod13 : r.report.rmse_lod22, 10000);
      feature.SetField(6, "[]");  // the level as written is valid (an invalid model is never written)
      feature.SetField(7, surfaces.c_str());
      feature.SetGeometry(&solid);
      if (level->solid->CreateFeature(&feature) != OGRERR_NONE)
        fail("cannot write the LoD" + g.lod + " model of " + r.report.id);
    }
  }
  if (ds->CommitTransaction() != OGRERR_NONE) fail("cannot commit the levels of detail");

  // `roof_parts`, as earlier versions wrote it: a view of lod22_2d with its columns, registered as a
  // feature layer (GDAL and QGIS open it as one), so that no roof face is stored twice.
  ds->FlushCache();
  for (const char* sql :
       {"CREATE VIEW roof_parts AS SELECT fid, geom, building_id, part, h_min, h_max, h_mean, slope, azimuth, area "
        "FROM lod22_2d",
        "INSERT INTO gpkg_contents (table_name, data_type, identifier, description, last_change, min_x, min_y, max_x, "
        "max_y, srs_id) SELECT 'roof_parts', data_type, 'roof_parts', 'the LoD2.2 roof parts (a view of lod22_2d)', "
        "last_change, min_x, min_y, max_x, max_y, srs_id FROM gpkg_contents WHERE table_name = 'lod22_2d'",
        "INSERT INTO gpkg_geometry_columns (table_name, column_name, geometry_type_name, srs_id, z, m) SELECT "
        "'roof_parts', column_name, geometry_type_name, srs_id, z, m FROM gpkg_geometry_columns WHERE table_name = "
        "'lod22_2d'"}) {
    CPLErrorReset();
    ds->ExecuteSQL(sql, nullptr, nullptr);
    if (CPLGetLastErrorType() >= CE_Failure) fail("cannot create the view roof_parts");
  }
  ds.reset();
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(temp.c_str());
    throw IoError("gpkg: cannot rename " + temp + " to " + path + ": " + why);
  }
}

}  // namespace city3d
