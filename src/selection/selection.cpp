// Face selection: builds the linearised integer program of selection.hpp, reduces it exactly,
// splits it into independent components and solves each with GLPK or CBC.
//
// The program handed to a backend (PolyFit's linearisation, after the reductions below):
//
//   variables  x_i in {0,1}   per free face (faces forced equal by a two-face edge share one variable)
//              y_e in {0,1}   per edge with three or more free faces and none fixed on
//              c_e in [0,1]   per edge whose corner indicator is not constant (continuous: at any
//                             integral x its cheapest value is already 0 or 1, so a binary would only
//                             add branching)
//   minimise   sum_i x_i (-lambda_d support_i / |P| + lambda_r (z_max - z_i) / ((z_max - z_min) |F|)
//                         + lambda_u unsupported_i / A)
//              + lambda_c / |E| sum_e c_e          (the constant lambda_d and the terms of faces
//                                                   fixed on stay out; selection_energy() adds them)
//   subject to sum_{j in N(e)} x_j - 2 y_e = 0     edge used by 0 or 2 faces
//              sum_{j in N(e), free} x_j = 1       edge with exactly one face fixed on
//              c_e >= x_i - sum_{j ~ i} x_j        each face i of e with a sharp partner, j ~ i its
//                                                  coplanar partners (edges with y_e; see build_program)
//              c_e >= x_i + x_j - 1                each sharp pair (i, j) of an edge with one face on or
//                                                  two free faces (c_e >= x_j when x_i = 1)
//              sum_{k in group} x_k = 1            each exactly_one group with free faces (single layer)
//              x_i + x_j <= 1                      each vertically overlapping pair no group covers
//
// Single layer: the paper writes sum_{k in V(f_i)} x_k = 1 for every face. With partially overlapping
// candidate faces (face A overlaps B and C, which do not overlap each other) that equality asks for
// exactly one of {A, B} and exactly one of {A, C}, and chains of such sets easily become infeasible, and
// it also forces a roof where no face should be selected. So the equality is kept only for the groups
// where it holds (problem.exactly_one: faces that each cover the whole group's area, which must be
// roofed; tight for the LP relaxation), and every other overlap gets the pairwise x_i + x_j <= 1:
// coverage is already implied by watertightness (a closed surface over the footprint has a roof
// everywhere), so elsewhere only "never two layers" is needed.
//
// Exact reductions before solving (they never change the optimum):
//  - face prior / forced_on fix faces to 1, forced_off to 0, and fixed values are substituted;
//  - propagation on edges: two faces on => the rest off; one on and one free => that one on; no face
//    on and one free => that one off (it cannot be paired); overlaps of a face on => partner off;
//    contradictions are reported as infeasible without calling a solver;
//  - an edge with exactly two free faces and none on makes them equal: they share one variable (and
//    its sharp corner costs lambda_c / |E| on that variable directly);
//  - faces linked by no constraint chain are independent: each connected component is solved alone.
//
// Start: when the problem carries a start assignment (the hypothesis builds one: one roof per cell)
// that satisfies this call's constraints, it is mapped onto each component's variables, handed to
// CBC as its MIP start, and kept whenever a limit stops a backend with nothing better, so a
// building never falls back only because no feasible point was found in time.
//
// Limits: node_limit applies to each component's search; time_limit to the whole call (each
// component gets the time left; backends can overshoot it by their root processing). solver = "auto"
// uses GLPK (with glpk_time_share of the time left, when there is a time limit), then CBC on the rest if GLPK
// stopped on a limit. Components of more than max_exact_variables are solved by windows.
#include "city3d/selection.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/log.hpp"
#include "selection/solver.hpp"
#include "selection/solver_process.hpp"
#include "selection/windows.hpp"

namespace city3d {
namespace {

using detail::MipLimits;
using detail::MipModel;
using detail::MipSolution;
using detail::MipStatus;

// Why solver = "auto" gives every program to GLPK first (CBC only after GLPK's node limit): with the
// corner rows per face (build_program) the LP relaxation is tight and GLPK, in this process, solves
// the hypothesis' programs fastest at every size measured. 2026-11-24, one run each side by side
// (docs/BENCHMARKS.md, "Solvers"): Delft block selection 0.42 s with GLPK for all against 1.37 s with
// CBC from 200 variables; city3d_dev (197 clouds) 60.5 s of CPU in all against 151.5 s, p99 3.3 s
// against 8.6 s. (With the pairwise corner rows CBC had been faster from ~200 variables: GLPK needed
// 5 s where CBC needed 0.3 s on Vaihingen 00039 and 00049.)

constexpr std::int8_t kFree = -1;

/// Union-find whose root is always the smallest member, so numbering by root is deterministic.
class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  std::size_t find(std::size_t a) {
    while (parent_[a] != a) a = parent_[a] = parent_[parent_[a]];
    return a;
  }
  void unite(std::size_t a, std::size_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (b < a) std::swap(a, b);
    parent_[b] = a;
  }

