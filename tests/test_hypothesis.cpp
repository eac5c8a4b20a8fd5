// Tests of the face hypothesis (candidate faces, SelectionProblem) and the model assembly, on
// synthetic buildings built in code (fixed seed, 0.03 m noise). Selection uses a small exact
// reference selector written here, so these tests do not depend on the solver backends.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/evaluation.hpp"
#include "city3d/hypothesis.hpp"
#include "city3d/mesh_check.hpp"
#include "city3d/model.hpp"
#include "city3d/selection.hpp"
#include "hypothesis/geometry.hpp"

namespace city3d {
namespace {

// ------------------------------------------------------------------------------------------------
// Synthetic buildings.

struct RoofPart {
  Ring2 region;   // xy region of the roof plane, counter-clockwise
  double sx, sy, z0;  // z = sx x + sy y + z0
};

struct Synthetic {
  std::vector<Point3> points;
  std::vector<PlanarSegment> roofs;
  std::vector<VerticalPlane> walls;
  std::vector<Polygon2> footprint;
  double ground_z = 0.0;
  bool ground_measured = true;
  double volume = 0.0;  // exact volume of the intended model
};

bool inside(const Ring2& ring, double x, double y) {
  bool in = false;
  for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) {
    const auto& a = ring[i];
    const auto& b = ring[j];
    if ((a.y > y) != (b.y > y) && x < (b.x - a.x) * (y - a.y) / (b.y - a.y) + a.x) in = !in;
  }
  return in;
}

Plane3 plane_of(const RoofPart& part) {
  const double n = std::sqrt(part.sx * part.sx + part.sy * part.sy + 1.0);
  return {-part.sx / n, -part.sy / n, 1.0 / n, -part.z0 / n};
}

Synthetic make_building(const std::vector<Polygon2>& footprint, const std::vector<RoofPart>& parts,
                        double volume, std::uint32_t seed = 7) {
  Synthetic b;
  b.footprint = footprint;
  b.volume = volume;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.1, 0.1);
  std::normal_distribution<double> noise(0.0, 0.03);
  const double spacing = 0.35;  // about 8 points per m2, as AHN3
  for (const auto& part : parts) {
    PlanarSegment seg;
    seg.plane = plane_of(part);
    seg.kind = PlanarSegment::Kind::roof;
    Box2 box;
    for (const auto& p : part.region) box.add(p);
    for (double y = box.min.y + spacing / 2; y < box.max.y; y += spacing) {
      for (double x = box.min.x + spacing / 2; x < box.max.x; x += spacing) {
        const double px = x + jitter(rng), py = y + jitter(rng);
        if (!inside(part.region, px, py)) continue;
        seg.points.push_back(static_cast<std::uint32_t>(b.points.size()));
        b.points.push_back({px, py, part.sx * px + part.sy * py + part.z0 + noise(rng)});
      }
    }
    b.roofs.push_back(seg);
  }
  // Outer walls from the footprint (the hypothesis uses the footprint itself; these are passed for
  // realism and must be ignored).
  for (const auto& poly : footprint) {
    for (std::size_t i = 0; i < poly.outer.size(); ++i) {
      VerticalPlane w;
      w.a = poly.outer[i];
      w.b = poly.outer[(i + 1) % poly.outer.size()];
      const double len = std::hypot(w.b.x - w.a.x, w.b.y - w.a.y);
      w.normal = {(w.b.y - w.a.y) / len, -(w.b.x - w.a.x) / len};
      w.offset = w.normal.x * w.a.x + w.normal.y * w.a.y;
      w.outer = true;
      w.source = VerticalPlane::Source::footprint;
      b.walls.push_back(w);
    }
  }
  return b;
}

Polygon2 rectangle(double x0, double y0, double x1, double y1) {
  return Polygon2{{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}, {}};
}

Synthetic box_building() {  // 10 x 6, flat roof at 5 m
  return make_building({rectangle(0, 0, 10, 6)}, {{{{0, 0}, {10, 0}, {10, 6}, {0, 6}}, 0.0, 0.0, 5.0}}, 300.0);
}

Synthetic gable_building() {  // 10 x 8, ridge along x at y = 4: eaves 4 m, ridge 6 m
  return make_building({rectangle(0, 0, 10, 8)},
                       {{{{0, 0}, {10, 0}, {10, 4}, {0, 4}}, 0.0, 0.5, 4.0},
                        {{{0, 4}, {10, 4}, {10, 8}, {0, 8}}, 0.0, -0.5, 8.0}},
                       10.0 * (8.0 * 4.0 + 0.5 * 8.0 * 2.0));
}

Synthetic l_building() {  // L-shape, flat at 3 m, area 64 m2
  const Ring2 ring{{0, 0}, {10, 0}, {10, 4}, {4, 4}, {4, 10}, {0, 10}};
  return make_building({Polygon2{ring, {}}}, {{ring, 0.0, 0.0, 3.0}}, 64.0 * 3.0);
}

Synthetic step_building() {  // 12 x 6: x < 6 at 7 m, x > 6 at 4 m, an inner wall at x = 6
  Synthetic b = make_building({rectangle(0, 0, 12, 6)},
                              {{{{0, 0}, {6, 0}, {6, 6}, {0, 6}}, 0.0, 0.0, 7.0},
                               {{{6, 0}, {12, 0}, {12, 6}, {6, 6}}, 0.0, 0.0, 4.0}},
                              36.0 * 7.0 + 36.0 * 4.0);
  VerticalPlane inner;
  inner.a = {6, 0};
  inner.b = {6, 6};
  inner.normal = {-1, 0};
  inner.offset = -6;
  inner.outer = false;
  b.walls.push_back(inner);
  return b;
}

