// Large programs by windows: a large-neighbourhood search from a feasible start. Private to
// src/selection; solve_selection() uses it for components too large to solve whole within the work
// limits.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "selection/solver.hpp"

namespace city3d::detail {

/// How a window search went.
struct WindowSearch {
  std::size_t windows = 0;   ///< sub-programs solved, or known unchanged (below)
  std::size_t improved = 0;  ///< of them, how many lowered the objective
  std::size_t rounds = 0;    ///< passes over the whole program
  /// Of the windows, how many had the sub-program they had in an earlier round, which improved
  /// nothing then: not solved again, since the answer would be the same.
  std::size_t repeated = 0;
};

/// A window's sub-program with its settled columns taken out. Fixing the rest of the program turns
/// many rows into rows of one window column (an overlap pair whose partner is on, an edge whose other
/// faces are outside the window): 43% of the rows and 17% of the columns of the windows of
/// city3d_dev_large's AHN3/06790. Such a row is only a bound on its column; a column whose bounds
/// meet is settled, and its share moves into the bounds of its other rows, which may leave them with
/// one column in turn. The reduced program has the same feasible set over the free columns (the
/// settled ones at their values), so the same optima, with 43% fewer rows for the simplex there.
struct ReducedWindow {
  MipModel program;             ///< the free columns only, their bounds tightened, start carried over
  std::vector<int> free_index;  ///< per column of the sub-program: its column in `program`, or -1
  std::vector<double> settled;  ///< per column of the sub-program: its value where settled
};

/// Reduces `sub` by its rows of at most one free column (bounds rounded inward for integer columns).
/// Returns false when two bounds cross by more than rounding (a start that satisfies `sub` rules
/// that out); `out` is then unusable and `sub` is to be solved as it is.
bool reduce_window(const MipModel& sub, ReducedWindow& out);

/// Solves `model` (which must carry a feasible start) by windows: a window is about
/// `window_variables` columns grown breadth-first through shared rows from a seed column (the
/// first column no window of this round has held yet, in index order, or backwards in odd rounds),
/// through columns no window of the round has held before others, so it is a connected piece of
/// the building; every column outside it keeps its incumbent value, the window's sub-program
/// (rows with a window column, their bounds moved by the fixed columns) goes to `solve`, and its
/// answer replaces the incumbent's window columns when it lowers the objective. Rounds repeat until
/// one improves nothing, at most `max_rounds`. Every step keeps every row satisfied, so the result
/// is feasible; it is not proven optimal. Deterministic: windows, order and sub-programs depend on
/// the model alone. Each sub-program is reduced by reduce_window() before `solve` sees it; a window
/// whose sub-program is the one it had in an earlier round, which improved nothing then, does not go
/// to `solve` again (its answer would be the same: `solve` must be deterministic). `solve` returning
/// failed, infeasible or no_solution leaves the incumbent as it is.
MipSolution solve_by_windows(const MipModel& model, std::size_t window_variables, std::size_t max_rounds,
                             const std::function<MipSolution(const MipModel&)>& solve, WindowSearch& search);

}  // namespace city3d::detail
