// Fuzz harness: City3D OBJ footprint files (vertices, faces with i/t/n references and negative
// indices, o/g names, ring clean-up and repair).
#include <cmath>
#include <cstdint>

#include "city3d/error.hpp"
#include "fuzz_input.hpp"
#include "footprints/footprint_readers.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  city3d::fuzz::quiet_logging();
  const city3d::fuzz::MemoryFile file(data, size);
  try {
    const city3d::FootprintSet set = city3d::detail::read_obj_footprints(file.path(), {});
    // Every footprint that came out is usable: at least 3 distinct vertices per outer ring.
    for (const city3d::Footprint& f : set.footprints) {
      if (f.polygons.empty()) __builtin_trap();
      for (const city3d::Polygon2& p : f.polygons)
        if (p.outer.size() < 3) __builtin_trap();
    }
  } catch (const city3d::Error&) {
  }
  return 0;
}
