// COIN-OR CBC backend of face selection: MipModel -> OsiClpSolverInterface -> CbcModel -> CbcMain1.
#include <algorithm>
#include <cmath>
#include <coin/CbcModel.hpp>
#include <coin/CbcSolver.hpp>
#include <coin/CoinPackedMatrix.hpp>
#include <coin/CoinPackedVector.hpp>
#include <coin/OsiClpSolverInterface.hpp>
#include <cstdio>
#include <mutex>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "selection/solver.hpp"

namespace city3d::detail {
namespace {

// CbcMain1 in CBC 2.10.8 keeps its parameter table in static storage: two concurrent calls corrupted
// each other's parsing (DEPENDENCIES.md). Everything CBC does here runs under this lock.
std::mutex cbc_mutex;

// std::to_string gives "10.000000"; CBC's parser accepts that, but a short form reads better in logs.
std::string number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3f", value);
  return buffer;
}

}  // namespace

MipSolution solve_with_cbc(const MipModel& model, const MipLimits& limits) {
  MipSolution solution;
  const int n = static_cast<int>(model.columns.size());
  if (n == 0) {
    solution.status = MipStatus::optimal;
    return solution;
  }

  std::lock_guard<std::mutex> lock(cbc_mutex);

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
  // -maxNodes is the deterministic work limit, -sec the wall-clock safety limit (CBC counts CPU time
  // unless -timeMode elapsed, which on a loaded machine lets a solve run far past the limit).
  const std::string seconds = number(limits.time_limit);
  const std::string nodes = std::to_string(limits.node_limit);
  const std::vector<std::string> arguments = {"city3d",                     //
                                              "-log",           "0",        //
                                              "-threads",       "0",        //
                                              "-randomSeed",    "1",        //
                                              "-randomCbcSeed", "1",        //
                                              "-timeMode",      "elapsed",  //
                                              "-sec",           seconds,    //
                                              "-maxNodes",      nodes,      //
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
    // status 1 = stopped on a limit; secondary status 3 = nodes, 4 = time (CbcModel.hpp).
    const int secondary = cbc.secondaryStatus();
    const std::string why = secondary == 3   ? "node limit " + nodes + " reached"
                            : secondary == 4 ? "time limit " + seconds + " s reached"
                                             : "stopped (status " + std::to_string(cbc.status()) + "/" +
                                                   std::to_string(secondary) + ")";
    if (best != nullptr) {
      solution.status = MipStatus::feasible;
      take_values();
      solution.message = "cbc: " + why + "; best feasible solution returned";
    } else {
      solution.status = MipStatus::no_solution;
      solution.message = "cbc: " + why + " before any feasible solution";
    }
  }
  return solution;
}

}  // namespace city3d::detail
