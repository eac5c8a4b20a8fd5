// Repair of a model as it will be written: rounded to the output grid, and when val3dity's rules fail
// on the rounded model, repaired by the mildest change that passes them (faces split into triangles of
// their own vertices, vertices snapped, zero-width spikes cut). The rules themselves are validity.cpp's.
#include "city3d/repair.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "city3d/evaluation.hpp"
#include "core/mesh_faces.hpp"
#include "core/vec.hpp"
#include "evaluation/validity_shared.hpp"

namespace city3d {
namespace {

using namespace detail;  // the helpers of validity_shared.hpp and core/vec.hpp

// Drops repeated consecutive vertices and faces of fewer than three, then unused vertices.
void clean_model(BuildingModel& model) {
  std::vector<std::vector<std::uint32_t>> faces;
  std::vector<SurfaceType> surfaces;
  const bool typed = model.surfaces.size() == model.mesh.faces.size();
  for (std::size_t f = 0; f < model.mesh.faces.size(); ++f) {
    std::vector<std::uint32_t> face;
    for (std::uint32_t i : model.mesh.faces[f])
      if (face.empty() || face.back() != i) face.push_back(i);
    while (face.size() > 1 && face.front() == face.back()) face.pop_back();
    if (face.size() < 3) continue;
    faces.push_back(std::move(face));
    if (typed) surfaces.push_back(model.surfaces[f]);
  }
  std::vector<std::uint32_t> index(model.mesh.vertices.size(), UINT32_MAX);
  std::vector<Point3> vertices;
  for (auto& face : faces)
    for (std::uint32_t& i : face) {
      if (index[i] == UINT32_MAX) {
        index[i] = static_cast<std::uint32_t>(vertices.size());
        vertices.push_back(model.mesh.vertices[i]);
      }
      i = index[i];
    }
  model.mesh.vertices = std::move(vertices);
  model.mesh.faces = std::move(faces);
  if (typed) model.surfaces = std::move(surfaces);
}

// Cuts zero-width spikes off every face: a vertex whose two edges fold back onto each other (the
// same neighbour on both sides, or edges pointing the same way with the shorter one's end within
// `tolerance` of the longer one's line). Returns how many.
std::size_t remove_spikes(BuildingModel& model, double tolerance) {
  std::size_t removed = 0;
  auto& faces = model.mesh.faces;
  for (std::size_t f = 0; f < faces.size(); ++f) {
    auto& face = faces[f];
    for (bool changed = true; changed && face.size() >= 3;) {
      changed = false;
      for (std::size_t k = 0; k < face.size() && face.size() >= 3; ++k) {
        const std::size_t n = face.size();
        const std::uint32_t ia = face[(k + n - 1) % n], ib = face[k], ic = face[(k + 1) % n];
        const Point3& a = model.mesh.vertices[ia];
        const Point3& b = model.mesh.vertices[ib];
        const Point3& c = model.mesh.vertices[ic];
        const Vec ba = sub(a, b), bc = sub(c, b);
        const double lab = norm(ba), lbc = norm(bc);
        const bool same = ia == ic;
        // |ba x bc| / longer edge = distance of the shorter edge's end from the longer edge's line.
        const bool folded = lab > 0 && lbc > 0 && dot(ba, bc) > 0 && norm(cross(ba, bc)) <= tolerance * std::max(lab, lbc);
        if (!same && !folded) continue;
        face.erase(face.begin() + static_cast<std::ptrdiff_t>(k));
        if (same) {
          face.erase(face.begin() + static_cast<std::ptrdiff_t>(k % face.size()));  // a, b, a -> a
        } else {
          // The face across the spike runs c, b, a with b on its edge: it loses b too, so both
          // faces keep sharing the edge a-c.
          for (std::size_t g = 0; g < faces.size(); ++g) {
            if (g == f) continue;
            auto& other = faces[g];
            const std::size_t m = other.size();
            for (std::size_t j = 0; j < m; ++j)
              if (other[j] == ic && other[(j + 1) % m] == ib && other[(j + 2) % m] == ia) {
                other.erase(other.begin() + static_cast<std::ptrdiff_t>((j + 1) % m));
                break;
              }
          }
        }
        ++removed;
        changed = true;
        break;
      }
    }
  }
  return removed;
}

// Polygon-level codes (1xx, 2xx) of one face on its own, as validate_solid() gives them for a solid of
// that face over all the model's vertices; `snapped` is their snap map (snap_vertices()), made once
// for all the faces: made per face it cost a model of 1,500 faces and 2,400 vertices seconds.
std::vector<int> face_codes(const BuildingModel& model, std::size_t f,
                            const std::vector<std::uint32_t>& snapped, const ValidityParams& params) {
  std::vector<int> codes;
  for (const ValidityError& e :
       validate_snapped_solid(model.mesh.vertices, {{{model.mesh.faces[f]}}}, snapped, params))
    if (e.code < 300) codes.push_back(e.code);
  return codes;
}

}  // namespace

void round_to_grid(BuildingModel& model, double grid) {
  // Vertices that round to the same grid point become one, within each edge-connected part only:
  // detached parts (the blocks of a multipolygon touching at a corner) are separate Solids in
  // CityJSON and must stay separate here.
  const std::vector<std::size_t> part_of = detail::edge_connected_parts(model.mesh.faces);
  std::map<std::pair<std::size_t, std::array<long long, 3>>, std::uint32_t> index_of;
  std::vector<Point3> vertices;
  for (std::size_t f = 0; f < model.mesh.faces.size(); ++f) {
    const std::size_t part = part_of[f];
    for (std::uint32_t& i : model.mesh.faces[f]) {
      if (i >= model.mesh.vertices.size()) continue;
      const Point3& p = model.mesh.vertices[i];
      std::array<long long, 3> q;
      Point3 rounded = p;
      if (grid > 0) {
        q = {std::llround((p.x + model.origin.x) / grid), std::llround((p.y + model.origin.y) / grid),
             std::llround((p.z + model.origin.z) / grid)};
        rounded = {q[0] * grid - model.origin.x, q[1] * grid - model.origin.y, q[2] * grid - model.origin.z};
      } else {
        q = {static_cast<long long>(i), 0, 0};  // no rounding: keep vertices apart
      }
      const auto [it, fresh] = index_of.emplace(std::make_pair(part, q), static_cast<std::uint32_t>(vertices.size()));
      if (fresh) vertices.push_back(rounded);
      i = it->second;
    }
  }
  model.mesh.vertices = std::move(vertices);
  clean_model(model);
}

namespace {

// Faces that are not planar as rounded (203, 204), or not simple (104), split into triangles of their
// own vertices. Returns how many faces were split.
std::size_t split_bad_faces(BuildingModel& model, const ValidityParams& params) {
  std::vector<std::vector<std::uint32_t>> faces;
  std::vector<SurfaceType> surfaces;
  const bool typed = model.surfaces.size() == model.mesh.faces.size();
  std::size_t split = 0;
  const std::vector<std::uint32_t> snapped = snap_vertices(model.mesh.vertices, params.snap_tolerance);
  for (std::size_t f = 0; f < model.mesh.faces.size(); ++f) {
    const std::vector<int> codes = face_codes(model, f, snapped, params);
    const bool bad = std::any_of(codes.begin(), codes.end(), [](int c) { return c == 203 || c == 204 || c == 104; });
    if (!bad || model.mesh.faces[f].size() <= 3) {
      faces.push_back(model.mesh.faces[f]);
      if (typed) surfaces.push_back(model.surfaces[f]);
      continue;
    }
    PolygonMesh one;
    one.vertices = model.mesh.vertices;
    one.faces = {model.mesh.faces[f]};
    for (const auto& t : triangulate(one)) {
      faces.push_back({t[0], t[1], t[2]});
      if (typed) surfaces.push_back(model.surfaces[f]);
    }
    ++split;
  }
  model.mesh.faces = std::move(faces);
  if (typed) model.surfaces = std::move(surfaces);
  return split;
}

std::string plural(std::size_t n, const char* what) {
  const std::string w = what;
  return std::to_string(n) + " " + (n > 1 ? (w == "vertex" ? std::string("vertices") : w + "s") : w);
}

}  // namespace

WrittenValidity validate_as_written(BuildingModel& model, double grid, const ValidityParams& params) {
  WrittenValidity result;
  round_to_grid(model, grid);
  result.found = validate_model(model.mesh, params);
  result.remaining = result.found;
  if (result.found.empty()) return result;

  // Repairs, mildest first; the first that leaves a valid model wins. (1) Split the faces the
  // rounding bent (or that are not simple) into triangles of their own vertices: nothing moves.
  // (2) Snap: vertices closer than the snap tolerance become one (what val3dity does before it
  // checks, so that it finds no repeated point, 102), then split. (3) Cut zero-width spikes (a
  // vertex whose edges fold back onto each other), then split.
  for (int attempt = 0; attempt < 3; ++attempt) {
    BuildingModel repaired = model;
    std::string repairs;
    if (attempt == 1) {
      const std::vector<std::uint32_t> to = snap_vertices(repaired.mesh.vertices, params.snap_tolerance);
      std::size_t merged = 0;
      for (std::uint32_t i = 0; i < to.size(); ++i) merged += to[i] != i;
      if (merged == 0) continue;
      for (auto& face : repaired.mesh.faces)
        for (std::uint32_t& i : face)
          if (i < to.size()) i = to[i];
      round_to_grid(repaired, grid);
      repairs = "snapped " + plural(merged, "vertex") + " onto a neighbour within " +
                format(params.snap_tolerance * 1000, 1) + " mm";
    }
    if (attempt == 2) {
      const std::size_t spikes = remove_spikes(repaired, std::max(params.snap_tolerance, grid));
      if (spikes == 0) continue;
      round_to_grid(repaired, grid);
      repairs = "cut " + plural(spikes, "zero-width spike");
    }
    const std::size_t split = split_bad_faces(repaired, params);
    if (split) {
      round_to_grid(repaired, grid);
      repairs += (repairs.empty() ? "" : "; ") + std::string("split ") + plural(split, "face") + " into triangles";
    }
    if (repairs.empty()) continue;
    std::vector<ValidityError> remaining = validate_model(repaired.mesh, params);
    if (remaining.empty()) {
      model = std::move(repaired);
      result.remaining.clear();
      result.repairs = repairs;
      return result;
    }
  }
  return result;  // not repaired: the model stays as built (rounded), e.g. for --debug
}

}  // namespace city3d