Synthetic courtyard_building() {  // 12 x 12 with a 4 x 4 courtyard in the middle, flat at 5 m
  Polygon2 poly = rectangle(0, 0, 12, 12);
  poly.holes.push_back({{4, 4}, {4, 8}, {8, 8}, {8, 4}});  // clockwise
  Synthetic b = make_building({rectangle(0, 0, 12, 12)}, {{{{0, 0}, {12, 0}, {12, 12}, {0, 12}}, 0.0, 0.0, 5.0}},
                              (144.0 - 16.0) * 5.0);
  // No roof points over the courtyard.
  std::vector<Point3> kept;
  PlanarSegment seg = b.roofs[0];
  seg.points.clear();
  for (const auto& p : b.points) {
    if (p.x > 4 && p.x < 8 && p.y > 4 && p.y < 8) continue;
    seg.points.push_back(static_cast<std::uint32_t>(kept.size()));
    kept.push_back(p);
  }
  b.points = kept;
  b.roofs = {seg};
  b.footprint = {poly};
  return b;
}

CandidateFaces candidates_of(const Synthetic& b, const HypothesisParams& params = {}) {
  return generate_candidates(b.points, b.roofs, b.walls, b.footprint, b.ground_z, b.ground_measured, params);
}

std::size_t count_kind(const CandidateFaces& c, FaceKind kind) {
  return static_cast<std::size_t>(
      std::count_if(c.faces.begin(), c.faces.end(), [&](const CandidateFace& f) { return f.kind == kind; }));
}

// ------------------------------------------------------------------------------------------------
// Reference selector: exact minimum of the contract's energy by depth-first search with constraint
// pruning (edges 0 or 2, single layer, face prior, forced faces). Only for small problems.

double reference_energy(const SelectionProblem& p, const std::vector<bool>& x, const SelectionParams& w) {
  double support = 0.0, roof = 0.0, corners = 0.0;
  for (std::size_t i = 0; i < p.face_count; ++i) {
    if (!x[i]) continue;
    support += p.support[i];
    roof += (p.z_max - p.centroid_z[i]) / (p.z_max - p.z_min);
  }
  for (const auto& e : p.edges)
    for (const auto& [a, b] : e.sharp_pairs)
      if (x[a] && x[b]) {
        corners += 1.0;
        break;
      }
  const double ed = 1.0 - support / static_cast<double>(std::max<std::size_t>(p.point_count, 1));
  const double ec = corners / static_cast<double>(std::max<std::size_t>(p.edges.size(), 1));
  const double er = roof / static_cast<double>(std::max<std::size_t>(p.face_count, 1));
  return w.lambda_data * ed + w.lambda_complexity * ec + w.lambda_roof * er;
}

std::vector<bool> reference_select(const SelectionProblem& p, const SelectionParams& w = {}) {
  const std::size_t n = p.face_count;
  std::vector<int> fixed(n, -1);
  for (auto f : p.forced_on) fixed[f] = 1;
  for (auto f : p.face_prior) fixed[f] = 1;
  for (auto f : p.forced_off) fixed[f] = 0;
  std::vector<std::vector<std::size_t>> edges_by_last(n);
  for (std::size_t e = 0; e < p.edges.size(); ++e)
    edges_by_last[*std::max_element(p.edges[e].faces.begin(), p.edges[e].faces.end())].push_back(e);
  std::vector<std::vector<std::uint32_t>> overlaps_by_last(n);
  for (const auto& [a, b] : p.vertical_overlaps) overlaps_by_last[std::max(a, b)].push_back(std::min(a, b));
  std::vector<bool> x(n, false), best;
  double best_energy = std::numeric_limits<double>::infinity();
  std::function<void(std::size_t)> search = [&](std::size_t i) {
    if (i == n) {
      const double energy = reference_energy(p, x, w);
      if (energy < best_energy) {
        best_energy = energy;
        best = x;
      }
      return;
    }
    for (int value : {0, 1}) {
      if (fixed[i] >= 0 && fixed[i] != value) continue;
      x[i] = value == 1;
      bool ok = true;
      for (std::size_t e : edges_by_last[i]) {
        int count = 0;
        for (auto f : p.edges[e].faces) count += x[f] ? 1 : 0;
        if (count != 0 && count != 2) ok = false;
      }
      for (auto other : overlaps_by_last[i])
        if (x[i] && x[other]) ok = false;
      if (ok) search(i + 1);
    }
    x[i] = false;
  };
  search(0);
  return best;
}

struct Reconstruction {
  CandidateFaces candidates;
  std::vector<bool> selected;
  PolygonMesh mesh;
  std::vector<SurfaceType> surfaces;
  MeshCheck check;
};

Reconstruction reconstruct(const Synthetic& b) {
  Reconstruction r;
  r.candidates = candidates_of(b);
  r.selected = reference_select(r.candidates.problem);
  EXPECT_EQ(r.selected.size(), r.candidates.faces.size()) << "the reference selector found no feasible selection";
  r.mesh = assemble_model(r.candidates, r.selected, AssembleParams{}, &r.surfaces);
  r.check = check_mesh(r.mesh);
  return r;
}

std::size_t count_surface(const std::vector<SurfaceType>& s, SurfaceType t) {
  return static_cast<std::size_t>(std::count(s.begin(), s.end(), t));
}

void expect_valid_solid(const Reconstruction& r, double volume) {
  EXPECT_TRUE(r.check.closed) << r.check.boundary_edges << " boundary edges";
  EXPECT_TRUE(r.check.manifold);
  EXPECT_TRUE(r.check.outward) << "volume " << r.check.signed_volume;
  EXPECT_EQ(r.check.degenerate_faces, 0u);
  EXPECT_EQ(r.check.shell_count, 1u);
  EXPECT_NEAR(r.check.signed_volume, volume, 0.03 * volume);
  EXPECT_EQ(r.surfaces.size(), r.mesh.faces.size());
}

// ------------------------------------------------------------------------------------------------
// Candidate generation.

