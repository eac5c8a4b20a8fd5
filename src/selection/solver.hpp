// The small interface between face selection and its mixed-integer backends (GLPK, COIN-OR CBC):
// a plain row-wise model in, a status and a value per column out. No solver header leaks from here.
#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

namespace city3d::detail {

/// A mixed-integer linear program: minimise cost . v subject to row_lower <= A v <= row_upper and
/// column bounds. Infinite bounds are +/- std::numeric_limits<double>::infinity().
struct MipModel {
  struct Column {
    double cost = 0.0;
    double lower = 0.0;
    double upper = 1.0;
    bool integer = true;
  };
  struct Row {
    std::vector<int> columns;    ///< column indices, each at most once
    std::vector<double> values;  ///< same length as columns
    double lower = -std::numeric_limits<double>::infinity();
    double upper = std::numeric_limits<double>::infinity();
  };
  std::vector<Column> columns;
  std::vector<Row> rows;
  /// A feasible value per column to start the search from, or empty. Backends may ignore it.
  std::vector<double> start;
};

/// Limits of one solve. The node limit is the deterministic one; the wall-clock limit is a safety net
/// that makes the result depend on the machine when it fires.
struct MipLimits {
  double time_limit = std::numeric_limits<double>::infinity();  ///< wall clock, seconds (> 0; infinity: none)
  long node_limit = 100000;  ///< branch-and-bound nodes (>= 1); deterministic
  /// GLPK: its LP presolver before the relaxation. A window's sub-program (windows.hpp) carries
  /// what fixing the rest of the program left behind, which the presolver takes out; on the whole
  /// programs it costs more than it saves (docs/BENCHMARKS.md, "CPU: issue 27, fifth step").
  bool presolve_relaxation = false;
  /// GLPK: Gomory's cuts in the search on programs of more columns than this (SelectionParams).
  std::size_t gomory_min_columns = 1500;
};

/// failed: the backend itself broke (CBC's process crashed or was killed); the message says how.
enum class MipStatus { optimal, feasible, infeasible, no_solution, failed };

struct MipSolution {
  MipStatus status = MipStatus::no_solution;
  std::vector<double> values;  ///< per column, when optimal or feasible
  double objective = 0.0;      ///< cost . values as the backend reports it
  std::string message;         ///< which limit was hit, or the backend's status code
};

/// A backend: solves `model` within `limits`. Throws ReconstructionError when the backend fails in a
/// way that is not a status (e.g. an internal error code).
using MipBackend = MipSolution (*)(const MipModel& model, const MipLimits& limits);

/// GLPK 5.0 branch-and-cut (glp_intopt with its presolver). Thread-safe (GLPK keeps its environment
/// per thread). The node limit is emulated with a callback (GLPK has none).
MipSolution solve_with_glpk(const MipModel& model, const MipLimits& limits);

/// COIN-OR CBC 2.10 through CbcMain1 (preprocessing, cuts, heuristics), from model.start when given
/// (CBC's MIP start: its incumbent before the search, so every bound prunes from the first node). Each
/// call runs in a child process of its own (solver_process.hpp): CbcMain1 in 2.10.8 is not thread-safe,
/// and an assertion inside Clp aborts the process it runs in. A crash or the wall-clock limit gives
/// A backend stopped by a limit (`why`): feasible with its best solution when it has one, else
/// no_solution; the message says which ("cbc: node limit 200000 reached; best feasible solution
/// returned").
inline void stopped_by_limit(MipSolution& solution, const std::string& backend, const std::string& why, bool has_best) {
  solution.status = has_best ? MipStatus::feasible : MipStatus::no_solution;
  solution.message = backend + ": " + why + (has_best ? "; best feasible solution returned" : " before any feasible solution");
}

/// MipStatus::failed or no_solution with the reason; the calling process goes on.
MipSolution solve_with_cbc(const MipModel& model, const MipLimits& limits);

}  // namespace city3d::detail
