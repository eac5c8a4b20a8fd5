// OBJ and PLY model writers: polygonal faces, world coordinates at 0.1 mm or local coordinates with
// the origin recorded, one building per file or many per file.
#include "city3d/model_io.hpp"

#include <cinttypes>
#include <cstdio>
#include <cstring>

#include "city3d/error.hpp"
#include "files/atomic_file.hpp"

namespace city3d {
namespace {

// World coordinates at RD New magnitudes (~447 000 m) have 6 integer digits; 4 decimals keep
// 0.1 mm, well below the 1 mm the data (LAS scale 0.001) carries. Local coordinates get 6 decimals.
constexpr const char* kWorldFormat = "%.4f";
constexpr const char* kLocalFormat = "%.6f";

Point3 output_point(const BuildingModel& m, const Point3& p, bool local) {
  if (local) return p;
  return {p.x + m.origin.x, p.y + m.origin.y, p.z + m.origin.z};
}

void check_mesh_indices(const BuildingModel& m) {
  for (std::size_t f = 0; f < m.mesh.faces.size(); ++f) {
    const auto& face = m.mesh.faces[f];
    if (face.size() < 3)
      throw IoError("write: building " + m.id + " face " + std::to_string(f) + " has fewer than 3 vertices");
    for (std::uint32_t v : face)
      if (v >= m.mesh.vertices.size())
        throw IoError("write: building " + m.id + " face " + std::to_string(f) + " uses vertex " +
                      std::to_string(v) + " of " + std::to_string(m.mesh.vertices.size()));
  }
}

void print_coordinate_triple(std::FILE* out, const char* prefix, const Point3& p, bool local) {
  const char* fmt = local ? kLocalFormat : kWorldFormat;
  std::fputs(prefix, out);
  std::fprintf(out, fmt, p.x);
  std::fputc(' ', out);
  std::fprintf(out, fmt, p.y);
  std::fputc(' ', out);
  std::fprintf(out, fmt, p.z);
  std::fputc('\n', out);
}

// OBJ: one `o <id>` object per building, its faces grouped by semantic surface (ground, walls,
// roofs: `g` and `usemtl` RoofSurface, WallSurface, GroundSurface, materials of kSurfaceMaterials,
// so that Blender or MeshLab tell them apart); indices are global (1-based) across objects.
void write_obj(std::FILE* out, const std::vector<BuildingModel>& models, const ModelWriteOptions& options) {
  std::fprintf(out, "# city3d %s\n", CITY3D_VERSION);
  std::fputs(options.local_coordinates ? "# local coordinates: world = local + origin of each building\n"
                                       : "# world coordinates\n",
             out);
  std::fprintf(out, "mtllib %s\n", kSurfaceMaterialFile);
  std::size_t base = 1;
  for (const BuildingModel& m : models) {
    if (options.local_coordinates) print_coordinate_triple(out, "# origin ", m.origin, false);
    std::fprintf(out, "o %s\n", m.id.c_str());
    for (const Point3& p : m.mesh.vertices)
      print_coordinate_triple(out, "v ", output_point(m, p, options.local_coordinates), options.local_coordinates);
    const std::vector<SurfaceType> types = surface_types(m);
    for (const SurfaceType type : {SurfaceType::ground, SurfaceType::wall, SurfaceType::roof}) {
      bool started = false;
      for (std::size_t f = 0; f < m.mesh.faces.size(); ++f) {
        if (types[f] != type) continue;
        if (!started) std::fprintf(out, "g %s\nusemtl %s\n", surface_type_name(type), surface_type_name(type));
        started = true;
        std::fputc('f', out);
        for (std::uint32_t v : m.mesh.faces[f]) std::fprintf(out, " %zu", base + v);
        std::fputc('\n', out);
      }
    }
    base += m.mesh.vertices.size();
  }
}

bool host_is_little_endian() {
  const std::uint16_t probe = 1;
  std::uint8_t first;
  std::memcpy(&first, &probe, 1);
  return first == 1;
}

template <typename T>
void put_le(std::FILE* out, T value) {
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if (!host_is_little_endian())
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
  std::fwrite(bytes, 1, sizeof(T), out);
}

// PLY: vertices as double (world or local), faces as a vertex-index list; with several buildings a
// per-face `building` index refers to the `comment building <index> <id>` lines.
void write_ply(std::FILE* out, const std::vector<BuildingModel>& models, const ModelWriteOptions& options,
               bool binary) {
  std::size_t vertex_count = 0, face_count = 0, max_degree = 0;
  for (const BuildingModel& m : models) {
    vertex_count += m.mesh.vertices.size();
    face_count += m.mesh.faces.size();
    for (const auto& f : m.mesh.faces) max_degree = std::max(max_degree, f.size());
  }
  const bool per_face_building = models.size() > 1;
  const bool small_lists = max_degree <= 255;
  std::fputs("ply\n", out);
  std::fputs(binary ? "format binary_little_endian 1.0\n" : "format ascii 1.0\n", out);
  std::fprintf(out, "comment city3d %s\n", CITY3D_VERSION);
  for (std::size_t i = 0; i < models.size(); ++i) {
    std::fprintf(out, "comment building %zu %s\n", i, models[i].id.c_str());
    if (options.local_coordinates)
      std::fprintf(out, "comment origin %zu %.4f %.4f %.4f\n", i, models[i].origin.x, models[i].origin.y,
                   models[i].origin.z);
  }
  std::fprintf(out, "comment %s coordinates\n", options.local_coordinates ? "local" : "world");
  std::fprintf(out, "element vertex %zu\n", vertex_count);
  std::fputs("property double x\nproperty double y\nproperty double z\n", out);
  std::fprintf(out, "element face %zu\n", face_count);
  std::fputs(small_lists ? "property list uchar int vertex_indices\n" : "property list int int vertex_indices\n",
             out);
  if (per_face_building) std::fputs("property int building\n", out);
  std::fputs("end_header\n", out);

  for (const BuildingModel& m : models) {
    for (const Point3& v : m.mesh.vertices) {
      const Point3 p = output_point(m, v, options.local_coordinates);
      if (binary) {
        put_le(out, p.x);
        put_le(out, p.y);
        put_le(out, p.z);
      } else {
        print_coordinate_triple(out, "", p, options.local_coordinates);
      }
    }
  }
  std::size_t base = 0;
  for (std::size_t b = 0; b < models.size(); ++b) {
    const BuildingModel& m = models[b];
    for (const auto& face : m.mesh.faces) {
      if (binary) {
        if (small_lists)
          put_le(out, static_cast<std::uint8_t>(face.size()));
        else
          put_le(out, static_cast<std::int32_t>(face.size()));
        for (std::uint32_t v : face) put_le(out, static_cast<std::int32_t>(base + v));
        if (per_face_building) put_le(out, static_cast<std::int32_t>(b));
      } else {
        std::fprintf(out, "%zu", face.size());
        for (std::uint32_t v : face) std::fprintf(out, " %zu", base + v);
        if (per_face_building) std::fprintf(out, " %zu", b);
        std::fputc('\n', out);
      }
    }
    base += m.mesh.vertices.size();
  }
}

}  // namespace

MeshFormat parse_mesh_format(const std::string& name) {
  if (name == "obj") return MeshFormat::obj;
  if (name == "ply") return MeshFormat::ply_binary;
  if (name == "ply-ascii") return MeshFormat::ply_ascii;
  throw ConfigError("format: unknown model format '" + name + "' (expected obj, ply or ply-ascii)");
}

std::string mesh_extension(MeshFormat format) { return format == MeshFormat::obj ? ".obj" : ".ply"; }

std::string model_file_name(const BuildingId& id, MeshFormat format) {
  std::string name;
  name.reserve(id.size());
  bool changed = false;
  for (char c : id) {
    const bool safe = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '.' ||
                      c == '_' || c == '-';
    name += safe ? c : '_';
    changed = changed || !safe;
  }
  // Never empty, never a hidden file or "..".
  if (name.empty() || name[0] == '.') name.insert(name.begin(), '_'), changed = true;
  // Never longer than a file name may be (255 bytes), with the hash, the extension and the temporary
  // name's suffix (AtomicFile) added: a 300-character id, or a cloud's 240-character file name.
  constexpr std::size_t kMaxNameBytes = 200;
  if (name.size() > kMaxNameBytes) name.resize(kMaxNameBytes), changed = true;
  // Two ids that differ only where characters were replaced ("a b" and "a_b", "DALES/00011" and
  // "DALES_00011") must not share a file: a changed name carries the id's hash (32-bit FNV-1a).
  if (changed) {
    std::uint32_t hash = 2166136261u;
    for (unsigned char c : id) hash = (hash ^ c) * 16777619u;
    char suffix[16];
    std::snprintf(suffix, sizeof suffix, "-%08x", hash);
    name += suffix;
  }
  return name + mesh_extension(format);
}

void write_models(const std::string& path, const std::vector<BuildingModel>& models,
                  const ModelWriteOptions& options) {
  for (const BuildingModel& m : models) check_mesh_indices(m);
  detail::AtomicFile file(path);
  switch (options.format) {
    case MeshFormat::obj:
      write_obj(file.file(), models, options);
      break;
    case MeshFormat::ply_ascii:
      write_ply(file.file(), models, options, false);
      break;
    case MeshFormat::ply_binary:
      write_ply(file.file(), models, options, true);
      break;
  }
  file.commit();
}

void write_surface_materials(const std::string& path) {
  detail::AtomicFile file(path);
  std::fprintf(file.file(),
               "# city3d %s: the materials of the OBJ models' semantic surfaces (CityJSON's types)\n"
               "newmtl GroundSurface\nKd 0.45 0.45 0.45\n"
               "newmtl WallSurface\nKd 0.92 0.91 0.87\n"
               "newmtl RoofSurface\nKd 0.80 0.36 0.28\n",
               CITY3D_VERSION);
  file.commit();
}

void write_model(const std::string& path, const BuildingModel& model, const ModelWriteOptions& options) {
  write_models(path, std::vector<BuildingModel>{model}, options);
}

}  // namespace city3d
