// Synthetic face-selection problems shaped like real City3D hypotheses, for bench_selection and
// test_selection: a footprint grid of cells, a few candidate roof heights per cell, wall strips on
// every cell boundary between consecutive heights, a floor per cell, and a random "true" building
// (rectangular blocks of different heights) that decides the support of each face.
#pragma once

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "city3d/selection.hpp"

namespace city3d::bench {

struct BuildingShape {
  int cells_x = 4;         ///< footprint grid columns
  int cells_y = 3;         ///< footprint grid rows
  int levels = 2;          ///< candidate roof heights (horizontal planes)
  int blocks = 2;          ///< rectangular blocks of the true building
  bool face_prior = true;  ///< fill SelectionProblem::face_prior (best face of each roof level)
};

/// Builds the problem for `shape` from `seed`. Deterministic (std::mt19937 with explicit draws).
inline SelectionProblem building_problem(const BuildingShape& shape, std::uint32_t seed) {
  std::mt19937 rng(seed);
  const auto uniform = [&rng](double lo, double hi) {
    return lo + (hi - lo) * (static_cast<double>(rng() >> 8) / static_cast<double>(1u << 24));
  };
  const int nx = shape.cells_x, ny = shape.cells_y, nk = shape.levels;
  const double cell = 3.0;                   // metres
  std::vector<double> level_z(nk + 1, 0.0);  // level 0 is the ground
  for (int k = 1; k <= nk; ++k) level_z[k] = level_z[k - 1] + uniform(2.0, 4.0);

  // True height level of every cell: blocks painted over a base level.
  std::vector<int> truth(nx * ny, 1);
  for (int b = 0; b < shape.blocks; ++b) {
    const int x0 = static_cast<int>(rng() % nx), y0 = static_cast<int>(rng() % ny);
    const int x1 = std::min(nx, x0 + 1 + static_cast<int>(rng() % std::max(1, nx / 2)));
    const int y1 = std::min(ny, y0 + 1 + static_cast<int>(rng() % std::max(1, ny / 2)));
    const int k = 1 + static_cast<int>(rng() % nk);
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) truth[y * nx + x] = k;
  }
  const double points_per_m2 = 8.0;

  SelectionProblem p;
  std::vector<int> roof_level_of_face;  // -1 for walls and floors
  const auto add_face = [&](double support, double z, bool roof, int level) {
    p.support.push_back(std::max(0.0, support));
    p.centroid_z.push_back(z);
    p.is_roof.push_back(roof);
    roof_level_of_face.push_back(roof ? level : -1);
    return static_cast<std::uint32_t>(p.support.size() - 1);
  };
  const double cell_points = points_per_m2 * cell * cell;
  // floor[c], roof[c][k-1]
  std::vector<std::uint32_t> floor(nx * ny);
  std::vector<std::vector<std::uint32_t>> roof(nx * ny, std::vector<std::uint32_t>(nk));
  for (int c = 0; c < nx * ny; ++c) {
    floor[c] = add_face(0.0, 0.0, false, -1);  // aerial LiDAR sees no floor
    for (int k = 1; k <= nk; ++k) {
      const double support =
          truth[c] == k ? cell_points * uniform(0.8, 1.0) : cell_points * uniform(0.0, 0.08);
      roof[c][k - 1] = add_face(support, level_z[k], true, k);
    }
  }
  // Boundary segments: horizontal ones (between (x, y-1) and (x, y)) for y in 0..ny, vertical ones
  // (between (x-1, y) and (x, y)) for x in 0..nx. Cell index -1 is outside.
  struct Segment {
    int cell_a, cell_b;
    bool along_x;
    int gx, gy;  // grid coordinates of its first end
  };
  std::vector<Segment> segments;
  for (int y = 0; y <= ny; ++y)
    for (int x = 0; x < nx; ++x)
      segments.push_back({y > 0 ? (y - 1) * nx + x : -1, y < ny ? y * nx + x : -1, true, x, y});
  for (int x = 0; x <= nx; ++x)
    for (int y = 0; y < ny; ++y)
      segments.push_back({x > 0 ? y * nx + x - 1 : -1, x < nx ? y * nx + x : -1, false, x, y});
  const auto level_of = [&](int c) { return c < 0 ? 0 : truth[c]; };
  // strip[s][k]: wall between level k and k+1 on segment s.
  std::vector<std::vector<std::uint32_t>> strip(segments.size(), std::vector<std::uint32_t>(nk));
  for (std::size_t s = 0; s < segments.size(); ++s) {
    const int lo = std::min(level_of(segments[s].cell_a), level_of(segments[s].cell_b));
    const int hi = std::max(level_of(segments[s].cell_a), level_of(segments[s].cell_b));
    for (int k = 0; k < nk; ++k) {
      const double area = cell * (level_z[k + 1] - level_z[k]);
      const bool real = k >= lo && k < hi;
      // Walls get few points from above: a fraction of their area.
      const double support = area * points_per_m2 * (real ? uniform(0.15, 0.3) : uniform(0.0, 0.02));
      strip[s][k] = add_face(support, 0.5 * (level_z[k] + level_z[k + 1]), false, -1);
    }
  }
  p.face_count = p.support.size();
  p.point_count = 0;
  for (int c = 0; c < nx * ny; ++c) p.point_count += static_cast<std::size_t>(cell_points);
  p.z_min = 0.0;
  p.z_max = level_z[nk] + 0.5;

