// Face-selection solver benchmark: building-like programs of about 100 to 8,000 variables (fixed
// seeds), solved by GLPK and CBC side by side; prints one line per problem and the median seconds
// per size class. Used to set the "auto" threshold in src/selection/selection.cpp.
//
//   bench_selection [--time-limit S] [--seeds N] [--max-faces F]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "building_problems.hpp"
#include "city3d/selection.hpp"

namespace {

const char* status_name(city3d::SelectionStatus s) {
  switch (s) {
    case city3d::SelectionStatus::optimal:
      return "optimal";
    case city3d::SelectionStatus::feasible:
      return "feasible";
    case city3d::SelectionStatus::infeasible:
      return "infeasible";
    case city3d::SelectionStatus::no_solution:
      return "no_solution";
  }
  return "?";
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

}  // namespace

int main(int argc, char** argv) {
  double time_limit = 30.0;
  int seeds = 3;
  std::size_t max_faces = 20000;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--time-limit")
      time_limit = std::atof(argv[i + 1]);
    else if (flag == "--seeds")
      seeds = std::atoi(argv[i + 1]);
    else if (flag == "--max-faces")
      max_faces = static_cast<std::size_t>(std::atol(argv[i + 1]));
    else {
      std::fprintf(stderr, "bench_selection: unknown flag %s\n", flag.c_str());
      return 2;
    }
  }

  // Grid shapes chosen to span ~100 to ~8,000 variables after the exact reductions.
  const std::vector<city3d::bench::BuildingShape> shapes = {
      {3, 2, 2, 2, true},  {4, 3, 3, 2, true},  {6, 4, 3, 3, true},   {7, 5, 4, 3, true},  {8, 6, 4, 4, true},
      {10, 8, 4, 4, true}, {12, 9, 5, 5, true}, {16, 12, 5, 6, true}, {20, 16, 6, 8, true}};
  // Size classes by reduced variable count.
  const std::vector<std::size_t> class_upper = {300, 600, 900, 1300, 2000, 4000, 8000, 1000000};
  std::map<std::size_t, std::vector<double>> glpk_times, cbc_times;
  std::map<std::size_t, int> glpk_unsolved, cbc_unsolved;

  std::printf("%-14s %6s %6s %6s %5s | %9s %-11s | %9s %-11s | %s\n", "shape", "seed", "faces", "vars",
              "comps", "glpk s", "status", "cbc s", "status", "objective glpk / cbc");
  for (const auto& shape : shapes) {
    for (int seed = 1; seed <= seeds; ++seed) {
      const auto problem = city3d::bench::building_problem(shape, static_cast<std::uint32_t>(seed));
      if (problem.face_count > max_faces) continue;
      city3d::SelectionParams params;
      params.time_limit = time_limit;
      params.node_limit = 1000000;
      params.solver = "glpk";
      const auto glpk = city3d::solve_selection(problem, params);
      params.solver = "cbc";
      const auto cbc = city3d::solve_selection(problem, params);
      char name[32];
      std::snprintf(name, sizeof name, "%dx%dx%d/%d", shape.cells_x, shape.cells_y, shape.levels,
                    shape.blocks);
      std::printf(
          "%-14s %6d %6zu %6zu %5zu | %9.3f %-11s | %9.3f %-11s | %.9f / %.9f%s\n", name, seed,
          problem.face_count, cbc.variables, cbc.components, glpk.seconds, status_name(glpk.status),
          cbc.seconds, status_name(cbc.status), glpk.objective, cbc.objective,
          glpk.status == cbc.status && std::fabs(glpk.objective - cbc.objective) > 1e-9 ? "  DIFFER" : "");
      std::fflush(stdout);
      const std::size_t size_class = *std::lower_bound(class_upper.begin(), class_upper.end(), cbc.variables);
      glpk_times[size_class].push_back(glpk.seconds);
      cbc_times[size_class].push_back(cbc.seconds);
      glpk_unsolved[size_class] += glpk.status != city3d::SelectionStatus::optimal;
      cbc_unsolved[size_class] += cbc.status != city3d::SelectionStatus::optimal;
    }
  }
  std::printf("\nmedian seconds per size class (variables after reduction; time limit %.0f s)\n", time_limit);
  std::printf("%-12s %5s | %9s %10s | %9s %10s\n", "variables", "n", "glpk", "not opt.", "cbc", "not opt.");
  std::size_t lower = 0;
  for (std::size_t upper : class_upper) {
    if (glpk_times.count(upper)) {
      std::printf("%5zu-%-6zu %5zu | %9.3f %10d | %9.3f %10d\n", lower, upper, glpk_times[upper].size(),
                  median(glpk_times[upper]), glpk_unsolved[upper], median(cbc_times[upper]),
                  cbc_unsolved[upper]);
    }
    lower = upper;
  }
  return 0;
}