void expect_well_formed(const CandidateFaces& c) {
  const auto& p = c.problem;
  ASSERT_EQ(p.face_count, c.faces.size());
  ASSERT_EQ(p.support.size(), c.faces.size());
  ASSERT_EQ(p.centroid_z.size(), c.faces.size());
  ASSERT_EQ(p.is_roof.size(), c.faces.size());
  ASSERT_EQ(c.polygons.size(), c.faces.size());
  for (const auto& e : p.edges) {
    EXPECT_GE(e.faces.size(), 2u);
    for (auto f : e.faces) EXPECT_LT(f, p.face_count);
  }
  for (std::size_t i = 0; i < c.faces.size(); ++i) {
    EXPECT_GE(c.faces[i].vertices.size(), 3u);
    EXPECT_GT(c.faces[i].area, 0.0);
    EXPECT_EQ(p.is_roof[i], c.faces[i].kind == FaceKind::roof);
    // Every vertex lies on the face's plane: roofs on their plane, floors at the ground, walls vertical.
    std::set<std::uint32_t> distinct(c.faces[i].vertices.begin(), c.faces[i].vertices.end());
    EXPECT_EQ(distinct.size(), c.faces[i].vertices.size()) << "face " << i << " repeats a vertex";
  }
}

TEST(Hypothesis, box_gives_one_roof_four_walls_and_a_floor) {
  const auto c = candidates_of(box_building());
  expect_well_formed(c);
  EXPECT_EQ(c.cell_count, 1u);
  EXPECT_EQ(c.faces.size(), 6u);
  EXPECT_EQ(count_kind(c, FaceKind::roof), 1u);
  EXPECT_EQ(count_kind(c, FaceKind::wall), 4u);
  EXPECT_EQ(count_kind(c, FaceKind::floor), 1u);
  EXPECT_EQ(c.problem.edges.size(), 12u);
  for (const auto& e : c.problem.edges) EXPECT_EQ(e.faces.size(), 2u);
}

TEST(Hypothesis, gable_roof_planes_meet_in_one_ridge) {
  const auto c = candidates_of(gable_building());
  expect_well_formed(c);
  EXPECT_EQ(c.line_count, 1u);
  EXPECT_EQ(c.cell_count, 2u);
  // Both planes over both cells; 2 floors; every boundary edge carries floor-to-lower-roof and
  // lower-to-upper-roof walls: 2 long eaves (2 each) and 4 gable halves (2 each).
  EXPECT_EQ(count_kind(c, FaceKind::roof), 4u);
  EXPECT_EQ(count_kind(c, FaceKind::floor), 2u);
  EXPECT_EQ(count_kind(c, FaceKind::wall), 12u);
  EXPECT_EQ(c.faces.size(), 18u);
  EXPECT_EQ(c.problem.vertical_overlaps.size(), 2u);
}

TEST(Hypothesis, ridge_edge_is_welded_by_identity_across_four_roof_faces) {
  const auto c = candidates_of(gable_building());
  // The ridge runs along y = 4 at z = 6 from x = 0 to x = 10; all four roof faces contain it.
  std::size_t ridge_edges = 0;
  for (const auto& e : c.problem.edges) {
    bool all_roof = true;
    for (auto f : e.faces) all_roof = all_roof && c.faces[f].kind == FaceKind::roof;
    if (!all_roof || e.faces.size() != 4) continue;
    ++ridge_edges;
    EXPECT_EQ(e.sharp_pairs.size(), 4u);  // A-B pairs are sharp, A-A and B-B are not
  }
  EXPECT_EQ(ridge_edges, 1u);
  // The ridge end vertices: both planes give the same height there, within noise of the fit.
  std::size_t ridge_vertices = 0;
  for (const auto& v : c.vertices)
    if (std::abs(v.y - 4.0) < 0.05 && std::abs(v.z - 6.0) < 0.1) ++ridge_vertices;
  EXPECT_EQ(ridge_vertices, 2u);
}

TEST(Hypothesis, floor_faces_are_forced_on) {
  for (const auto& b : {box_building(), gable_building(), step_building()}) {
    const auto c = candidates_of(b);
    std::vector<std::uint32_t> floors;
    for (std::uint32_t i = 0; i < c.faces.size(); ++i)
      if (c.faces[i].kind == FaceKind::floor) floors.push_back(i);
    EXPECT_EQ(c.problem.forced_on, floors);
    EXPECT_EQ(floors.size(), c.cell_count);
    for (auto f : floors)
      for (const auto& v : c.faces[f].vertices) EXPECT_DOUBLE_EQ(c.vertices[v].z, 0.0);
  }
}

TEST(Hypothesis, face_prior_is_the_best_supported_face_of_each_roof_segment) {
  const auto c = candidates_of(gable_building());
  const auto& p = c.problem;
  ASSERT_EQ(p.face_prior.size(), 2u);
  for (auto prior : p.face_prior) {
    const int seg = c.faces[prior].source;
    for (std::size_t i = 0; i < c.faces.size(); ++i)
      if (c.faces[i].kind == FaceKind::roof && c.faces[i].source == seg) EXPECT_LE(p.support[i], p.support[prior]);
  }
  // Plane 0 (y < 4) is best supported over the cell at y < 4, and it holds most of its points.
  const auto& a = c.faces[p.face_prior[0]];
  double cy = 0.0;
  for (auto v : a.vertices) cy += c.vertices[v].y;
  cy /= static_cast<double>(a.vertices.size());
  EXPECT_LT(cy, 4.0);
  EXPECT_EQ(a.source, 0);
  const double points_a = static_cast<double>(gable_building().roofs[0].points.size());
  EXPECT_GT(p.support[p.face_prior[0]], 0.9 * points_a);
}

