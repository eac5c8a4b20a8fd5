// Large programs by windows (windows.hpp): windows grown through shared rows, sub-programs with the
// rest fixed at the incumbent and their rows of one free column taken as bounds, accepted when they
// lower the objective.
#include "selection/windows.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <optional>
#include <vector>

namespace city3d::detail {
namespace {

// A window's answer must lower the objective by more than this to replace the incumbent (rounding).
constexpr double kImprovement = 1e-12;

// Rows within this of their bounds count as satisfied when the incumbent is checked.
constexpr double kRowTolerance = 1e-9;

// Whether two programs are the same, exactly: columns, rows and start.
bool same_program(const MipModel& a, const MipModel& b) {
  const auto same_column = [](const MipModel::Column& c, const MipModel::Column& d) {
    return c.cost == d.cost && c.lower == d.lower && c.upper == d.upper && c.integer == d.integer;
  };
  const auto same_row = [](const MipModel::Row& r, const MipModel::Row& q) {
    return r.columns == q.columns && r.values == q.values && r.lower == q.lower && r.upper == q.upper;
  };
  return a.start == b.start &&
         std::equal(a.columns.begin(), a.columns.end(), b.columns.begin(), b.columns.end(), same_column) &&
         std::equal(a.rows.begin(), a.rows.end(), b.rows.begin(), b.rows.end(), same_row);
}

// A window that improved nothing: its columns and its sub-program as they were.
struct Unimproved {
  std::vector<std::size_t> window;
  MipModel sub;
};

}  // namespace

bool reduce_window(const MipModel& sub, ReducedWindow& out) {
  const std::size_t n = sub.columns.size();
  std::vector<double> lower(n), upper(n);
  for (std::size_t c = 0; c < n; ++c) {
    lower[c] = sub.columns[c].lower;
    upper[c] = sub.columns[c].upper;
  }
  std::vector<std::vector<std::size_t>> rows_of(n);
  for (std::size_t r = 0; r < sub.rows.size(); ++r)
    for (int c : sub.rows[r].columns) rows_of[static_cast<std::size_t>(c)].push_back(r);
  std::vector<bool> row_gone(sub.rows.size(), false);
  const auto settled = [&](std::size_t c) { return lower[c] == upper[c]; };
  std::vector<std::size_t> queue(sub.rows.size());
  for (std::size_t r = 0; r < queue.size(); ++r) queue[r] = r;
  while (!queue.empty()) {
    const std::size_t r = queue.back();
    queue.pop_back();
    if (row_gone[r]) continue;
    const MipModel::Row& row = sub.rows[r];
    double fixed = 0.0, coef = 0.0;
    std::size_t free_count = 0, column = 0;
    for (std::size_t k = 0; k < row.columns.size(); ++k) {
      const auto c = static_cast<std::size_t>(row.columns[k]);
      if (settled(c)) {
        fixed += row.values[k] * lower[c];
      } else {
        ++free_count;
        column = c;
        coef = row.values[k];
      }
    }
    if (free_count > 1) continue;
    row_gone[r] = true;
    if (free_count == 0) continue;  // the start satisfies it
    // lower - fixed <= coef x <= upper - fixed
    double from = (coef > 0.0 ? row.lower : row.upper) - fixed;
    double to = (coef > 0.0 ? row.upper : row.lower) - fixed;
    from /= coef;
    to /= coef;
    if (sub.columns[column].integer) {
      from = std::ceil(from - kRowTolerance);
      to = std::floor(to + kRowTolerance);
    }
    lower[column] = std::max(lower[column], from);
    upper[column] = std::min(upper[column], to);
    if (lower[column] > upper[column] + kRowTolerance) return false;
    if (lower[column] > upper[column]) lower[column] = upper[column] = 0.5 * (lower[column] + upper[column]);
    if (settled(column))
      for (std::size_t other : rows_of[column])
        if (!row_gone[other]) queue.push_back(other);
  }

  out.program = MipModel{};
  out.free_index.assign(n, -1);
  out.settled.assign(n, 0.0);
  for (std::size_t c = 0; c < n; ++c) {
    if (settled(c)) {
      out.settled[c] = lower[c];
      continue;
    }
    out.free_index[c] = static_cast<int>(out.program.columns.size());
    MipModel::Column column = sub.columns[c];
    column.lower = lower[c];
    column.upper = upper[c];
    out.program.columns.push_back(column);
    out.program.start.push_back(sub.start[c]);
  }
  for (std::size_t r = 0; r < sub.rows.size(); ++r) {
    if (row_gone[r]) continue;
    const MipModel::Row& row = sub.rows[r];
    MipModel::Row part;
    double fixed = 0.0;
    for (std::size_t k = 0; k < row.columns.size(); ++k) {
      const auto c = static_cast<std::size_t>(row.columns[k]);
      if (out.free_index[c] < 0) {
        fixed += row.values[k] * out.settled[c];
      } else {
        part.columns.push_back(out.free_index[c]);
        part.values.push_back(row.values[k]);
      }
    }
    part.lower = row.lower - fixed;
    part.upper = row.upper - fixed;
    out.program.rows.push_back(std::move(part));
  }
  return true;
}

MipSolution solve_by_windows(const MipModel& model, std::size_t window_variables, std::size_t max_rounds,
                             const std::function<MipSolution(const MipModel&)>& solve, WindowSearch& search) {
  const std::size_t n = model.columns.size();
  MipSolution result;
  result.status = MipStatus::feasible;
  result.values = model.start;
  std::vector<double>& x = result.values;
  // Integer columns exactly integral: a value of 0.9999999 from a backend would leave the fixed
  // share of a row a hair off its integer bound, and Clp asserts on bounds that cross by a hair.
  const auto settle = [&model](std::size_t c, double v) { return model.columns[c].integer ? std::round(v) : v; };
  for (std::size_t c = 0; c < n; ++c) x[c] = settle(c, x[c]);
  std::vector<std::vector<std::size_t>> rows_of(n);
  for (std::size_t r = 0; r < model.rows.size(); ++r)
    for (int c : model.rows[r].columns) rows_of[static_cast<std::size_t>(c)].push_back(r);

  std::vector<int> local(n, -1);
  std::vector<std::size_t> window;
  // The rounds of one parity make the same windows, in the same order (they depend on the model
  // alone). A window that improved nothing, and whose sub-program is the same again (no column it
  // holds or shares a row with has changed since), would get the same answer: it is not solved again.
  std::vector<std::optional<Unimproved>> unimproved[2];
  for (search.rounds = 0; search.rounds < max_rounds; ++search.rounds) {
    bool improved = false;
    std::vector<bool> held(n, false);  // by a window of this round
    // Odd rounds seed from the last column backwards, so their windows cut the building elsewhere.
    const bool backwards = search.rounds % 2 == 1;
    std::vector<std::optional<Unimproved>>& before = unimproved[search.rounds % 2];
    std::size_t ordinal = 0;  // of the window in this round
    for (std::size_t step = 0; step < n; ++step) {
      const std::size_t seed = backwards ? n - 1 - step : step;
      if (held[seed]) continue;
      // The window: breadth-first from the seed through shared rows, through columns no window of
      // this round has held first, so the round's windows overlap little.
      window.clear();
      std::deque<std::size_t> fresh{seed}, seen;
      local[seed] = 0;
      while ((!fresh.empty() || !seen.empty()) && window.size() < window_variables) {
        std::deque<std::size_t>& from = fresh.empty() ? seen : fresh;
        const std::size_t c = from.front();
        from.pop_front();
        window.push_back(c);
        for (std::size_t r : rows_of[c])
          for (int d : model.rows[r].columns)
            if (local[static_cast<std::size_t>(d)] < 0) {
              local[static_cast<std::size_t>(d)] = 0;
              (held[static_cast<std::size_t>(d)] ? seen : fresh).push_back(static_cast<std::size_t>(d));
            }
      }
      for (std::size_t c : fresh) local[c] = -1;
      for (std::size_t c : seen) local[c] = -1;
      std::sort(window.begin(), window.end());
      for (std::size_t k = 0; k < window.size(); ++k) {
        local[window[k]] = static_cast<int>(k);
        held[window[k]] = true;
      }

      // Its sub-program: the window's columns; every row that holds one, with the fixed columns'
      // share moved into its bounds.
      MipModel sub;
      double incumbent = 0.0;
      for (std::size_t c : window) {
        sub.columns.push_back(model.columns[c]);
        sub.start.push_back(x[c]);
        incumbent += model.columns[c].cost * x[c];
      }
      std::vector<bool> row_taken(model.rows.size(), false);
      for (std::size_t c : window)
        for (std::size_t r : rows_of[c]) {
          if (row_taken[r]) continue;
          row_taken[r] = true;
          const MipModel::Row& row = model.rows[r];
          MipModel::Row part;
          double fixed = 0.0;
          for (std::size_t k = 0; k < row.columns.size(); ++k) {
            const int l = local[static_cast<std::size_t>(row.columns[k])];
            if (l >= 0) {
              part.columns.push_back(l);
              part.values.push_back(row.values[k]);
            } else {
              fixed += row.values[k] * x[static_cast<std::size_t>(row.columns[k])];
            }
          }
          part.lower = row.lower - fixed;
          part.upper = row.upper - fixed;
          sub.rows.push_back(std::move(part));
        }
      for (std::size_t c : window) local[c] = -1;
      if (before.size() <= ordinal) before.resize(ordinal + 1);
      std::optional<Unimproved>& last = before[ordinal++];
      if (last && last->window == window && same_program(last->sub, sub)) {
        ++search.windows;
        ++search.repeated;
        continue;
      }
      last.reset();

      MipSolution answer;
      ReducedWindow reduced;
      if (!reduce_window(sub, reduced)) {
        answer = solve(sub);
      } else if (reduced.program.columns.empty()) {
        answer.status = MipStatus::optimal;  // every column settled by its rows: the start
        answer.values = sub.start;
      } else {
        answer = solve(reduced.program);
        if ((answer.status == MipStatus::optimal || answer.status == MipStatus::feasible) &&
            answer.values.size() == reduced.program.columns.size()) {
          std::vector<double> values(window.size());
          for (std::size_t k = 0; k < window.size(); ++k)
            values[k] = reduced.free_index[k] < 0
                            ? reduced.settled[k]
                            : answer.values[static_cast<std::size_t>(reduced.free_index[k])];
          answer.values = std::move(values);
        }
      }
      ++search.windows;
      if ((answer.status == MipStatus::optimal || answer.status == MipStatus::feasible) &&
          answer.values.size() == window.size()) {
        double objective = 0.0;
        for (std::size_t k = 0; k < window.size(); ++k) objective += sub.columns[k].cost * answer.values[k];
        if (objective < incumbent - kImprovement) {
          for (std::size_t k = 0; k < window.size(); ++k) x[window[k]] = settle(window[k], answer.values[k]);
          improved = true;
          ++search.improved;
        } else {
          last = Unimproved{window, std::move(sub)};
        }
      }
    }
    if (!improved) {
      ++search.rounds;
      break;
    }
  }

  result.objective = 0.0;
  for (std::size_t c = 0; c < n; ++c) result.objective += model.columns[c].cost * x[c];
  // Every accepted window kept its rows; check it once more over the whole program.
  for (const MipModel::Row& row : model.rows) {
    double sum = 0.0;
    for (std::size_t k = 0; k < row.columns.size(); ++k) sum += row.values[k] * x[static_cast<std::size_t>(row.columns[k])];
    if (sum < row.lower - kRowTolerance || sum > row.upper + kRowTolerance) {
      result.status = MipStatus::no_solution;
      result.values.clear();
      result.message = "windows: the combined answer breaks a row";
      return result;
    }
  }
  result.message = "solved by " + std::to_string(search.windows) + " windows of up to " +
                   std::to_string(window_variables) + " variables in " + std::to_string(search.rounds) +
                   " rounds (" + std::to_string(search.improved) + " improved the start); not proven optimal";
  return result;
}

}  // namespace city3d::detail
