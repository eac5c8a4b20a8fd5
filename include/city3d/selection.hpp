// Face selection (paper section 3.3 and appendix): choose the subset of candidate faces that forms
// the building by a binary integer program
//
//   min  lambda_d * E_d + lambda_c * E_c + lambda_r * E_r + lambda_u * E_u
//   E_d = 1 - (1/|P|) sum_i x_i support(f_i)                      data fitting (PolyFit)
//   E_c = (1/|E|) sum_e corner(e)                                  model complexity (PolyFit)
//   E_r = (1/|F|) sum_i x_i (z_max - z_i) / (z_max - z_min)        roof preference (City3D)
//   E_u = (1/A) sum_i x_i unsupported(f_i)                         surface no point supports (issue 23)
//   s.t. sum_{j in N(e)} x_j in {0, 2}  for every edge e          watertight, 2-manifold
//        single-layer roof: exactly one roof face over each cell, and vertically overlapping roof
//        faces never selected together
//        face prior: x_l = 1 for the best-supported face l of each planar segment
//        x_i in {0, 1}
//
// E_u is data fitting the other way, from the model to the points: unsupported(f_i) is the area of
// face i more than 1 m above the highest point within 1.5 m of it in plan (surface_support.hpp) and A
// the building's plan area. The data term pays lambda_d / |P| per point explained, about lambda_d / A
// per square metre of roof (|P| = density x A); at lambda_u = lambda_d a square metre of surface no
// point asks for costs what a square metre of points left out costs. Without it the energy is blind to
// such surface: a steep plane extended over a cell beyond its points (a blade metres above the roof)
// has no support and no cost, and wins where it saves a few sharp edges.
//
// The problem is solver-independent; backends (GLPK, COIN-OR CBC) sit behind solve_selection().
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace city3d {

/// The integer program of one building, built by the hypothesis module.
/// Every field is compared by same_hypothesis() (src/pipeline/rebuild.cpp), which lets the rebuilds skip
/// a hypothesis already selected over: a field added here must be compared there too.
struct SelectionProblem {
  std::size_t face_count = 0;                 ///< |F|, candidate faces 0..face_count-1
  std::vector<double> support;                ///< per face: support(f_i), points epsilon-close (may be weighted)
  std::vector<double> centroid_z;             ///< per face: z of the centroid (for E_r)
  std::vector<bool> is_roof;                  ///< per face: lies on a roof plane
  /// per face, or empty (no E_u): m2 of the face more than the tolerance above its local top
  std::vector<double> unsupported;
  double plan_area = 0.0;                     ///< A, m2: the plan area of the cells (> 0 with unsupported)
  std::size_t point_count = 0;                ///< |P|
  double z_min = 0.0, z_max = 1.0;            ///< lowest / highest building point z

  /// An edge of the candidate faces (a pairwise intersection): the faces that contain it, and the
  /// pairs of them whose joint selection makes a sharp (non-coplanar) edge.
  struct Edge {
    std::vector<std::uint32_t> faces;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> sharp_pairs;
  };
  std::vector<Edge> edges;

  /// Pairs of roof faces whose vertical projections overlap (area above a tolerance).
  std::vector<std::pair<std::uint32_t, std::uint32_t>> vertical_overlaps;
  /// Groups of roof faces that cover the same part of the footprint (in the 2.5D hypothesis: the
  /// roof faces over one cell), of which exactly one is selected: the paper's single-layer equality
  /// sum_{k in V(f_i)} x_k = 1. It holds where every face of a group covers the whole group's area
  /// and that area must be roofed; it implies the vertical overlaps inside a group and, unlike their
  /// pairwise form, is tight for the LP relaxation. Applied with use_single_layer.
  std::vector<std::vector<std::uint32_t>> exactly_one;
  /// Faces fixed to 1 by the face prior (best-supported face of each planar segment).
  std::vector<std::uint32_t> face_prior;
  /// Faces fixed to 1 for other reasons (e.g. the floor), and faces fixed to 0.
  std::vector<std::uint32_t> forced_on;
  std::vector<std::uint32_t> forced_off;
  /// A feasible assignment known in advance (empty when there is none): it satisfies every hard
  /// constraint except perhaps the face prior. The solvers start from it (CBC) or fall back on it
  /// when a limit stops them before they find a better one.
  std::vector<bool> start;
};

/// Energy weights and solver limits. Defaults are the paper's weights. Each weight is 0 to 1e6 (the
/// terms are normalised; larger weights overflow the solvers' objective).
struct SelectionParams {
  double lambda_data = 0.34;        ///< lambda_d
  /// lambda_c. 0.3, not the paper's 0.62: with the refitted planes and the step lines (issue 10) the
  /// hypothesis holds the roof parts that were missing, and at 0.62 the complexity term merged them
  /// away; 0.3 gave lower RMSE on the Delft block (0.193 against 0.197 m median, 2,958 against 2,868
  /// faces) and on every dataset of the dev set (docs/BENCHMARKS.md, "RMSE against faces").
  double lambda_complexity = 0.3;
  double lambda_roof = 0.04;        ///< lambda_r
  /// lambda_u: the weight of surface no point supports (E_u). lambda_d's value: a square metre of it
  /// weighs what a square metre of points left out weighs (see the file comment).
  double lambda_unsupported = 0.34;
  /// "auto": GLPK, then CBC where GLPK stops on its node limit or breaks; "glpk" or "cbc": that
  /// backend (the other one only where it breaks). See selection.cpp for the measurement.
  std::string solver = "auto";
  /// Opt-in wall-clock safety limit for the whole call, seconds; 0 (the default): none. When it
  /// fires, the result depends on the machine's speed and load.
  double time_limit = 0.0;
  /// With a time limit, "auto" gives GLPK this share of the time left, CBC the rest, in (0, 1].
  double glpk_time_share = 0.5;
  /// Under a building's time limit (ReconstructionParams::time_limit) each selection gets at least
  /// this many seconds, however little of its rung's share is left, > 0.
  double min_time_limit = 0.1;
  long node_limit = 1000;           ///< deterministic work limit: branch-and-bound nodes per program solved
  /// Components with more variables than this are solved by windows from the start (when there is
  /// one): sub-programs of about window_variables variables, the rest fixed, until a round of
  /// windows improves nothing or window_rounds rounds are done. Deterministic; not proven optimal.
  std::size_t max_exact_variables = 1500;
  std::size_t window_variables = 600;
  std::size_t window_rounds = 4;
  /// GLPK's search uses Gomory's mixed-integer cuts (beside the MIR cuts it always uses) on programs
  /// of more columns than this: below, they cost more than they save (docs/BENCHMARKS.md, "CPU: issue
  /// 27, fourteenth step"). Work, not outcome: the solutions were the same either way there.
  std::size_t gomory_min_columns = 1500;
  bool use_face_prior = true;
  bool use_single_layer = true;
  /// Throws ConfigError listing every invalid field.
  void validate() const;
};

enum class SelectionStatus {
  optimal,           ///< proven optimum
  feasible,          ///< a limit was hit; the best feasible solution is returned
  infeasible,        ///< no assignment satisfies the hard constraints
  no_solution,       ///< a limit was hit before any feasible solution was found
};

struct SelectionResult {
  SelectionStatus status = SelectionStatus::no_solution;
  std::vector<bool> selected;       ///< per face, valid for optimal / feasible
  double objective = 0.0;
  std::string solver;               ///< backend that produced the result
  double seconds = 0.0;
  std::size_t variables = 0, constraints = 0;
  std::size_t components = 0;       ///< independent sub-problems solved separately
  std::size_t window_components = 0;  ///< of them, solved by windows (too large to solve whole)
  std::string message;              ///< why, when not optimal
  /// A backend that broke on a component (CBC's process crashed) and what it said; GLPK then solved
  /// that component instead.
  std::vector<std::string> backend_failures;
};

/// Evaluates the objective of an assignment (for tests and for checking solver results).
double selection_energy(const SelectionProblem& problem, const std::vector<bool>& selected,
                        const SelectionParams& params);

/// True when the assignment satisfies every hard constraint (edges 0 or 2, single layer, priors).
bool satisfies_constraints(const SelectionProblem& problem, const std::vector<bool>& selected,
                           const SelectionParams& params);

/// Solves the program. Deterministic: the same problem and parameters give the same result, unless
/// the opt-in time limit fires. Thread-safe: CBC runs in a child process per call, so calls from
/// several threads solve at once, and a crash inside CBC costs only that call (backend_failures).
SelectionResult solve_selection(const SelectionProblem& problem, const SelectionParams& params);

/// CPU seconds (user + system) that the solver processes started from this thread have used so far:
/// the part of a building's CPU time that is not the thread's own.
double solver_process_cpu_seconds();

}  // namespace city3d
