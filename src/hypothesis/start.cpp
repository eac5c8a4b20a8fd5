// Face hypothesis, step 6: a closed start for the solvers: one roof face per cell, the floors, and the
// wall faces between the chosen roofs. Large programs whose solver finds no feasible point within its
// limits then still give a full LoD2 model.
#include <algorithm>
#include <cstddef>
#include <string>
#include <vector>

#include "city3d/log.hpp"
#include "hypothesis/steps.hpp"

namespace city3d::detail {
namespace {

// A change must lower the energy by more than this to count (rounding in the running sums).
constexpr double kEnergyTolerance = 1e-12;

}  // namespace

// A feasible start for face selection: one roof face per cell, the floors, and over every edge the
// wall faces between the roofs chosen on its two sides (or the floor, outside). Each cell first takes
// its segment's face prior if it holds one, else its best-supported roof face. One roof per cell can
// still leave an edge with one or four faces (a checkerboard of high and low cells around a vertex
// puts four walls on one vertical edge), so a local search then changes one cell's roof at a time,
// taking the change that leaves the fewest such edges (cells holding a face prior only when no other
// change helps), until none is left or no change helps. Returns an empty vector in that case.
//
// The closed start then descends the selection energy of selection.hpp under `energy`'s weights, kept
// up to date as faces toggle (support, roof-preference and unsupported-area sums, and per edge whether a
// sharp pair is on): each pass visits the cells in order and gives each the roof face that lowers the energy
// most among those that keep every edge at 0 or 2 faces; cells holding a face prior keep it, so the
// start still satisfies the prior when it did. Passes repeat until none improves, at most
// max_passes (hypothesis.start_descent_passes): every accepted change lowers the energy, so the search ends,
// and it visits the same cells in the same order on every machine.
std::vector<bool> start_assignment(const CandidateFaces& out, const PlainArrangement& arr, const Levels& lv,
                                   std::size_t cell_count, const SelectionParams& energy,
                                   std::size_t max_passes) {
  const SelectionProblem& prob = out.problem;
  const std::size_t nf = out.faces.size();
  const int floor_level = lv.floor();
  std::vector<bool> is_prior(nf, false);
  for (auto f : prob.face_prior) is_prior[f] = true;
  std::vector<std::vector<std::uint32_t>> roofs_of_cell(cell_count), walls_of_edge(arr.edges.size());
  std::vector<Point3> wall_centroid(nf);
  std::vector<bool> selected(nf, false);
  for (std::uint32_t i = 0; i < nf; ++i) {
    const auto& f = out.faces[i];
    if (f.kind == FaceKind::roof) roofs_of_cell[f.cell_or_edge].push_back(i);
    if (f.kind == FaceKind::floor) selected[i] = true;
    if (f.kind == FaceKind::wall) {
      walls_of_edge[f.cell_or_edge].push_back(i);
      wall_centroid[i] = centroid(out.polygons[i]);
    }
  }
  std::vector<std::vector<std::uint32_t>> edges_of_face(nf);
  for (std::uint32_t e = 0; e < prob.edges.size(); ++e)
    for (auto f : prob.edges[e].faces) edges_of_face[f].push_back(e);

  // The chosen roof face per cell, and per problem edge how many selected faces it has.
  std::vector<std::uint32_t> roof_of_cell(cell_count);
  std::vector<bool> prior_cell(cell_count, false);
  for (std::size_t c = 0; c < cell_count; ++c) {
    if (roofs_of_cell[c].empty()) return {};
    std::uint32_t best = roofs_of_cell[c].front();
    for (auto i : roofs_of_cell[c]) {
      if (is_prior[i] != is_prior[best] ? is_prior[i] : prob.support[i] > prob.support[best]) best = i;
      prior_cell[c] = prior_cell[c] || is_prior[i];
    }
    roof_of_cell[c] = best;
  }
  std::vector<int> count(prob.edges.size(), 0);
  std::size_t bad = 0;
  const auto is_bad = [](int n) { return n != 0 && n != 2; };
  // The energy's parts: sum of support and of roof preference over the selected faces, and the
  // edges where two selected faces meet at a sharp angle.
  const double z_span = prob.z_max - prob.z_min;
  double support_sum = 0.0, roof_sum = 0.0, unsupported_sum = 0.0;
  std::size_t sharp_edges = 0;
  std::vector<bool> sharp(prob.edges.size(), false);
  const auto toggle = [&](std::uint32_t f) {
    selected[f] = !selected[f];
    const double sign = selected[f] ? 1.0 : -1.0;
    support_sum += sign * prob.support[f];
    if (!prob.unsupported.empty()) unsupported_sum += sign * prob.unsupported[f];
    if (z_span > 0) roof_sum += sign * (prob.z_max - prob.centroid_z[f]) / z_span;
    for (auto e : edges_of_face[f]) {
      bad -= is_bad(count[e]);
      count[e] += selected[f] ? 1 : -1;
      bad += is_bad(count[e]);
      bool now = false;
      for (const auto& [a, b] : prob.edges[e].sharp_pairs) now = now || (selected[a] && selected[b]);
      if (now != sharp[e]) {
        sharp[e] = now;
        sharp_edges += now ? 1 : std::size_t(0) - 1;
      }
    }
  };
  const auto current_energy = [&] {
    const double data = prob.point_count ? 1.0 - support_sum / static_cast<double>(prob.point_count) : 0.0;
    const double complexity = prob.edges.empty() ? 0.0 : static_cast<double>(sharp_edges) / prob.edges.size();
    const double roof = nf ? roof_sum / static_cast<double>(nf) : 0.0;
    const double unsupported = prob.unsupported.empty() ? 0.0 : unsupported_sum / prob.plan_area;
    return energy.lambda_data * data + energy.lambda_complexity * complexity + energy.lambda_roof * roof +
           energy.lambda_unsupported * unsupported;
  };
  const auto level = [&](int cell) {
    return cell < 0 ? floor_level : out.faces[roof_of_cell[static_cast<std::size_t>(cell)]].source;
  };
  const auto wall_on = [&](std::uint32_t f) {
    const auto& edge = arr.edges[out.faces[f].cell_or_edge];
    const int a = level(edge.left), b = level(edge.right);
    if (a == b) return false;
    const Point3& c = wall_centroid[f];
    const double ha = lv.height(a, c.x, c.y), hb = lv.height(b, c.x, c.y);
    return std::min(ha, hb) < c.z && c.z < std::max(ha, hb);
  };
  // Puts roof face `roof` on cell c and updates the walls around it.
  const auto choose = [&](std::size_t c, std::uint32_t roof) {
    if (selected[roof_of_cell[c]]) toggle(roof_of_cell[c]);
    roof_of_cell[c] = roof;
    toggle(roof);
    for (const auto& [e, forward] : arr.cells[c].loop)
      for (auto f : walls_of_edge[e])
        if (selected[f] != wall_on(f)) toggle(f);
  };
  for (std::uint32_t f = 0; f < nf; ++f)
    if (selected[f]) {
      selected[f] = false;
      toggle(f);
    }
  for (std::size_t c = 0; c < cell_count; ++c) choose(c, roof_of_cell[c]);

  const std::size_t max_steps = 4 * cell_count + 16;
  for (std::size_t step = 0; bad > 0 && step < max_steps; ++step) {
    std::size_t e = 0;
    while (!is_bad(count[e])) ++e;
    std::vector<std::size_t> cells;
    for (auto f : prob.edges[e].faces) {
      const auto& face = out.faces[f];
      if (face.kind != FaceKind::wall) {
        cells.push_back(face.cell_or_edge);
        continue;
      }
      for (int side : {arr.edges[face.cell_or_edge].left, arr.edges[face.cell_or_edge].right})
        if (side >= 0) cells.push_back(static_cast<std::size_t>(side));
    }
    std::sort(cells.begin(), cells.end());
    cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
    std::size_t best_bad = bad, best_cell = 0;
    std::uint32_t best_roof = 0;
    for (bool allow_prior : {false, true}) {
      for (std::size_t c : cells) {
        if (prior_cell[c] && !allow_prior) continue;
        const std::uint32_t current = roof_of_cell[c];
        for (auto roof : roofs_of_cell[c]) {
          if (roof == current) continue;
          choose(c, roof);
          if (bad < best_bad) {
            best_bad = bad;
            best_cell = c;
            best_roof = roof;
          }
          choose(c, current);
        }
      }
      if (best_bad < bad) break;
    }
    if (best_bad == bad) break;
    choose(best_cell, best_roof);
  }
  if (bad > 0) {
    log_debug("hypothesis: no start assignment (" + std::to_string(bad) +
              " edges left with one or more than two faces)");
    return {};
  }

  // Descent: one cell's roof at a time, closed and prior-keeping changes only.
  const double initial = current_energy();
  double e_now = initial;
  std::size_t passes = 0, changes = 0;
  for (bool improved = true; improved && passes < max_passes; ++passes) {
    improved = false;
    for (std::size_t c = 0; c < cell_count; ++c) {
      const std::uint32_t current = roof_of_cell[c];
      if (is_prior[current]) continue;
      std::uint32_t best = current;
      double best_energy = e_now;
      for (auto roof : roofs_of_cell[c]) {
        if (roof == current) continue;
        choose(c, roof);
        const double e = current_energy();
        if (bad == 0 && e < best_energy - kEnergyTolerance) {
          best = roof;
          best_energy = e;
        }
        choose(c, current);
      }
      if (best == current) continue;
      choose(c, best);
      e_now = current_energy();
      improved = true;
      ++changes;
    }
  }
  log_debug("hypothesis: start energy " + std::to_string(initial) + " -> " + std::to_string(e_now) + " (" +
            std::to_string(changes) + " cells changed in " + std::to_string(passes) + " passes)");
  return selected;
}

}  // namespace city3d::detail
