// GeoPackage output through OGR: the footprints with every report attribute (layer `buildings`) and
// the LoD2.2 roof parts in plan view with heights, slope and azimuth (layer `roof_parts`).
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
#include "pipeline/report.hpp"

namespace city3d {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The field type that holds every value a name takes: integers stay 64-bit integers, integers
// mixed with numbers become reals, anything mixed with text becomes text.
enum class Kind { none, boolean, integer, real, text };

Kind kind_of(const AttributeValue& v) {
  if (std::holds_alternative<bool>(v)) return Kind::boolean;
  if (std::holds_alternative<std::int64_t>(v)) return Kind::integer;
  if (std::holds_alternative<double>(v)) return Kind::real;
  if (std::holds_alternative<std::string>(v)) return Kind::text;
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

  // Layer `roof_parts`: each LoD2.2 roof face in plan view.
  OGRLayer* roofs = ds->CreateLayer("roof_parts", srs_ptr, wkbPolygon, nullptr);
  if (!roofs) fail("cannot create layer roof_parts");
  const std::pair<const char*, OGRFieldType> roof_fields[] = {
      {"building_id", OFTString}, {"part", OFTInteger}, {"h_min", OFTReal},   {"h_max", OFTReal},
      {"h_mean", OFTReal},        {"slope", OFTReal},   {"azimuth", OFTReal}, {"area", OFTReal}};
  for (const auto& [name, type] : roof_fields) {
    OGRFieldDefn field(name, type);
    if (roofs->CreateField(&field) != OGRERR_NONE) fail(std::string("cannot create field ") + name);
  }
  if (ds->StartTransaction() != OGRERR_NONE) fail("cannot start a transaction");
  for (std::size_t k = 0; k < records.size(); ++k) {
    const OverviewRecord r = records.at(k, true);
    for (const CityGeometry& g : r.lods) {
      if (g.lod != "2.2") continue;
      const BuildingModel& m = g.model;
      const std::vector<SurfaceType> types = surface_types(m);
      int part = 0;
      for (std::size_t f = 0; f < m.mesh.faces.size(); ++f) {
        if (types[f] != SurfaceType::roof) continue;
        const auto& face = m.mesh.faces[f];
        double nx = 0, ny = 0, nz = 0, lo = INFINITY, hi = -INFINITY, sum = 0;
        OGRLinearRing ring;
        for (std::size_t k = 0; k < face.size(); ++k) {
          const Point3& a = m.mesh.vertices[face[k]];
          const Point3& b = m.mesh.vertices[face[(k + 1) % face.size()]];
          nx += (a.y - b.y) * (a.z + b.z);
          ny += (a.z - b.z) * (a.x + b.x);
          nz += (a.x - b.x) * (a.y + b.y);
          const double z = a.z + m.origin.z;
          lo = std::min(lo, z), hi = std::max(hi, z), sum += z;
          ring.addPoint(a.x + m.origin.x, a.y + m.origin.y);
        }
        ring.closeRings();
        const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
        if (!(len > 0)) continue;
        OGRPolygon polygon;
        polygon.addRing(&ring);
        OGRFeature feature(roofs->GetLayerDefn());
        feature.SetField(0, r.report.id.c_str());
        feature.SetField(1, part++);
        feature.SetField(2, std::round(lo * 1000) / 1000);
        feature.SetField(3, std::round(hi * 1000) / 1000);
        feature.SetField(4, std::round(sum / face.size() * 1000) / 1000);
        const double slope = std::acos(std::min(1.0, std::fabs(nz) / len)) * 180.0 / kPi;
        feature.SetField(5, std::round(slope * 100) / 100);
        // The horizontal part of the normal points downhill; azimuth clockwise from north (+y).
        double azimuth = std::atan2(nx, ny) * 180.0 / kPi;
        if (azimuth < 0) azimuth += 360.0;
        if (slope < 0.01) feature.SetFieldNull(6);
        else feature.SetField(6, std::round(azimuth * 100) / 100);
        feature.SetField(7, std::round(std::fabs(nz) / 2 * 100) / 100);
        feature.SetGeometry(&polygon);
        if (roofs->CreateFeature(&feature) != OGRERR_NONE) fail("cannot write a roof part of " + r.report.id);
      }
    }
  }
  if (ds->CommitTransaction() != OGRERR_NONE) fail("cannot commit the roof parts");
  ds.reset();
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(temp.c_str());
    throw IoError("gpkg: cannot rename " + temp + " to " + path + ": " + why);
  }
}

}  // namespace city3d