TEST(Hypothesis, roof_faces_face_up_and_floors_face_down) {
  const auto c = candidates_of(step_building());
  for (std::size_t i = 0; i < c.faces.size(); ++i) {
    const auto& poly = c.polygons[i];
    double nz = 0.0;
    for (std::size_t k = 0; k < poly.size(); ++k) {
      const auto& p = poly[k];
      const auto& q = poly[(k + 1) % poly.size()];
      nz += (p.x - q.x) * (p.y + q.y);
    }
    if (c.faces[i].kind == FaceKind::roof) EXPECT_GT(nz, 0.0);
    if (c.faces[i].kind == FaceKind::floor) EXPECT_LT(nz, 0.0);
    if (c.faces[i].kind == FaceKind::wall) EXPECT_NEAR(nz, 0.0, 1e-9);
  }
}

TEST(Hypothesis, inner_wall_splits_the_footprint_and_is_the_source_of_its_faces) {
  const auto b = step_building();
  const auto c = candidates_of(b);
  expect_well_formed(c);
  EXPECT_EQ(c.cell_count, 2u);
  std::size_t on_inner = 0;
  for (const auto& f : c.faces)
    if (f.kind == FaceKind::wall && f.source == static_cast<int>(b.walls.size() - 1)) ++on_inner;
  EXPECT_EQ(on_inner, 1u);  // one face between the two flat roofs over x = 6
}

TEST(Hypothesis, start_assignment_is_a_closed_selection_for_every_synthetic_building) {
  SelectionParams no_prior;
  no_prior.use_face_prior = false;
  for (const auto& b :
       {box_building(), gable_building(), l_building(), step_building(), courtyard_building()}) {
    const auto c = candidates_of(b);
    ASSERT_EQ(c.problem.start.size(), c.faces.size());
    EXPECT_TRUE(satisfies_constraints(c.problem, c.problem.start, no_prior));
    EXPECT_TRUE(satisfies_constraints(c.problem, c.problem.start, SelectionParams{}));  // priors agree here
    std::size_t roofs = 0;
    for (std::size_t i = 0; i < c.faces.size(); ++i)
      roofs += c.problem.start[i] && c.faces[i].kind == FaceKind::roof;
    EXPECT_EQ(roofs, c.cell_count);  // one roof per cell
    const auto mesh = assemble_model(c, c.problem.start, AssembleParams{});
    EXPECT_TRUE(check_mesh(mesh).valid());
  }
}

TEST(Hypothesis, generation_is_deterministic) {
  const auto a = candidates_of(gable_building());
  const auto b = candidates_of(gable_building());
  ASSERT_EQ(a.faces.size(), b.faces.size());
  for (std::size_t i = 0; i < a.faces.size(); ++i) {
    EXPECT_EQ(a.faces[i].vertices, b.faces[i].vertices);
    EXPECT_EQ(a.problem.support[i], b.problem.support[i]);
  }
}

TEST(Hypothesis, rejects_input_without_roof_planes) {
  const auto b = box_building();
  try {
    generate_candidates(b.points, {}, b.walls, b.footprint, 0.0, true, HypothesisParams{});
    FAIL() << "no exception";
  } catch (const ReconstructionError& e) {
    EXPECT_NE(std::string(e.what()).find("need at least 1 roof plane"), std::string::npos) << e.what();
  }
}

// The checkpoint (a time limit) is called between the steps, and what it throws stops the work; a
// checkpoint that returns changes nothing.
TEST(Hypothesis, the_checkpoint_is_called_between_the_steps_and_may_stop_them) {
  const auto b = box_building();
  const CandidateFaces plain = candidates_of(b);
  int calls = 0;
  const CandidateFaces checked =
      generate_candidates(b.points, b.roofs, b.walls, b.footprint, b.ground_z, b.ground_measured,
                          HypothesisParams{}, SelectionParams{}, [&calls] { ++calls; });
  EXPECT_GE(calls, 4);
  ASSERT_EQ(plain.faces.size(), checked.faces.size());
  for (std::size_t i = 0; i < plain.faces.size(); ++i)
    EXPECT_EQ(plain.faces[i].vertices, checked.faces[i].vertices);
  for (int stop_at = 1; stop_at <= calls; ++stop_at) {
    int seen = 0;
    try {
      generate_candidates(b.points, b.roofs, b.walls, b.footprint, b.ground_z, b.ground_measured,
                          HypothesisParams{}, SelectionParams{}, [&] {
                            if (++seen == stop_at)
                              throw ReconstructionError(ReconstructionStage::hypothesis, "out of time");
                          });
      ADD_FAILURE() << "not stopped at checkpoint " << stop_at;
    } catch (const ReconstructionError& e) {
      EXPECT_EQ(seen, stop_at);
      EXPECT_NE(std::string(e.what()).find("out of time"), std::string::npos);
    }
  }
}

TEST(Hypothesis, rejects_invalid_parameters_listing_each) {
  HypothesisParams params;
  params.support_distance = 0.0;
  params.min_support_points = 0;
  try {
    params.validate();
    FAIL() << "no exception";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("support_distance"), std::string::npos);
    EXPECT_NE(m.find("min_support_points"), std::string::npos);
  }
}

TEST(Hypothesis, rejects_invalid_size_bounds_listing_each) {
  HypothesisParams params;
  params.min_cell_width = -0.1;
  params.max_planes_per_large_cell = 0;
  params.line_merge_distance = -1.0;
  try {
    params.validate();
    FAIL() << "no exception";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("min_cell_width"), std::string::npos) << m;
    EXPECT_NE(m.find("max_planes_per_large_cell"), std::string::npos) << m;
    EXPECT_NE(m.find("line_merge_distance"), std::string::npos) << m;
  }
}

// ------------------------------------------------------------------------------------------------
// End to end: candidates -> reference selection -> assembled model.

TEST(Model, box_is_a_closed_six_faced_solid) {
  const auto r = reconstruct(box_building());
  expect_valid_solid(r, 300.0);
  EXPECT_EQ(r.mesh.faces.size(), 6u);
  EXPECT_EQ(r.mesh.vertices.size(), 8u);
  EXPECT_EQ(count_surface(r.surfaces, SurfaceType::roof), 1u);
  EXPECT_EQ(count_surface(r.surfaces, SurfaceType::wall), 4u);
  EXPECT_EQ(count_surface(r.surfaces, SurfaceType::ground), 1u);
}

