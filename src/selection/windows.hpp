// Large programs by windows: a large-neighbourhood search from a feasible start. Private to
// src/selection; solve_selection() uses it for components too large to solve whole within the work
// limits.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

#include "selection/solver.hpp"

namespace city3d::detail {

/// How a window search went.
struct WindowSearch {
  std::size_t windows = 0;   ///< sub-programs solved
  std::size_t improved = 0;  ///< of them, how many lowered the objective
  std::size_t rounds = 0;    ///< passes over the whole program
};

/// Solves `model` (which must carry a feasible start) by windows: a window is about
/// `window_variables` columns grown breadth-first through shared rows from a seed column (the
/// first column no window of this round has held yet, in index order, or backwards in odd rounds),
/// through columns no window of the round has held before others, so it is a connected piece of
/// the building; every column outside it keeps its incumbent value, the window's sub-program
/// (rows with a window column, their bounds moved by the fixed columns) goes to `solve`, and its
/// answer replaces the incumbent's window columns when it lowers the objective. Rounds repeat until
/// one improves nothing, at most `max_rounds`. Every step keeps every row satisfied, so the result
/// is feasible; it is not proven optimal. Deterministic: windows, order and sub-programs depend on
/// the model alone. `solve` returning failed, infeasible or no_solution leaves the incumbent as it is.
MipSolution solve_by_windows(const MipModel& model, std::size_t window_variables, std::size_t max_rounds,
                             const std::function<MipSolution(const MipModel&)>& solve, WindowSearch& search);

}  // namespace city3d::detail
