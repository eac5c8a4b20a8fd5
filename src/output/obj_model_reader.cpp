// OBJ model reader: enough of the format to read back our models and the OBJ models other tools
// (City3D, PolyFit, MeshLab) write, for evaluation.
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "city3d/error.hpp"
#include "city3d/model_io.hpp"

namespace city3d {

BuildingModel read_obj_model(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("obj: cannot open " + path + ": " + std::strerror(errno));
  BuildingModel model;
  model.id = std::filesystem::path(path).stem().string();
  std::string line;
  std::size_t line_number = 0;
  auto fail = [&](const std::string& what) {
    throw IoError("obj: " + path + " line " + std::to_string(line_number) + ": " + what);
  };
  // city3d's --local-coordinates models: "# origin x y z" before a building's vertices, which are
  // relative to it (world = local + origin).
  Point3 origin{0.0, 0.0, 0.0};
  while (std::getline(in, line)) {
    ++line_number;
    if (line.rfind("# origin ", 0) == 0) {
      double xyz[3];
      const char* p = line.c_str() + 9;
      bool read = true;
      for (double& c : xyz) {
        char* end = nullptr;
        c = std::strtod(p, &end);
        read = read && end != p && std::isfinite(c);
        p = end;
      }
      if (read) origin = {xyz[0], xyz[1], xyz[2]};
      continue;
    }
    if (line.size() < 2 || line[1] != ' ' || (line[0] != 'v' && line[0] != 'f')) continue;
    const char* p = line.c_str() + 2;
    if (line[0] == 'v') {
      double xyz[3];
      for (double& c : xyz) {
        char* end = nullptr;
        c = std::strtod(p, &end);
        if (end == p || !std::isfinite(c)) fail("malformed vertex '" + line + "'");
        p = end;
      }
      model.mesh.vertices.push_back({xyz[0] + origin.x, xyz[1] + origin.y, xyz[2] + origin.z});
    } else {
      std::vector<std::uint32_t> face;
      for (;;) {
        while (*p == ' ' || *p == '\t' || *p == '\r') ++p;
        if (*p == '\0') break;
        char* end = nullptr;
        const long index = std::strtol(p, &end, 10);
        if (end == p || index == 0) fail("malformed face '" + line + "'");
        const long n = static_cast<long>(model.mesh.vertices.size());
        const long resolved = index > 0 ? index - 1 : n + index;  // negative: relative to the end
        if (resolved < 0 || resolved >= n) fail("face uses vertex " + std::to_string(index) + " of " + std::to_string(n));
        face.push_back(static_cast<std::uint32_t>(resolved));
        p = end;
        while (*p && *p != ' ' && *p != '\t') ++p;  // skip "/vt/vn"
      }
      if (face.size() < 3) fail("face with fewer than 3 vertices");
      model.mesh.faces.push_back(std::move(face));
    }
  }
  if (model.mesh.faces.empty()) throw IoError("obj: " + path + " holds no face");
  return model;
}

}  // namespace city3d