TEST(Model, gable_has_two_roofs_two_long_walls_two_pentagons_and_a_floor) {
  const auto r = reconstruct(gable_building());
  expect_valid_solid(r, 400.0);
  EXPECT_EQ(r.mesh.faces.size(), 7u);
  EXPECT_EQ(r.mesh.vertices.size(), 10u);
  std::size_t pentagons = 0;
  for (const auto& f : r.mesh.faces) pentagons += f.size() == 5 ? 1 : 0;
  EXPECT_EQ(pentagons, 2u);
  EXPECT_EQ(count_surface(r.surfaces, SurfaceType::roof), 2u);
}

TEST(Model, l_shaped_flat_roof_has_eight_faces) {
  const auto r = reconstruct(l_building());
  expect_valid_solid(r, 192.0);
  EXPECT_EQ(r.mesh.faces.size(), 8u);
  EXPECT_EQ(count_surface(r.surfaces, SurfaceType::wall), 6u);
}

TEST(Model, step_building_has_one_step_wall_and_merged_side_walls) {
  const auto r = reconstruct(step_building());
  expect_valid_solid(r, 396.0);
  // floor + 2 roofs + west + east + south + north (each one polygon over both heights) + step wall.
  EXPECT_EQ(r.mesh.faces.size(), 8u);
  EXPECT_EQ(count_surface(r.surfaces, SurfaceType::roof), 2u);
  EXPECT_EQ(count_surface(r.surfaces, SurfaceType::wall), 5u);
  EXPECT_EQ(count_surface(r.surfaces, SurfaceType::ground), 1u);
  std::size_t hexagons = 0;
  for (const auto& f : r.mesh.faces) hexagons += f.size() == 6 ? 1 : 0;
  EXPECT_EQ(hexagons, 2u);  // south and north walls; the floor is one rectangle again
}

TEST(Model, courtyard_building_keeps_faces_with_holes_as_simple_pieces) {
  const auto r = reconstruct(courtyard_building());
  expect_valid_solid(r, 640.0);
  EXPECT_EQ(count_surface(r.surfaces, SurfaceType::wall), 8u);
  EXPECT_EQ(count_surface(r.surfaces, SurfaceType::roof), 2u);
  EXPECT_EQ(count_surface(r.surfaces, SurfaceType::ground), 2u);
}

TEST(Model, merged_faces_that_would_touch_themselves_stay_simple_pieces) {
  // Built by hand: a 16 x 16 block, a 2 m ring at 7 m around a 12 x 12 part at 5 m, in which a
  // triangle at 3 m touches the ring at P = (2, 8). The 5 m part comes in two pieces split along
  // y = 8; merged, its boundary would come back to P (not a simple polygon), so the pieces stay.
  CandidateFaces c;
  std::map<std::array<double, 3>, std::uint32_t> index;
  const auto vertex = [&](Point2 p, double z) {
    const auto [it, fresh] = index.insert({{p.x, p.y, z}, static_cast<std::uint32_t>(c.vertices.size())});
    if (fresh) c.vertices.push_back({p.x, p.y, z});
    return it->second;
  };
  const auto add = [&](FaceKind kind, std::uint32_t plane, std::vector<std::uint32_t> loop) {
    CandidateFace f;
    f.kind = kind;
    f.plane_id = plane;
    f.vertices = std::move(loop);
    c.faces.push_back(f);
  };
  const auto flat = [&](FaceKind kind, std::uint32_t plane, const Ring2& ring, double z) {
    std::vector<std::uint32_t> loop;
    for (const auto& p : ring) loop.push_back(vertex(p, z));
    add(kind, plane, loop);
  };
  const auto wall = [&](std::uint32_t plane, Point2 a, Point2 b, double z0, double z1) {
    add(FaceKind::wall, plane, {vertex(a, z0), vertex(b, z0), vertex(b, z1), vertex(a, z1)});
  };
  const Point2 P{2, 8}, Q{6, 8}, R{14, 8};
  flat(FaceKind::roof, 0, {Q, R, {14, 14}, {2, 14}, P, {6, 10}}, 5.0);
  flat(FaceKind::roof, 0, {{2, 2}, {14, 2}, R, Q, {6, 6}, P}, 5.0);
  flat(FaceKind::roof, 1, {P, {6, 6}, Q, {6, 10}}, 3.0);
  flat(FaceKind::roof, 2, {{0, 0}, {16, 0}, {14, 2}, {2, 2}}, 7.0);
  flat(FaceKind::roof, 2, {{16, 0}, {16, 16}, {14, 14}, R, {14, 2}}, 7.0);
  flat(FaceKind::roof, 2, {{16, 16}, {0, 16}, {2, 14}, {14, 14}}, 7.0);
  flat(FaceKind::roof, 2, {{0, 16}, {0, 0}, {2, 2}, P, {2, 14}}, 7.0);
  flat(FaceKind::floor, 3, {{0, 0}, {0, 16}, {16, 16}, {16, 0}}, 0.0);
  const Ring2 outline{{0, 0}, {16, 0}, {16, 16}, {0, 16}};
  for (std::size_t k = 0; k < 4; ++k)
    wall(4 + static_cast<std::uint32_t>(k), outline[k], outline[(k + 1) % 4], 0.0, 7.0);
  const Ring2 inner{{2, 2}, {14, 2}, R, {14, 14}, {2, 14}, P};
  const std::uint32_t inner_line[] = {8, 9, 9, 10, 11, 11};
  for (std::size_t k = 0; k < inner.size(); ++k)
    wall(inner_line[k], inner[k], inner[(k + 1) % inner.size()], 5.0, 7.0);
  const Ring2 notch{P, {6, 6}, Q, {6, 10}};
  const std::uint32_t notch_line[] = {12, 13, 13, 14};
  for (std::size_t k = 0; k < notch.size(); ++k)
    wall(notch_line[k], notch[k], notch[(k + 1) % notch.size()], 3.0, 5.0);
  for (const auto& f : c.faces) {
    std::vector<Point3> polygon;
    for (auto v : f.vertices) polygon.push_back(c.vertices[v]);
    c.polygons.push_back(polygon);
  }

  std::vector<SurfaceType> surfaces;
  const auto mesh = assemble_model(c, std::vector<bool>(c.faces.size(), true), AssembleParams{}, &surfaces);
  const auto check = check_mesh(mesh);
  EXPECT_TRUE(check.valid());
  EXPECT_EQ(check.degenerate_faces, 0u);
  EXPECT_NEAR(check.signed_volume, 112.0 * 7.0 + 136.0 * 5.0 + 8.0 * 3.0, 1e-9);
  for (const auto& face : mesh.faces) {
    std::vector<std::uint32_t> sorted(face);
    std::sort(sorted.begin(), sorted.end());
    EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end())
        << "a face visits a vertex twice";
  }
}

