// COIN-OR CBC backend of face selection: MipModel -> OsiClpSolverInterface -> CbcModel -> CbcMain1, in
// a child process per solve (solver_process.hpp).
#include <algorithm>
#include <cmath>
#include <coin/CbcModel.hpp>
#include <coin/CbcSolver.hpp>
#include <coin/CoinPackedMatrix.hpp>
#include <coin/CoinPackedVector.hpp>
#include <coin/OsiClpSolverInterface.hpp>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "selection/solver.hpp"
#include "selection/solver_process.hpp"

namespace city3d::detail {
namespace {

// The solve itself, as it runs in the child process.
MipSolution solve_here(const MipModel& model, const MipLimits& limits) {
  MipSolution solution;
  const int n = static_cast<int>(model.columns.size());
  OsiClpSolverInterface lp;
  const double inf = lp.getInfinity();
  std::vector<double> col_lower(n), col_upper(n), cost(n);
  for (int j = 0; j < n; ++j) {
    col_lower[j] = model.columns[j].lower;
    col_upper[j] = model.columns[j].upper;
    cost[j] = model.columns[j].cost;
  }
  CoinPackedMatrix matrix(false, 0, 0);  // row-ordered
  matrix.setDimensions(0, n);
  std::vector<double> row_lower, row_upper;
  row_lower.reserve(model.rows.size());
  row_upper.reserve(model.rows.size());
  for (const auto& r : model.rows) {
    matrix.appendRow(static_cast<int>(r.columns.size()), r.columns.data(), r.values.data());
    row_lower.push_back(std::isfinite(r.lower) ? r.lower : -inf);
    row_upper.push_back(std::isfinite(r.upper) ? r.upper : inf);
  }
  lp.loadProblem(matrix, col_lower.data(), col_upper.data(), cost.data(), row_lower.data(), row_upper.data());
  for (int j = 0; j < n; ++j)
    if (model.columns[j].integer) lp.setInteger(j);
  lp.messageHandler()->setLogLevel(0);

  // The MIP start goes by column name, the only form CbcMain1 maps through its preprocessing.
  std::vector<std::string> names;
  if (model.start.size() == static_cast<std::size_t>(n)) {
    lp.setIntParam(OsiNameDiscipline, 1);
    names.reserve(n);
    for (int j = 0; j < n; ++j) {
      names.push_back("v" + std::to_string(j));
      lp.setColName(j, names.back());
    }
  }

  CbcModel cbc(lp);
  cbc.setLogLevel(0);
  cbc.messageHandler()->setLogLevel(0);
  CbcMain0(cbc);
  // Single-threaded with fixed seeds: the same model gives the same search and the same optimum.
  // -maxNodes is the deterministic work limit. No -sec: a wall-clock limit is the parent's to apply
  // (it kills this process), so CBC never decides anything by the clock.
  // Probing and two-step MIR cuts off (measured 2026-11-24 on the 22 programs of the Delft block
  // that go to CBC, CbcMain1 from the same starts, CPU time): the same optima in 2.4 s instead of
  // 3.4 s; and every program seen to hit Clp's assertion `lowerValue <= upperValue'
  // (ClpNonLinearCost.cpp:1064; the Delft footprint of issue 14 and four windows of AHN3/07163)
  // solves without it once probing is off.
  const std::string nodes = std::to_string(limits.node_limit);
  const std::vector<std::string> arguments = {"city3d",                //
                                              "-log",           "0",   //
                                              "-threads",       "0",   //
                                              "-randomSeed",    "1",   //
                                              "-randomCbcSeed", "1",   //
                                              "-probing",       "off", //
                                              "-twoMir",        "off", //
                                              "-maxNodes",      nodes, //
                                              "-solve",         "-quit"};
  if (!names.empty()) {
    std::vector<const char*> start_names;
    for (const auto& name : names) start_names.push_back(name.c_str());
    cbc.setMIPStart(n, start_names.data(), model.start.data());
  }
  std::vector<const char*> argv;
  for (const auto& a : arguments) argv.push_back(a.c_str());
  CbcMain1(static_cast<int>(argv.size()), argv.data(), cbc);

  const double* best = cbc.bestSolution();
  const auto take_values = [&] {
    const int m = cbc.getNumCols();  // CbcMain1 maps the solution back to the original columns
    solution.values.assign(best, best + std::min(m, n));
    solution.values.resize(n, 0.0);
    solution.objective = cbc.getObjValue();
  };
  if (cbc.isProvenOptimal() && best != nullptr) {
    solution.status = MipStatus::optimal;
    take_values();
  } else if (cbc.isProvenInfeasible()) {
    solution.status = MipStatus::infeasible;
    solution.message = "cbc: proven infeasible";
  } else {
    // status 1 = stopped on a limit; secondary status 3 = nodes (CbcModel.hpp).
    const int secondary = cbc.secondaryStatus();
    const std::string why = secondary == 3 ? "node limit " + nodes + " reached"
                                           : "stopped (status " + std::to_string(cbc.status()) + "/" +
                                                 std::to_string(secondary) + ")";
    stopped_by_limit(solution, "cbc", why, best != nullptr);
    if (best != nullptr) take_values();
  }
  return solution;
}

// The result crosses the pipe as: status, objective, message length, message, value count, values.
std::string encode(const MipSolution& solution) {
  std::string out;
  const auto put = [&out](const void* data, std::size_t size) { out.append(static_cast<const char*>(data), size); };
  const std::int32_t status = static_cast<std::int32_t>(solution.status);
  const std::uint64_t message_size = solution.message.size(), value_count = solution.values.size();
  put(&status, sizeof status);
  put(&solution.objective, sizeof solution.objective);
  put(&message_size, sizeof message_size);
  put(solution.message.data(), solution.message.size());
  put(&value_count, sizeof value_count);
  put(solution.values.data(), value_count * sizeof(double));
  return out;
}

bool decode(const std::string& in, std::size_t columns, MipSolution& solution) {
  std::size_t at = 0;
  const auto take = [&](void* data, std::size_t size) {
    if (in.size() - at < size) return false;
    if (size > 0) std::memcpy(data, in.data() + at, size);  // an empty vector's data() may be null
    at += size;
    return true;
  };
  std::int32_t status = 0;
  std::uint64_t message_size = 0, value_count = 0;
  if (!take(&status, sizeof status) || status < 0 || status > static_cast<std::int32_t>(MipStatus::no_solution) ||
      !take(&solution.objective, sizeof solution.objective) || !take(&message_size, sizeof message_size) ||
      message_size > in.size() - at)
    return false;
  solution.status = static_cast<MipStatus>(status);
  solution.message.assign(in, at, message_size);
  at += message_size;
  if (!take(&value_count, sizeof value_count) || (value_count != 0 && value_count != columns)) return false;
  solution.values.resize(value_count);
  return take(solution.values.data(), value_count * sizeof(double)) && at == in.size();
}

}  // namespace

MipSolution solve_with_cbc(const MipModel& model, const MipLimits& limits) {
  if (model.columns.empty()) {
    MipSolution solution;
    solution.status = MipStatus::optimal;
    return solution;
  }
  const ChildResult child = run_in_child([&] { return encode(solve_here(model, limits)); }, limits.time_limit);
  MipSolution solution;
  if (child.completed && decode(child.output, model.columns.size(), solution)) return solution;
  solution = MipSolution{};
  if (child.timed_out) {
    solution.status = MipStatus::no_solution;
    solution.message = "cbc: wall-clock limit reached (the solver process was stopped)";
    return solution;
  }
  solution.status = MipStatus::failed;
  solution.message = "cbc: the solver process " + (child.completed ? std::string("sent a result that cannot be read") : child.failure);
  if (!child.stderr_tail.empty()) {
    // The last line is the one that says what happened (an assertion, say).
    const std::size_t cut = child.stderr_tail.find_last_of('\n');
    solution.message += ": " + child.stderr_tail.substr(cut == std::string::npos ? 0 : cut + 1);
  }
  return solution;
}

}  // namespace city3d::detail