 private:
  std::vector<std::size_t> parent_;
};

/// Gathers every structural problem of `problem` and throws once.
void check_problem(const SelectionProblem& problem) {
  std::vector<std::string> errors;
  const std::size_t n = problem.face_count;
  const auto add = [&errors](std::string e) {
    if (errors.size() < 10) errors.push_back(std::move(e));
  };
  if (problem.support.size() != n)
    add("support has " + std::to_string(problem.support.size()) + " entries, need " + std::to_string(n));
  if (problem.centroid_z.size() != n)
    add("centroid_z has " + std::to_string(problem.centroid_z.size()) + " entries, need " +
        std::to_string(n));
  if (!problem.is_roof.empty() && problem.is_roof.size() != n)
    add("is_roof has " + std::to_string(problem.is_roof.size()) + " entries, need 0 or " + std::to_string(n));
  if (problem.point_count == 0) add("point_count is 0");
  if (!problem.unsupported.empty() && problem.unsupported.size() != n)
    add("unsupported has " + std::to_string(problem.unsupported.size()) + " entries, need 0 or " + std::to_string(n));
  if (!problem.unsupported.empty() && !(problem.plan_area > 0.0))
    add("plan_area " + std::to_string(problem.plan_area) + " is not > 0");
  if (!(problem.z_max > problem.z_min))
    add("z_max " + std::to_string(problem.z_max) + " is not above z_min " + std::to_string(problem.z_min));
  for (std::size_t e = 0; e < problem.edges.size(); ++e) {
    const auto& edge = problem.edges[e];
    std::vector<std::uint32_t> sorted = edge.faces;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
      add("edge " + std::to_string(e) + " lists a face twice");
    for (auto f : edge.faces)
      if (f >= n)
        add("edge " + std::to_string(e) + " names face " + std::to_string(f) + " of " + std::to_string(n));
    for (const auto& [a, b] : edge.sharp_pairs)
      if (a == b || !std::binary_search(sorted.begin(), sorted.end(), a) ||
          !std::binary_search(sorted.begin(), sorted.end(), b))
        add("edge " + std::to_string(e) + " has sharp pair (" + std::to_string(a) + ", " + std::to_string(b) +
            ") not made of two of its faces");
  }
  for (const auto& [a, b] : problem.vertical_overlaps)
    if (a >= n || b >= n || a == b)
      add("vertical overlap (" + std::to_string(a) + ", " + std::to_string(b) + ") is not a pair of faces");
  for (std::size_t g = 0; g < problem.exactly_one.size(); ++g) {
    std::vector<std::uint32_t> sorted = problem.exactly_one[g];
    std::sort(sorted.begin(), sorted.end());
    if (sorted.empty()) add("exactly_one group " + std::to_string(g) + " is empty");
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
      add("exactly_one group " + std::to_string(g) + " lists a face twice");
    if (!sorted.empty() && sorted.back() >= n)
      add("exactly_one group " + std::to_string(g) + " names face " + std::to_string(sorted.back()) + " of " +
          std::to_string(n));
  }
  const auto check_list = [&](const std::vector<std::uint32_t>& list, const char* name) {
    for (auto f : list)
      if (f >= n) add(std::string(name) + " names face " + std::to_string(f) + " of " + std::to_string(n));
  };
  if (!problem.start.empty() && problem.start.size() != n)
    add("start has " + std::to_string(problem.start.size()) + " entries, need 0 or " + std::to_string(n));
  check_list(problem.face_prior, "face_prior");
  check_list(problem.forced_on, "forced_on");
  check_list(problem.forced_off, "forced_off");
  if (errors.empty()) return;
  std::string message = "invalid problem (" + std::to_string(n) + " faces):";
  for (const auto& e : errors) message += " " + e + ";";
  message.pop_back();
  throw ReconstructionError(ReconstructionStage::selection, message);
}

/// The objective coefficient of x_i (without the constant lambda_d).
double face_cost(const SelectionProblem& problem, const SelectionParams& params, std::size_t i) {
  const double data = -params.lambda_data * problem.support[i] / static_cast<double>(problem.point_count);
  const double roof = params.lambda_roof * (problem.z_max - problem.centroid_z[i]) /
                      ((problem.z_max - problem.z_min) * static_cast<double>(problem.face_count));
  const double unsupported =
      problem.unsupported.empty() ? 0.0 : params.lambda_unsupported * problem.unsupported[i] / problem.plan_area;
  return data + roof + unsupported;
}

double corner_cost(const SelectionProblem& problem, const SelectionParams& params) {
  return problem.edges.empty() ? 0.0 : params.lambda_complexity / static_cast<double>(problem.edges.size());
}

/// Fixes faces from the priors and propagates through edges and overlaps. Returns an empty string,
/// or why the program is infeasible.
std::string propagate_fixings(const SelectionProblem& problem, const SelectionParams& params,
                              std::vector<std::int8_t>& value) {
  const std::size_t n = problem.face_count;
  value.assign(n, kFree);
  std::vector<std::vector<std::uint32_t>> edges_of(n), overlaps_of(n), groups_of(n);
  for (std::size_t e = 0; e < problem.edges.size(); ++e)
    for (auto f : problem.edges[e].faces) edges_of[f].push_back(static_cast<std::uint32_t>(e));
  if (params.use_single_layer) {
    for (const auto& [a, b] : problem.vertical_overlaps) {
      overlaps_of[a].push_back(b);
      overlaps_of[b].push_back(a);
    }
    for (std::size_t g = 0; g < problem.exactly_one.size(); ++g)
      for (auto f : problem.exactly_one[g]) groups_of[f].push_back(static_cast<std::uint32_t>(g));
  }

  std::deque<std::uint32_t> queue;
  std::string conflict;
  const auto fix = [&](std::uint32_t f, std::int8_t v, const std::string& why) {
    if (value[f] == kFree) {
      value[f] = v;
      queue.push_back(f);
    } else if (value[f] != v && conflict.empty()) {
      conflict = "face " + std::to_string(f) + " must be " + (v ? "on" : "off") + " (" + why + ") but is " +
                 (value[f] ? "on" : "off");
    }
  };
  for (auto f : problem.forced_on) fix(f, 1, "forced on");
  if (params.use_face_prior)
    for (auto f : problem.face_prior) fix(f, 1, "face prior");
  for (auto f : problem.forced_off) fix(f, 0, "forced off");

  // How many of `faces` are on and how many free, and the last free one.
  struct Tally {
    int on = 0, open = 0;
    std::uint32_t last_open = 0;
  };
  const auto tally = [&](const std::vector<std::uint32_t>& faces) {
    Tally t;
    for (auto f : faces) {
      if (value[f] == 1) ++t.on;
      if (value[f] == kFree) {
        ++t.open;
        t.last_open = f;
      }
    }
    return t;
  };
  const auto settle_edge = [&](std::uint32_t e) {
    const auto& faces = problem.edges[e].faces;
    const auto [on, open, last_open] = tally(faces);
    const std::string where = "edge " + std::to_string(e);
    if (on > 2 && conflict.empty()) conflict = where + " has " + std::to_string(on) + " faces on";
    if (on == 1 && open == 0 && conflict.empty()) conflict = where + " has one face on and no partner left";
    if (on == 2)
      for (auto f : faces)
        if (value[f] == kFree) fix(f, 0, where + " already has two faces");
    if (on == 1 && open == 1) fix(last_open, 1, "only partner on " + where);
    if (on == 0 && open == 1) fix(last_open, 0, "only candidate on " + where);
  };
  // A group: a face on => the rest off; none on and one left open => that one on.
  const auto settle_group = [&](std::uint32_t g) {
    const auto& faces = problem.exactly_one[g];
    const auto [on, open, last_open] = tally(faces);
    const std::string where = "roof group " + std::to_string(g);
    if (on > 1 && conflict.empty()) conflict = where + " has " + std::to_string(on) + " faces on";
    if (on == 0 && open == 0 && conflict.empty()) conflict = where + " has no face left";
    if (on == 1)
      for (auto f : faces)
        if (value[f] == kFree) fix(f, 0, where + " already has its face");
    if (on == 0 && open == 1) fix(last_open, 1, "only face left in " + where);
  };
  for (std::uint32_t e = 0; e < problem.edges.size(); ++e) settle_edge(e);
  if (params.use_single_layer)
    for (std::uint32_t g = 0; g < problem.exactly_one.size(); ++g) settle_group(g);
  while (!queue.empty() && conflict.empty()) {
    const std::uint32_t f = queue.front();
    queue.pop_front();
    for (auto e : edges_of[f]) settle_edge(e);
    for (auto g : groups_of[f]) settle_group(g);
    if (value[f] == 1)
      for (auto g : overlaps_of[f]) fix(g, 0, "overlaps face " + std::to_string(f) + " which is on");
  }
  return conflict;
}

/// A constraint over global variables (face classes first, then auxiliary y_e / c_e).
struct GlobalRow {
  std::vector<std::size_t> vars;
  std::vector<double> coefs;
  double lower, upper;
  void add(std::size_t var, double coef) {
    for (std::size_t k = 0; k < vars.size(); ++k)
      if (vars[k] == var) {
        coefs[k] += coef;
        return;
      }
    vars.push_back(var);
    coefs.push_back(coef);
  }
};

struct GlobalProgram {
  std::vector<std::size_t> class_of_face;  // class index per free face (unused for fixed faces)
  std::vector<MipModel::Column> columns;   // classes first, then auxiliaries
  std::size_t class_count = 0;
  std::vector<GlobalRow> rows;
};

GlobalProgram build_program(const SelectionProblem& problem, const SelectionParams& params,
                            const std::vector<std::int8_t>& value) {
  const std::size_t n = problem.face_count;
  const double inf = std::numeric_limits<double>::infinity();
  GlobalProgram program;

  // Faces forced equal by an edge with exactly two free faces and none on.
  DisjointSets equal(n);
  for (const auto& edge : problem.edges) {
    std::vector<std::uint32_t> open;
    int on = 0;
    for (auto f : edge.faces) {
      if (value[f] == kFree) open.push_back(f);
      on += value[f] == 1;
    }
    if (on == 0 && open.size() == 2) equal.unite(open[0], open[1]);
  }
  program.class_of_face.assign(n, 0);
  std::vector<std::size_t> class_of_root(n, SIZE_MAX);
  for (std::size_t f = 0; f < n; ++f) {
    if (value[f] != kFree) continue;
    const std::size_t root = equal.find(f);
    if (class_of_root[root] == SIZE_MAX) {
      class_of_root[root] = program.columns.size();
      program.columns.push_back({0.0, 0.0, 1.0, true});
    }
    program.class_of_face[f] = class_of_root[root];
    program.columns[program.class_of_face[f]].cost += face_cost(problem, params, f);
  }
  program.class_count = program.columns.size();

  const double corner = corner_cost(problem, params);
  for (std::size_t e = 0; e < problem.edges.size(); ++e) {
    const auto& edge = problem.edges[e];
    std::vector<std::uint32_t> open;
    int on = 0;
    for (auto f : edge.faces) {
      if (value[f] == kFree) open.push_back(f);
      on += value[f] == 1;
    }
    if (open.empty()) continue;  // settled: its corner indicator is a constant
    const bool merged = on == 0 && open.size() == 2;
    if (!merged) {
      GlobalRow row;
      for (auto f : open) row.add(program.class_of_face[f], 1.0);
      if (on == 0) {  // sum x - 2 y_e = 0
        row.add(program.columns.size(), -2.0);
        program.columns.push_back({0.0, 0.0, 1.0, true});
        row.lower = row.upper = 0.0;
      } else {  // exactly one face on (propagation leaves on in {0, 1} with >= 2 free faces)
        row.lower = row.upper = 1.0;
      }
      program.rows.push_back(std::move(row));
    }
    if (corner == 0.0) continue;

    // Corner indicator: each live sharp pair is one class (the other face on, or both faces in the
    // same class: c_e >= x) or two classes (c_e >= x_a + x_b - 1).
    bool always_sharp = false;
    std::vector<std::pair<std::size_t, std::size_t>> pairs;  // second == SIZE_MAX: single class
    for (const auto& [a, b] : edge.sharp_pairs) {
      if (value[a] == 0 || value[b] == 0) continue;
      if (value[a] == 1 && value[b] == 1) {
        always_sharp = true;
        break;
      }
      if (value[a] == 1)
        pairs.emplace_back(program.class_of_face[b], SIZE_MAX);
      else if (value[b] == 1)
        pairs.emplace_back(program.class_of_face[a], SIZE_MAX);
      else if (program.class_of_face[a] == program.class_of_face[b])
        pairs.emplace_back(program.class_of_face[a], SIZE_MAX);
      else
        pairs.emplace_back(program.class_of_face[a], program.class_of_face[b]);
    }
    if (always_sharp || pairs.empty()) continue;
    const bool one_class = std::all_of(pairs.begin(), pairs.end(), [&](const auto& p) {
      return p.second == SIZE_MAX && p.first == pairs.front().first;
    });
    if (one_class) {  // c_e = x exactly: put the cost on x
      program.columns[pairs.front().first].cost += corner;
      continue;
    }
    const std::size_t c = program.columns.size();
    program.columns.push_back({corner, 0.0, 1.0, false});
    if (on == 0 && !merged) {
      // An edge of three or more free faces (sum x = 2 y_e): per face i with a sharp partner,
      // c_e >= x_i - sum of x_j over i's non-sharp (coplanar) partners j. At an integral point it
      // says what the pairs say (with i on, c_e = 1 unless i's partner is coplanar with it), but it
      // is far tighter for the LP relaxation: two sharp faces at 1/2 each give c_e >= 1/2, where
      // c_e >= x_i + x_j - 1 gives 0. Measured: the Delft block's programs 3.3 s -> 0.4 s in all,
      // the same optima (docs/BENCHMARKS.md).
      for (auto i : open) {
        bool has_sharp_partner = false;
        GlobalRow row;
        row.add(c, 1.0);
        row.add(program.class_of_face[i], -1.0);
        for (auto j : open) {
          if (j == i) continue;
          const bool sharp = std::any_of(edge.sharp_pairs.begin(), edge.sharp_pairs.end(), [&](const auto& p) {
            return (p.first == i && p.second == j) || (p.first == j && p.second == i);
          });
          if (sharp)
            has_sharp_partner = true;
          else
            row.add(program.class_of_face[j], 1.0);
        }
        if (!has_sharp_partner) continue;
        row.lower = 0.0;
        row.upper = inf;
        program.rows.push_back(std::move(row));
      }
      continue;
    }
    for (const auto& [a, b] : pairs) {
      GlobalRow row;
      row.add(c, 1.0);
      row.add(a, -1.0);
      if (b != SIZE_MAX) row.add(b, -1.0);
      row.lower = b == SIZE_MAX ? 0.0 : -1.0;
      row.upper = inf;
      program.rows.push_back(std::move(row));
    }
  }

  // Single layer: one equality per group with free faces (propagation leaves a group with a face
  // on fully settled), then the overlapping pairs no group already covers.
  std::vector<int> group_of(n, -1);
  if (params.use_single_layer)
    for (std::size_t g = 0; g < problem.exactly_one.size(); ++g) {
      GlobalRow row;
      for (auto f : problem.exactly_one[g]) {
        group_of[f] = static_cast<int>(g);
        if (value[f] == kFree) row.add(program.class_of_face[f], 1.0);
      }
      if (row.vars.empty()) continue;
      row.lower = row.upper = 1.0;
      program.rows.push_back(std::move(row));
    }
  if (params.use_single_layer)
    for (const auto& [a, b] : problem.vertical_overlaps) {
      if (value[a] != kFree || value[b] != kFree) continue;  // settled by propagation
      if (group_of[a] >= 0 && group_of[a] == group_of[b]) continue;  // in its group's equality
      GlobalRow row;
      row.add(program.class_of_face[a], 1.0);
      row.add(program.class_of_face[b], 1.0);
      row.lower = -inf;
      row.upper = 1.0;
      program.rows.push_back(std::move(row));
    }
  return program;
}

/// The program's variables at the face assignment `start` (classes from their faces, y_e and c_e at
/// their cheapest values), or empty when it does not fit the program: a class whose faces disagree,
/// a face that propagation fixed otherwise, or a row it violates.
std::vector<double> program_start(const SelectionProblem& problem, const GlobalProgram& program,
                                  const std::vector<std::int8_t>& value, const std::vector<bool>& start) {
  if (start.size() != problem.face_count) return {};
  std::vector<double> x(program.columns.size(), 0.0);
  std::vector<bool> set(program.class_count, false);
  for (std::size_t f = 0; f < problem.face_count; ++f) {
    const double v = start[f] ? 1.0 : 0.0;
    if (value[f] != kFree) {
      if (value[f] != static_cast<std::int8_t>(start[f])) return {};
      continue;
    }
    const std::size_t k = program.class_of_face[f];
    if (set[k] && x[k] != v) return {};
    set[k] = true;
    x[k] = v;
  }
  // Each row holds at most one auxiliary: y_e (integer, in an equality) or c_e (continuous, >=).
  for (const GlobalRow& row : program.rows) {
    double rest = 0.0, coef = 0.0;
    std::size_t aux = SIZE_MAX;
    for (std::size_t i = 0; i < row.vars.size(); ++i) {
      if (row.vars[i] >= program.class_count) {
        aux = row.vars[i];
        coef = row.coefs[i];
      } else {
        rest += row.coefs[i] * x[row.vars[i]];
      }
    }
    if (aux == SIZE_MAX) continue;
    if (program.columns[aux].integer)
      x[aux] = -rest / coef;
    else
      x[aux] = std::max(x[aux], std::min(1.0, (row.lower - rest) / coef));
  }
  for (const GlobalRow& row : program.rows) {
    double sum = 0.0;
    for (std::size_t i = 0; i < row.vars.size(); ++i) sum += row.coefs[i] * x[row.vars[i]];
    if (sum < row.lower - 1e-9 || sum > row.upper + 1e-9) return {};
  }
  for (std::size_t v = 0; v < x.size(); ++v)
    if (program.columns[v].integer && x[v] != 0.0 && x[v] != 1.0) return {};
  return x;
}

struct Component {
  std::vector<std::size_t> vars;  // global variable indices, increasing
  std::vector<std::size_t> rows;  // global row indices, increasing
};

std::vector<Component> split_components(const GlobalProgram& program) {
  const std::size_t v = program.columns.size();
  DisjointSets linked(v);
  for (const auto& row : program.rows)
    for (std::size_t k = 1; k < row.vars.size(); ++k) linked.unite(row.vars[0], row.vars[k]);
  std::vector<std::size_t> index_of_root(v, SIZE_MAX);
  std::vector<Component> components;
  for (std::size_t i = 0; i < v; ++i) {
    const std::size_t root = linked.find(i);
    if (index_of_root[root] == SIZE_MAX) {
      index_of_root[root] = components.size();
      components.emplace_back();
    }
    components[index_of_root[root]].vars.push_back(i);
  }
  for (std::size_t r = 0; r < program.rows.size(); ++r)
    if (!program.rows[r].vars.empty())
      components[index_of_root[linked.find(program.rows[r].vars[0])]].rows.push_back(r);
  return components;
}

const char* status_name(SelectionStatus status) {
  switch (status) {
    case SelectionStatus::optimal:
      return "optimal";
    case SelectionStatus::feasible:
      return "feasible";
    case SelectionStatus::infeasible:
      return "infeasible";
    case SelectionStatus::no_solution:
      return "no_solution";
  }
  return "?";
}

/// The backends one solve_selection() call used, and the CBC failures GLPK stood in for.
struct Backends {
  bool glpk = false, cbc = false;
  std::vector<std::string> failures;
};

/// One program through the backends `params` choose, under the node limit and the time left: "auto"
/// gives it to GLPK, then to CBC when GLPK stopped on a limit (the better answer is kept) or broke;
/// "glpk" and "cbc" use that backend alone, and a broken backend hands the program to the other.
/// A limit that stops the search keeps the start when it is better than what was found.
MipSolution solve_program(const MipModel& model, const SelectionParams& params,
                          const std::function<double()>& time_left, Backends& used, bool window = false) {
  const bool automatic = params.solver == "auto";
  MipLimits limits;
  limits.node_limit = params.node_limit;
  limits.presolve_relaxation = window;
  limits.gomory_min_columns = params.gomory_min_columns;
  limits.time_limit = time_left();
  MipSolution part;
  bool from_cbc = false;  // which backend gave `part`
  const auto glpk = [&] {
    used.glpk = true;
    return detail::solve_with_glpk(model, limits);
  };
  const auto cbc = [&] {
    used.cbc = true;
    return detail::solve_with_cbc(model, limits);
  };
  if (limits.time_limit <= 0.0) {
    part.status = MipStatus::no_solution;
    part.message = "time limit " + std::to_string(params.time_limit) + " s reached before this program";
  } else if (params.solver == "cbc") {
    part = cbc();
    from_cbc = true;
  } else if (!automatic) {
    part = glpk();
  } else {
    // GLPK first (with glpk_time_share of the time left, when there is a time limit): with the tight corner
    // rows it solves the real programs fastest (docs/BENCHMARKS.md), in this process, without CBC's per-call
    // process. Where it stops on its node limit, CBC (preprocessing, cuts, heuristics) gets the program too
    // and the better answer is kept.
    if (std::isfinite(limits.time_limit)) limits.time_limit *= params.glpk_time_share;
    part = glpk();
    limits.time_limit = time_left();
    if ((part.status == MipStatus::feasible || part.status == MipStatus::no_solution) && limits.time_limit > 0.0) {
      MipSolution second = cbc();
      if (second.status == MipStatus::failed) {
        used.failures.push_back(second.message + "; glpk's selection kept");
      } else {
        const bool better = second.status == MipStatus::optimal || second.status == MipStatus::infeasible ||
                            (second.status == MipStatus::feasible &&
                             (part.status == MipStatus::no_solution || second.objective < part.objective));
        if (better) {
          part = std::move(second);
          from_cbc = true;
        }
      }
    }
  }
  if (part.status == MipStatus::failed) {
    // The backend broke (CBC's process crashed on an assertion inside Clp, or GLPK reported an
    // internal error): the same program goes to the other backend under the same node limit, so
    // the building still gets a selection and the run goes on.
    used.failures.push_back(part.message + (from_cbc ? "; solved with glpk instead" : "; solved with cbc instead"));
    limits.time_limit = time_left();
    part = limits.time_limit > 0.0 ? (from_cbc ? glpk() : cbc()) : MipSolution{};
    if (part.status == MipStatus::failed) {
      used.failures.push_back(part.message);
      part.status = MipStatus::no_solution;
    }
  }
  if (!model.start.empty() && (part.status == MipStatus::no_solution || part.status == MipStatus::feasible)) {
    // A limit stopped the backend: the start is feasible, so keep whichever is better.
    double start_objective = 0.0;
    for (std::size_t j = 0; j < model.columns.size(); ++j) start_objective += model.columns[j].cost * model.start[j];
    if (part.status == MipStatus::no_solution || start_objective < part.objective - 1e-12) {
      part.status = MipStatus::feasible;
      part.values = model.start;
      part.objective = start_objective;
      part.message += "; the start assignment is kept";
    }
  }
  return part;
}

}  // namespace