TEST(Model, pieces_of_one_line_that_bend_are_not_merged_into_a_warped_wall) {
  // A 10 x 10 x 5 box whose front wall (y = 0) comes in two pieces of one arrangement line, but
  // their shared corner (5, 0) sits 3 cm off it (as contracting a short edge can leave it). Merged,
  // the wall would be warped; the pieces stay two planar faces.
  CandidateFaces c;
  const std::vector<Point2> ring{{0, 0}, {5, -0.03}, {10, 0}, {10, 10}, {0, 10}};
  const auto n = static_cast<std::uint32_t>(ring.size());
  for (double z : {0.0, 5.0})
    for (const auto& p : ring) c.vertices.push_back({p.x, p.y, z});
  const auto add = [&](FaceKind kind, std::uint32_t plane, std::vector<std::uint32_t> loop) {
    CandidateFace f;
    f.kind = kind;
    f.plane_id = plane;
    f.vertices = std::move(loop);
    std::vector<Point3> polygon;
    for (auto v : f.vertices) polygon.push_back(c.vertices[v]);
    c.faces.push_back(f);
    c.polygons.push_back(polygon);
  };
  add(FaceKind::roof, 0, {5, 6, 7, 8, 9});
  add(FaceKind::floor, 1, {4, 3, 2, 1, 0});
  const std::uint32_t line[] = {2, 2, 3, 4, 5};  // both front pieces on line 2
  for (std::uint32_t k = 0; k < n; ++k)
    add(FaceKind::wall, line[k], {k, (k + 1) % n, (k + 1) % n + n, k + n});
  std::vector<SurfaceType> surfaces;
  const auto mesh = assemble_model(c, std::vector<bool>(c.faces.size(), true), AssembleParams{}, &surfaces);
  EXPECT_EQ(count_surface(surfaces, SurfaceType::wall), 5u);
  const auto validity = check_validity(mesh);
  EXPECT_TRUE(validity.valid()) << validity.problem;
  EXPECT_LT(validity.max_planarity_error, 1e-9);
}

TEST(Model, inner_wall_ending_short_of_the_outline_is_extended_to_it) {
  Synthetic b = step_building();
  b.walls.back().a = {6, 1.5};  // 1.5 m short at both ends: more than line_support_margin
  b.walls.back().b = {6, 4.5};
  const auto r = reconstruct(b);
  EXPECT_EQ(r.candidates.cell_count, 2u);
  expect_valid_solid(r, 396.0);
  EXPECT_EQ(r.mesh.faces.size(), 8u);
}

TEST(Hypothesis, nearly_concurrent_lines_leave_no_cell_without_area) {
  // Three inner walls through almost one point (within 1 mm): the tiny triangle they make is
  // contracted, so every face keeps an area and every floor survives.
  Synthetic b = make_building({rectangle(0, 0, 12, 12)}, {{{{0, 0}, {12, 0}, {12, 12}, {0, 12}}, 0.0, 0.0, 5.0}},
                              720.0);
  auto wall = [](Point2 a, Point2 c) {
    VerticalPlane w;
    w.a = a;
    w.b = c;
    w.outer = false;
    return w;
  };
  b.walls.push_back(wall({6, 0}, {6, 12}));
  b.walls.push_back(wall({0, 6.0004}, {12, 6.0004}));
  b.walls.push_back(wall({0, 0.0003}, {12, 12.0001}));
  const auto c = candidates_of(b);
  expect_well_formed(c);
  EXPECT_EQ(c.cell_count, 6u);
  for (const auto& f : c.faces) EXPECT_GT(f.area, 1e-3);
  const auto r = reconstruct(b);
  expect_valid_solid(r, 720.0);
  EXPECT_EQ(r.mesh.faces.size(), 6u);  // a box: the inner walls are not selected
}

TEST(Hypothesis, thin_strip_between_nearly_coincident_walls_is_merged_into_a_neighbour) {
  // Two inner walls 4 cm apart cut a 12 m x 4 cm strip (area < 0.05 x perimeter): it is merged into
  // a neighbour, leaving two cells, and the model stays a valid box.
  Synthetic b = make_building({rectangle(0, 0, 12, 12)}, {{{{0, 0}, {12, 0}, {12, 12}, {0, 12}}, 0.0, 0.0, 5.0}},
                              720.0);
  for (double x : {6.0, 6.04}) {
    VerticalPlane w;
    w.a = {x, 0};
    w.b = {x, 12};
    w.outer = false;
    b.walls.push_back(w);
  }
  const auto c = candidates_of(b);
  expect_well_formed(c);
  EXPECT_EQ(c.cell_count, 2u);
  const auto r = reconstruct(b);
  expect_valid_solid(r, 720.0);
  EXPECT_EQ(r.mesh.faces.size(), 6u);
}

