// Fuzz harness: footprints through GDAL/OGR, as GeoJSON in GDAL's in-memory file system (/vsimem/):
// layer choice, id and ground fields, geometry conversion, MakeValid repair. GDAL itself is not
// instrumented; the harness checks what city3d does with what GDAL hands it.
#include <cpl_vsi.h>

#include <cstdint>
#include <string>

#include "city3d/error.hpp"
#include "city3d/footprint_io.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  city3d::fuzz::quiet_logging();
  const std::string path = "/vsimem/city3d_fuzz.geojson";
  // GDAL reads the buffer in place (no copy, not taken over).
  VSILFILE* f = VSIFileFromMemBuffer(path.c_str(), const_cast<GByte*>(data), static_cast<vsi_l_offset>(size), FALSE);
  if (f == nullptr) return 0;
  VSIFCloseL(f);
  try {
    city3d::FootprintReadOptions options;
    options.ground_field = size % 2 ? "h" : "";
    options.id_field = size % 3 == 0 ? "id" : "";
    // Reprojection into the points' CRS, and a region in it (the block reads of a run).
    if (size % 5 == 0) options.target_srs = "EPSG:28992";
    if (size % 7 == 0) {
      city3d::Box2 box;
      box.add({84950.0, 447500.0});
      box.add({85050.0, 447600.0});
      options.bbox = box;
    }
    const city3d::FootprintSet set = city3d::read_footprints(path, options);
    for (const city3d::Footprint& fp : set.footprints) {
      if (fp.polygons.empty()) __builtin_trap();
      for (const city3d::Polygon2& p : fp.polygons)
        if (p.outer.size() < 3) __builtin_trap();
    }
  } catch (const city3d::Error&) {
  }
  VSIUnlink(path.c_str());
  return 0;
}