void SelectionParams::validate() const {
  std::vector<std::string> errors;
  // Up to a million: the terms are normalised to [0, 1], and a weight of 1e308 overflows the solvers'
  // objective (CBC aborts on a cost over 1e25, GLPK's simplex fails its assertions).
  const auto weight = [&errors](double w, const char* name) {
    if (!std::isfinite(w) || w < 0.0 || w > 1e6) {
      std::ostringstream text;
      text << name << " = " << w << " (need 0 to 1e6)";
      errors.push_back(text.str());
    }
  };
  weight(lambda_data, "lambda_data");
  weight(lambda_complexity, "lambda_complexity");
  weight(lambda_roof, "lambda_roof");
  weight(lambda_unsupported, "lambda_unsupported");
  if (solver != "auto" && solver != "glpk" && solver != "cbc")
    errors.push_back("solver = '" + solver + "' (need auto, glpk or cbc)");
  if (!std::isfinite(time_limit) || time_limit < 0.0)
    errors.push_back("time_limit = " + std::to_string(time_limit) + " s (need >= 0; 0: none)");
  if (!(glpk_time_share > 0.0 && glpk_time_share <= 1.0))
    errors.push_back("glpk_time_share = " + std::to_string(glpk_time_share) + " (need (0, 1])");
  if (!(min_time_limit > 0.0) || !std::isfinite(min_time_limit))
    errors.push_back("min_time_limit = " + std::to_string(min_time_limit) + " s (need > 0)");
  if (node_limit < 1) errors.push_back("node_limit = " + std::to_string(node_limit) + " (need >= 1)");
  if (window_variables < 2) errors.push_back("window_variables = " + std::to_string(window_variables) + " (need >= 2)");
  if (window_rounds < 1) errors.push_back("window_rounds = " + std::to_string(window_rounds) + " (need >= 1)");
  if (errors.empty()) return;
  std::string message = "selection: invalid parameters:";
  for (const auto& e : errors) message += " " + e + ";";
  message.pop_back();
  throw ConfigError(message);
}