TEST(Hypothesis, thin_cells_are_kept_when_merging_is_off) {
  Synthetic b = make_building({rectangle(0, 0, 12, 12)}, {{{{0, 0}, {12, 0}, {12, 12}, {0, 12}}, 0.0, 0.0, 5.0}},
                              720.0);
  for (double x : {6.0, 6.04}) {
    VerticalPlane w;
    w.a = {x, 0};
    w.b = {x, 12};
    w.outer = false;
    b.walls.push_back(w);
  }
  HypothesisParams params;
  params.min_cell_width = 0.0;
  const auto c = generate_candidates(b.points, b.roofs, b.walls, b.footprint, b.ground_z, true, params);
  EXPECT_EQ(c.cell_count, 3u);
}

TEST(Model, rejects_an_open_selection_naming_the_edge) {
  const auto c = candidates_of(box_building());
  std::vector<bool> selected(c.faces.size(), true);
  for (std::size_t i = 0; i < c.faces.size(); ++i)
    if (c.faces[i].kind == FaceKind::roof) selected[i] = false;
  try {
    assemble_model(c, selected, AssembleParams{});
    FAIL() << "no exception";
  } catch (const ReconstructionError& e) {
    EXPECT_NE(std::string(e.what()).find("is used by 1 selected faces"), std::string::npos) << e.what();
  }
}

TEST(Model, orients_faces_outward_whatever_their_input_orientation) {
  auto c = candidates_of(box_building());
  for (auto& f : c.faces) std::reverse(f.vertices.begin(), f.vertices.end());
  const auto mesh = assemble_model(c, std::vector<bool>(c.faces.size(), true), AssembleParams{});
  const auto check = check_mesh(mesh);
  EXPECT_TRUE(check.valid());
  EXPECT_NEAR(check.signed_volume, 300.0, 9.0);
}

// A flat box cut into 40 cells along x: its roof, floor and long walls are merged from 40 pieces
// each, which leaves 39 collinear vertices on each of its four long edges, every one in two faces
// with two neighbours. All are removed, one after another along each edge: a box again.
TEST(Model, chains_of_collinear_vertices_along_merged_edges_are_all_removed) {
  constexpr std::uint32_t n = 40;
  CandidateFaces c;
  const auto at = [](std::uint32_t i, std::uint32_t y, std::uint32_t z) { return 4 * i + 2 * y + z; };
  for (std::uint32_t i = 0; i <= n; ++i)
    for (std::uint32_t y = 0; y < 2; ++y)
      for (std::uint32_t z = 0; z < 2; ++z) c.vertices.push_back({0.5 * i, 6.0 * y, 3.0 * z});
  const auto add = [&](FaceKind kind, std::uint32_t plane, std::vector<std::uint32_t> loop) {
    CandidateFace f;
    f.kind = kind;
    f.plane_id = plane;
    f.vertices = std::move(loop);
    c.faces.push_back(std::move(f));
  };
  for (std::uint32_t i = 0; i < n; ++i) {
    add(FaceKind::roof, 0, {at(i, 0, 1), at(i + 1, 0, 1), at(i + 1, 1, 1), at(i, 1, 1)});
    add(FaceKind::floor, 1, {at(i, 0, 0), at(i, 1, 0), at(i + 1, 1, 0), at(i + 1, 0, 0)});
    add(FaceKind::wall, 2, {at(i, 0, 0), at(i + 1, 0, 0), at(i + 1, 0, 1), at(i, 0, 1)});
    add(FaceKind::wall, 3, {at(i, 1, 0), at(i, 1, 1), at(i + 1, 1, 1), at(i + 1, 1, 0)});
  }
  add(FaceKind::wall, 4, {at(0, 0, 0), at(0, 0, 1), at(0, 1, 1), at(0, 1, 0)});
  add(FaceKind::wall, 5, {at(n, 0, 0), at(n, 1, 0), at(n, 1, 1), at(n, 0, 1)});
  const PolygonMesh mesh = assemble_model(c, std::vector<bool>(c.faces.size(), true), AssembleParams{});
  EXPECT_EQ(mesh.faces.size(), 6u);
  EXPECT_EQ(mesh.vertices.size(), 8u);
  for (const auto& f : mesh.faces) EXPECT_EQ(f.size(), 4u);
  const MeshCheck check = check_mesh(mesh);
  EXPECT_TRUE(check.valid());
  EXPECT_NEAR(check.signed_volume, 20.0 * 6.0 * 3.0, 1e-9);
}

}  // namespace
}  // namespace city3d

namespace city3d {
namespace {

// Issue: a roof plane extended to the outline dropped below the floor (ground_z = lowest point), and
// the roof crossed the floor ("model: not a valid solid: self-intersecting").
TEST(Model, floor_is_lowered_below_a_roof_that_dips_under_ground_z) {
  // Shed 10 x 6, z = 1 + 0.5 x: the low eave (z = 1) is below the given ground_z of 1.5.
  Synthetic b = make_building({rectangle(0, 0, 10, 6)}, {{{{0, 0}, {10, 0}, {10, 6}, {0, 6}}, 0.5, 0.0, 1.0}}, 0.0);
  b.ground_z = 1.5;
  const Reconstruction r = reconstruct(b);
  const double floor_z = 1.0 - HypothesisParams{}.floor_clearance;
  for (const auto& p : r.mesh.vertices) EXPECT_GE(p.z, floor_z - 1e-9);
  expect_valid_solid(r, 60.0 * (3.5 - floor_z));
}

}  // namespace
}  // namespace city3d