  const auto horizontal_at = [&](int c, int k) { return k == 0 ? floor[c] : roof[c][k - 1]; };
  // Horizontal edges: along each segment at each level.
  for (std::size_t s = 0; s < segments.size(); ++s) {
    for (int k = 0; k <= nk; ++k) {
      SelectionProblem::Edge e;
      std::vector<std::uint32_t> flats, walls;
      for (int c : {segments[s].cell_a, segments[s].cell_b})
        if (c >= 0) flats.push_back(horizontal_at(c, k));
      if (k > 0) walls.push_back(strip[s][k - 1]);
      if (k < nk) walls.push_back(strip[s][k]);
      e.faces = flats;
      e.faces.insert(e.faces.end(), walls.begin(), walls.end());
      for (auto f : flats)
        for (auto w : walls) e.sharp_pairs.emplace_back(f, w);
      p.edges.push_back(std::move(e));
    }
  }
  // Vertical edges: at each grid vertex, between consecutive levels, the strips of incident segments.
  std::vector<std::vector<std::size_t>> at_vertex((nx + 1) * (ny + 1));
  for (std::size_t s = 0; s < segments.size(); ++s) {
    const auto& g = segments[s];
    at_vertex[g.gy * (nx + 1) + g.gx].push_back(s);
    const int ex = g.along_x ? g.gx + 1 : g.gx, ey = g.along_x ? g.gy : g.gy + 1;
    at_vertex[ey * (nx + 1) + ex].push_back(s);
  }
  for (const auto& incident : at_vertex) {
    for (int k = 0; k < nk; ++k) {
      SelectionProblem::Edge e;
      for (auto s : incident) e.faces.push_back(strip[s][k]);
      for (std::size_t i = 0; i < incident.size(); ++i)
        for (std::size_t j = i + 1; j < incident.size(); ++j)
          if (segments[incident[i]].along_x != segments[incident[j]].along_x)
            e.sharp_pairs.emplace_back(strip[incident[i]][k], strip[incident[j]][k]);
      p.edges.push_back(std::move(e));
    }
  }
  // Roof faces of one cell at different heights overlap vertically.
  for (int c = 0; c < nx * ny; ++c)
    for (int a = 0; a < nk; ++a)
      for (int b = a + 1; b < nk; ++b) p.vertical_overlaps.emplace_back(roof[c][a], roof[c][b]);
  // Face prior: the best-supported face of each roof plane (level) that has real points.
  if (shape.face_prior)
    for (int k = 1; k <= nk; ++k) {
      std::uint32_t best = 0;
      double best_support = -1.0;
      for (int c = 0; c < nx * ny; ++c)
        if (p.support[roof[c][k - 1]] > best_support) {
          best_support = p.support[roof[c][k - 1]];
          best = roof[c][k - 1];
        }
      if (best_support > 0.5 * cell_points) p.face_prior.push_back(best);
    }
  return p;
}

}  // namespace city3d::bench