double selection_energy(const SelectionProblem& problem, const std::vector<bool>& selected,
                        const SelectionParams& params) {
  check_problem(problem);
  if (selected.size() != problem.face_count)
    throw ReconstructionError(ReconstructionStage::selection, "assignment has " + std::to_string(selected.size()) +
                              " entries for " + std::to_string(problem.face_count) + " faces");
  double support = 0.0, roof = 0.0, unsupported = 0.0;
  for (std::size_t i = 0; i < problem.face_count; ++i) {
    if (!selected[i]) continue;
    support += problem.support[i];
    roof += (problem.z_max - problem.centroid_z[i]) / (problem.z_max - problem.z_min);
    if (!problem.unsupported.empty()) unsupported += problem.unsupported[i];
  }
  std::size_t sharp = 0;
  for (const auto& edge : problem.edges)
    sharp += std::any_of(edge.sharp_pairs.begin(), edge.sharp_pairs.end(),
                         [&](const auto& p) { return selected[p.first] && selected[p.second]; });
  const double e_data = 1.0 - support / static_cast<double>(problem.point_count);
  const double e_complexity =
      problem.edges.empty() ? 0.0 : static_cast<double>(sharp) / static_cast<double>(problem.edges.size());
  const double e_roof = problem.face_count == 0 ? 0.0 : roof / static_cast<double>(problem.face_count);
  const double e_unsupported = problem.unsupported.empty() ? 0.0 : unsupported / problem.plan_area;
  return params.lambda_data * e_data + params.lambda_complexity * e_complexity + params.lambda_roof * e_roof +
         params.lambda_unsupported * e_unsupported;
}