namespace city3d {
namespace {

// Issue: a roof-only cloud has its lowest point at the eaves. With that as a measured ground, the
// roof planes, extended to an outline a little outside the points, dipped below the floor and were
// dropped over their own cells: the opposite slope was lifted there instead (AHN3 dev buildings with
// RMSE 0.3-0.5 m instead of 0.04 m). An unmeasured ground drops no plane that stays within
// unmeasured_floor_drop of it.
Synthetic roof_only_gable(bool ground_measured) {
  Synthetic b = gable_building();
  b.footprint = {rectangle(-0.3, -0.3, 10.3, 8.3)};
  b.ground_z = std::numeric_limits<double>::infinity();
  for (const auto& p : b.points) b.ground_z = std::min(b.ground_z, p.z);
  b.ground_measured = ground_measured;
  return b;
}

// The roof face over each cell lies on the plane whose points are there.
void expect_roofs_on_their_own_planes(const Reconstruction& r) {
  std::size_t roofs = 0;
  for (std::size_t i = 0; i < r.candidates.faces.size(); ++i) {
    const CandidateFace& f = r.candidates.faces[i];
    if (!r.selected[i] || f.kind != FaceKind::roof) continue;
    ++roofs;
    double cy = 0.0;
    for (const Point3& p : r.candidates.polygons[i]) cy += p.y;
    cy /= static_cast<double>(r.candidates.polygons[i].size());
    EXPECT_EQ(f.source, cy < 4.0 ? 0 : 1) << "roof face " << i << " at y = " << cy;
  }
  EXPECT_EQ(roofs, 2u);
}

TEST(Hypothesis, unmeasured_ground_at_the_eaves_drops_no_roof_plane) {
  const Synthetic b = roof_only_gable(false);
  const Reconstruction r = reconstruct(b);
  expect_roofs_on_their_own_planes(r);
  EXPECT_TRUE(r.check.valid());
  // The floor went below the roof where it meets the outline (eaves at 4 - 0.5 x 0.3 = 3.85).
  double low = std::numeric_limits<double>::infinity();
  for (const auto& p : r.mesh.vertices) low = std::min(low, p.z);
  EXPECT_LE(low, 3.85 - HypothesisParams{}.floor_clearance + 1e-9);
}

TEST(Hypothesis, measured_ground_still_drops_planes_below_it) {
  // The same cloud with that height given as measured ground: the rule for real ground applies and
  // the planes that dip below it are replaced where another plane stays above (the old behaviour).
  const Synthetic b = roof_only_gable(true);
  const std::size_t measured = count_kind(candidates_of(b), FaceKind::roof);
  const std::size_t unmeasured = count_kind(candidates_of(roof_only_gable(false)), FaceKind::roof);
  EXPECT_LT(measured, unmeasured);
}

TEST(Hypothesis, unmeasured_ground_drops_a_plane_that_dips_metres_below_it) {
  // A flat roof at 5 m (x < 8) beside a steep one (x > 8, slope 3): extended over the flat part's
  // cell, the steep plane reaches z = -19 at x = 0. Without measured ground (ground_z = the lowest
  // point) it used to drag the floor there; now it is dropped over that cell, as it comes more than
  // unmeasured_floor_drop below ground_z.
  Synthetic b = make_building({rectangle(0, 0, 10, 8)},
                              {{{{0, 0}, {8, 0}, {8, 8}, {0, 8}}, 0.0, 0.0, 5.0},
                               {{{8, 0}, {10, 0}, {10, 8}, {8, 8}}, 3.0, 0.0, -19.0}},
                              448.0);
  b.ground_z = std::numeric_limits<double>::infinity();
  for (const auto& p : b.points) b.ground_z = std::min(b.ground_z, p.z);
  b.ground_measured = false;
  const Reconstruction r = reconstruct(b);
  EXPECT_TRUE(r.check.valid());
  double low = std::numeric_limits<double>::infinity();
  for (const auto& p : r.mesh.vertices) low = std::min(low, p.z);
  const HypothesisParams defaults;
  EXPECT_GE(low, b.ground_z - defaults.unmeasured_floor_drop - defaults.floor_clearance - 1e-9);
  // With the bar far enough down, the plane stays and the floor follows it (the old behaviour).
  HypothesisParams lenient;
  lenient.unmeasured_floor_drop = 100.0;
  const auto deep = generate_candidates(b.points, b.roofs, b.walls, b.footprint, b.ground_z, false, lenient);
  double deep_low = std::numeric_limits<double>::infinity();
  for (const auto& p : deep.vertices) deep_low = std::min(deep_low, p.z);
  EXPECT_LT(deep_low, -18.0);
}

// The cell supports' test (polygon_reach) must answer as distance_to_polygon does: 2 at distance 0
// (inside, or on an edge or corner), 1 within the reach, 0 beyond it. Points around an L-shaped ring
// with a slanted edge, on its corners and edges, and exactly at the reach beside its axis-aligned
// edges, where the squared distance alone could misjudge.
TEST(CellPlanes, polygon_reach_answers_as_the_distance_to_the_polygon_does) {
  const std::vector<Point2> ring{{0.0, 0.0}, {10.0, 0.0}, {10.0, 4.0}, {4.3, 4.0}, {3.7, 9.1}, {0.0, 9.1}};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-2.0, 12.0), pick(0.0, 1.0);
  for (const double reach : {0.0, 0.3, 0.7, 1.0}) {
    std::vector<Point2> points;
    for (int i = 0; i < 4000; ++i) points.push_back({u(rng), u(rng)});
    for (std::size_t k = 0; k < ring.size(); ++k) {
      const Point2 &a = ring[k], &b = ring[(k + 1) % ring.size()];
      points.push_back(a);
      const double t = pick(rng);
      points.push_back({a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)});
    }
    for (const double x : {2.0, 5.0, 9.9})
      points.push_back({x, -reach}), points.push_back({x, -std::nextafter(reach, 2.0)});
    for (const double y : {0.5, 2.0, 3.9}) points.push_back({10.0 + reach, y});
    for (const Point2& p : points) {
      const double d = detail::distance_to_polygon(ring, p.x, p.y);
      const int expected = d <= 0.0 ? 2 : d <= reach ? 1 : 0;
      ASSERT_EQ(detail::polygon_reach(ring, p.x, p.y, reach), expected)
          << "(" << p.x << ", " << p.y << ") at distance " << d << ", reach " << reach;
    }
  }
}

}  // namespace
}  // namespace city3d