bool satisfies_constraints(const SelectionProblem& problem, const std::vector<bool>& selected,
                           const SelectionParams& params) {
  if (selected.size() != problem.face_count) return false;
  const auto on = [&](std::uint32_t f) { return f < selected.size() && selected[f]; };
  for (const auto& edge : problem.edges) {
    const auto count = std::count_if(edge.faces.begin(), edge.faces.end(), on);
    if (count != 0 && count != 2) return false;
  }
  if (params.use_single_layer) {
    for (const auto& [a, b] : problem.vertical_overlaps)
      if (on(a) && on(b)) return false;
    for (const auto& group : problem.exactly_one)
      if (std::count_if(group.begin(), group.end(), on) != 1) return false;
  }
  if (params.use_face_prior && !std::all_of(problem.face_prior.begin(), problem.face_prior.end(), on))
    return false;
  if (!std::all_of(problem.forced_on.begin(), problem.forced_on.end(), on)) return false;
  return std::none_of(problem.forced_off.begin(), problem.forced_off.end(), on);
}

SelectionResult solve_selection(const SelectionProblem& problem, const SelectionParams& params) {
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&start] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  // Seconds the backends may still use: infinity unless the opt-in wall-clock limit is set.
  const auto time_left = [&] {
    return params.time_limit > 0.0 ? params.time_limit - elapsed() : std::numeric_limits<double>::infinity();
  };
  params.validate();
  check_problem(problem);

  SelectionResult result;
  const std::string prior_note = params.use_face_prior && !problem.face_prior.empty()
                                     ? " (the face prior fixes " + std::to_string(problem.face_prior.size()) +
                                           " faces; retry without it)"
                                     : "";

  std::vector<std::int8_t> value;
  const std::string conflict = propagate_fixings(problem, params, value);
  if (!conflict.empty()) {
    result.status = SelectionStatus::infeasible;
    result.solver = "presolve";
    result.message = "selection: infeasible: " + conflict + prior_note;
    result.seconds = elapsed();
    log_debug(result.message);
    return result;
  }

  const GlobalProgram program = build_program(problem, params, value);
  // The hypothesis' start assignment, when it satisfies this call's constraints (with the face prior
  // it may not).
  const std::vector<double> start_values =
      !problem.start.empty() && satisfies_constraints(problem, problem.start, params)
          ? program_start(problem, program, value, problem.start)
          : std::vector<double>{};
  const std::vector<Component> components = split_components(program);
  result.components = components.size();
  std::vector<double> solution(program.columns.size(), 0.0);
  Backends backends;
  result.status = SelectionStatus::optimal;
  std::vector<std::string> notes;

  for (std::size_t k = 0; k < components.size(); ++k) {
    const Component& component = components[k];
    std::vector<int> local(program.columns.size(), -1);
    MipModel model;
    for (std::size_t v : component.vars) {
      local[v] = static_cast<int>(model.columns.size());
      model.columns.push_back(program.columns[v]);
    }
    for (std::size_t r : component.rows) {
      const GlobalRow& global = program.rows[r];
      MipModel::Row row;
      for (std::size_t i = 0; i < global.vars.size(); ++i) {
        row.columns.push_back(local[global.vars[i]]);
        row.values.push_back(global.coefs[i]);
      }
      row.lower = global.lower;
      row.upper = global.upper;
      model.rows.push_back(std::move(row));
    }
    if (!start_values.empty())
      for (std::size_t v : component.vars) model.start.push_back(start_values[v]);
    result.variables += model.columns.size();
    result.constraints += model.rows.size();

    MipSolution part;
    if (model.columns.size() > params.max_exact_variables && !model.start.empty()) {
      // Too large to solve whole within the work limits: windows from the start.
      detail::WindowSearch search;
      part = detail::solve_by_windows(
          model, params.window_variables, params.window_rounds,
          [&](const MipModel& window) { return solve_program(window, params, time_left, backends, true); },
          search);
      ++result.window_components;
    } else {
      part = solve_program(model, params, time_left, backends);
    }
    const std::string where = "component " + std::to_string(k + 1) + "/" + std::to_string(components.size()) +
                              " (" + std::to_string(model.columns.size()) + " variables)";
    if (part.status == MipStatus::infeasible) {
      result.status = SelectionStatus::infeasible;
      notes.push_back(where + ": " + part.message);
      break;  // the whole program is infeasible; the other components do not matter
    }
    if (part.status == MipStatus::no_solution) {
      result.status = SelectionStatus::no_solution;
      notes.push_back(where + ": " + part.message);
      continue;
    }
    if (part.status == MipStatus::feasible) {
      if (result.status == SelectionStatus::optimal) result.status = SelectionStatus::feasible;
      notes.push_back(where + ": " + part.message);
    }
    for (std::size_t v : component.vars) solution[v] = part.values[local[v]];
  }
  result.solver = backends.glpk && backends.cbc ? "glpk+cbc" : backends.cbc ? "cbc" : backends.glpk ? "glpk" : "presolve";
  // Each distinct failure once, with how often it happened (windows can meet the same one again).
  for (const std::string& failure : backends.failures) {
    const auto times = std::count(backends.failures.begin(), backends.failures.end(), failure);
    const std::string text = failure + (times > 1 ? " (" + std::to_string(times) + " programs)" : "");
    if (std::find(result.backend_failures.begin(), result.backend_failures.end(), text) == result.backend_failures.end())
      result.backend_failures.push_back(text);
  }
  for (const std::string& failure : result.backend_failures) notes.push_back(failure);

  if (result.status == SelectionStatus::optimal || result.status == SelectionStatus::feasible) {
    result.selected.assign(problem.face_count, false);
    for (std::size_t f = 0; f < problem.face_count; ++f)
      result.selected[f] = value[f] == kFree ? solution[program.class_of_face[f]] > 0.5 : value[f] == 1;
    if (!satisfies_constraints(problem, result.selected, params)) {
      // Only a backend's numerical trouble can get here; never hand such a model on.
      result.status = SelectionStatus::no_solution;
      notes.push_back("the solver's assignment violates a hard constraint");
      result.selected.clear();
    } else {
      result.objective = selection_energy(problem, result.selected, params);
    }
  }
  if (result.status == SelectionStatus::infeasible) notes.back() += prior_note;
  for (const auto& note : notes) result.message += (result.message.empty() ? "selection: " : "; ") + note;
  result.seconds = elapsed();

  std::ostringstream line;
  line << "selection: " << problem.face_count << " faces, " << result.variables << " variables, "
       << result.constraints << " constraints, " << result.components << " components, " << result.solver
       << ", " << status_name(result.status) << ", energy " << result.objective << ", " << result.seconds << " s"
       << (start_values.empty() ? "" : ", from a start")
       << (result.message.empty() ? "" : ": " + result.message);
  log_debug(line.str());
  return result;
}

double solver_process_cpu_seconds() { return detail::children_cpu_seconds(); }

}  // namespace city3d
