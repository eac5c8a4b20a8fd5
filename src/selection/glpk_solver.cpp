// GLPK backend of face selection: MipModel -> glp_prob -> glp_intopt, with a node-count limit.
#include <glpk.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <csetjmp>
#include <string>
#include <vector>

#include "selection/solver.hpp"

namespace city3d::detail {
namespace {

// An integer column's relaxation value within this of an integer counts as integral (GLPK's own
// tolerance, tol_int, is 1e-5).
constexpr double kIntegral = 1e-9;

struct NodeBudget {
  long limit = 0;
  bool hit = false;
};

// GLPK has no node limit. t_cnt from glp_ios_tree_size counts every subproblem created so far
// (active and already fathomed), which is the same node count CBC's -maxNodes bounds up to a
// constant; it depends only on the search, so the limit is deterministic unlike tm_lim.
void count_nodes(glp_tree* tree, void* info) {
  auto* budget = static_cast<NodeBudget*>(info);
  if (glp_ios_reason(tree) != GLP_ISELECT) return;
  int active = 0, alive = 0, total = 0;
  glp_ios_tree_size(tree, &active, &alive, &total);
  if (total > budget->limit) {
    budget->hit = true;
    glp_ios_terminate(tree);
  }
}

int row_type(const MipModel::Row& row) {
  const bool has_lower = std::isfinite(row.lower), has_upper = std::isfinite(row.upper);
  if (has_lower && has_upper) return row.lower == row.upper ? GLP_FX : GLP_DB;
  if (has_lower) return GLP_LO;
  if (has_upper) return GLP_UP;
  return GLP_FR;
}

// Everything one glp_intopt run reads and writes, trivially destructible: the run may be left by
// longjmp (see solve_with_glpk), which must not skip a destructor.
struct GlpkRun {
  const MipModel* model = nullptr;
  const std::vector<int>* ia = nullptr;
  const std::vector<int>* ja = nullptr;
  const std::vector<double>* ar = nullptr;
  int tm_lim = INT_MAX;
  bool presolve_relaxation = false;
  std::size_t gomory_min_columns = 0;
  NodeBudget budget;
  int ret = 0, mip_status = 0;
  double objective = 0.0;
  double* values = nullptr;  // n values, written when the run has a solution
};

// The solved relaxation of `p` as the program's optimum, when every integer column's value is
// integral (within kIntegral; rounded): returns whether it was taken.
bool take_integral_relaxation(glp_prob* p, const MipModel& model, GlpkRun& run) {
  const int n = static_cast<int>(model.columns.size());
  for (int j = 0; j < n; ++j) {
    const double v = glp_get_col_prim(p, j + 1);
    if (model.columns[j].integer && std::abs(v - std::round(v)) > kIntegral) return false;
  }
  for (int j = 0; j < n; ++j) {
    const double v = glp_get_col_prim(p, j + 1);
    run.values[j] = model.columns[j].integer ? std::round(v) : v;
  }
  run.objective = glp_get_obj_val(p);
  run.ret = 0;
  run.mip_status = GLP_OPT;
  return true;
}

// The GLPK part of a solve: problem, parameters, glp_intopt, the answer copied out, problem deleted.
void run_glpk(GlpkRun& run) {
  const MipModel& model = *run.model;
  const int n = static_cast<int>(model.columns.size());
  glp_prob* p = glp_create_prob();
  glp_set_obj_dir(p, GLP_MIN);
  glp_add_cols(p, n);
  for (int j = 0; j < n; ++j) {
    const auto& c = model.columns[j];
    glp_set_col_kind(p, j + 1, c.integer ? GLP_IV : GLP_CV);
    glp_set_col_bnds(p, j + 1, c.lower == c.upper ? GLP_FX : GLP_DB, c.lower, c.upper);
    glp_set_obj_coef(p, j + 1, c.cost);
  }
  if (!model.rows.empty()) glp_add_rows(p, static_cast<int>(model.rows.size()));
  for (std::size_t i = 0; i < model.rows.size(); ++i) {
    const auto& r = model.rows[i];
    glp_set_row_bnds(p, static_cast<int>(i) + 1, row_type(r), std::isfinite(r.lower) ? r.lower : 0.0,
                     std::isfinite(r.upper) ? r.upper : 0.0);
  }
  glp_load_matrix(p, static_cast<int>(run.ia->size()) - 1, run.ia->data(), run.ja->data(), run.ar->data());

  // msg_lev does not silence everything: the clique-cut code prints "Constructing conflict graph..."
  // through GLPK's terminal hook. glp_term_out acts on this thread's GLPK environment only.
  const int previous_term_out = glp_term_out(GLP_OFF);

  // The LP relaxation first, by the dual simplex from an advanced basis, and the branch-and-cut from
  // its optimal basis without GLPK's MIP presolver: on the selection programs this is 2-5x faster
  // than glp_intopt's own presolve and primal simplex, with the same optima (the 67 programs of 150
  // variables or more of the Delft block: 0.38 s against 0.93 s in all). The Delft block's outputs
  // are byte-identical; of the 1,420 dev and instance clouds three differ, by one or two faces, no worse
  // either way, each a large program solved by windows (docs/BENCHMARKS.md, "CPU: issue 27, second
  // step"): a window with several optima of (nearly) equal energy may be left at another one. Where
  // the relaxation is not solved to optimality (infeasible, a limit), glp_intopt's presolver takes
  // the program as before and tells infeasibility apart.
  // A window's sub-program (windows.hpp) goes through GLPK's LP presolver instead of the advanced
  // basis: what fixing the rest of the program leaves (rows of two columns, dominated rows) it takes
  // out, and the window programs of city3d_dev_large's AHN3/06790 need 30% less CPU for the
  // relaxation and the search; the whole programs of the Delft block need 10-30% more
  // (docs/BENCHMARKS.md, "CPU: issue 27, fifth step").
  glp_smcp lp;
  glp_init_smcp(&lp);
  lp.msg_lev = GLP_MSG_OFF;
  lp.meth = GLP_DUAL;
  lp.tm_lim = run.tm_lim;
  lp.presolve = run.presolve_relaxation ? GLP_ON : GLP_OFF;
  if (!run.presolve_relaxation) glp_adv_basis(p, 0);
  const bool relaxation_solved = glp_simplex(p, &lp) == 0 && glp_get_status(p) == GLP_OPT;

  // A relaxation whose optimum is integral on every integer column is the program's optimum: the
  // search would take it at its root node as it is (GLPK rounds the integer columns of the solution it
  // records). Skipping glp_intopt's set-up (its tree, the cut generators' tables) saves about 1 ms
  // per such window program; 189 of the Delft block's 238 programs and 252 of AHN3/06790's 423 window
  // programs are such (docs/BENCHMARKS.md, "CPU: issue 27, fifth step").
  if (!(relaxation_solved && take_integral_relaxation(p, model, run))) {
    glp_iocp parm;
    glp_init_iocp(&parm);
    parm.msg_lev = GLP_MSG_OFF;
    parm.presolve = relaxation_solved ? GLP_OFF : GLP_ON;
    // Gomory + MIR cuts, nothing else (bench_selection, 2 seeds per size): without cuts GLPK needs
    // 2-4 s at ~700 variables and fails at ~2,000; Gomory alone fails at ~3,300; adding clique cuts
    // makes it 10-100x slower (building the conflict graph); cover cuts change nothing or slow it.
    // With Gomory + MIR it solves ~2,000 variables in 0.1-0.2 s and ~5,500 in 1.5-2.2 s.
    // On the hypotheses' own programs that reach the search, the Gomory cuts pay only on large ones:
    // up to gomory_min_columns columns (1,500) MIR alone takes 7-36% less time per size class, with the same
    // solutions (the Delft block, city3d_dev and city3d_dev_large byte-identical); above it,
    // Gomory cuts save up to 7x (city3d_dev's programs of 3,239 columns: 0.18 s each against 0.53 and 1.23
    // s). docs/BENCHMARKS.md, "CPU: issue 27, fourteenth step".
    parm.gmi_cuts = static_cast<std::size_t>(n) > run.gomory_min_columns ? GLP_ON : GLP_OFF;
    parm.mir_cuts = GLP_ON;
    parm.tm_lim = run.tm_lim;
    parm.cb_func = count_nodes;
    parm.cb_info = &run.budget;
    run.ret = glp_intopt(p, &parm);
    run.mip_status = glp_mip_status(p);
    if (run.mip_status == GLP_OPT || run.mip_status == GLP_FEAS) {
      for (int j = 0; j < n; ++j) run.values[j] = glp_mip_col_val(p, j + 1);
      run.objective = glp_mip_obj_val(p);
    }
  }
  glp_term_out(previous_term_out);
  glp_delete_prob(p);
}

// GLPK reports an internal error (a failed assertion, a bad argument) through glp_error, which
// aborts the process unless the error hook leaves by longjmp: solve_with_glpk then frees the
// thread's GLPK environment (glp_free_env, as GLPK's manual prescribes) and reports the program
// as failed, so the other backend gets it and the run goes on.
thread_local std::jmp_buf* glpk_error_exit = nullptr;

void on_glpk_error(void*) {
  if (glpk_error_exit != nullptr) std::longjmp(*glpk_error_exit, 1);
}

// GLPK keeps an environment per thread (its memory pools and hooks, about 5 KB) from the thread's first
// call until glp_free_env. The batch's worker threads end after every group of footprints, so a thread
// that solved with GLPK frees its environment as it ends; otherwise each left one behind.
struct ThreadEnvironment {
  bool used = false;
  ~ThreadEnvironment() {
    if (used) glp_free_env();
  }
};
thread_local ThreadEnvironment thread_environment;

}  // namespace

MipSolution solve_with_glpk(const MipModel& model, const MipLimits& limits) {
  MipSolution solution;
  const int n = static_cast<int>(model.columns.size());
  if (n == 0) {
    solution.status = MipStatus::optimal;
    return solution;
  }
  // glp_load_matrix takes 1-based triplets; index 0 is unused by GLPK's convention.
  std::vector<int> ia{0}, ja{0};
  std::vector<double> ar{0.0};
  for (std::size_t i = 0; i < model.rows.size(); ++i)
    for (std::size_t k = 0; k < model.rows[i].columns.size(); ++k) {
      ia.push_back(static_cast<int>(i) + 1);
      ja.push_back(model.rows[i].columns[k] + 1);
      ar.push_back(model.rows[i].values[k]);
    }
  std::vector<double> values(static_cast<std::size_t>(n), 0.0);
  GlpkRun run;
  run.model = &model;
  run.ia = &ia;
  run.ja = &ja;
  run.ar = &ar;
  run.values = values.data();
  run.budget = NodeBudget{limits.node_limit, false};
  run.presolve_relaxation = limits.presolve_relaxation;
  run.gomory_min_columns = limits.gomory_min_columns;
  const double ms = std::ceil(limits.time_limit * 1000.0);
  run.tm_lim = ms >= static_cast<double>(INT_MAX) ? INT_MAX : static_cast<int>(std::max(1.0, ms));

  // Nothing of this frame changes between setjmp and the end of run_glpk except through `run`,
  // which is not read after a longjmp.
  std::jmp_buf error_exit;
  if (setjmp(error_exit) != 0) {
    glpk_error_exit = nullptr;
    glp_error_hook(nullptr, nullptr);
    glp_free_env();  // every GLPK object of this thread, the half-solved problem included
    solution.status = MipStatus::failed;
    solution.message = "glpk: internal error on " + std::to_string(n) + " columns, " +
                       std::to_string(model.rows.size()) + " rows";
    return solution;
  }
  thread_environment.used = true;
  glpk_error_exit = &error_exit;
  glp_error_hook(on_glpk_error, nullptr);
  run_glpk(run);
  glp_error_hook(nullptr, nullptr);
  glpk_error_exit = nullptr;

  const int ret = run.ret, mip_status = run.mip_status;
  const NodeBudget& budget = run.budget;
  const auto take_values = [&] {
    solution.values = values;
    solution.objective = run.objective;
  };

  switch (ret) {
    case 0:
      if (mip_status == GLP_OPT) {
        solution.status = MipStatus::optimal;
        take_values();
      } else if (mip_status == GLP_NOFEAS) {
        solution.status = MipStatus::infeasible;
        solution.message = "glpk: no integer solution exists";
      } else if (mip_status == GLP_FEAS) {
        solution.status = MipStatus::feasible;
        solution.message = "glpk: stopped at a feasible solution";
        take_values();
      } else {
        solution.status = MipStatus::no_solution;
        solution.message = "glpk: solution undefined";
      }
      return solution;
    case GLP_ENOPFS:  // the presolver proved the LP relaxation (hence the program) infeasible
    case GLP_ENOFEAS:
      solution.status = MipStatus::infeasible;
      solution.message = "glpk: no feasible solution (LP relaxation infeasible)";
      return solution;
    case GLP_ETMLIM:
    case GLP_ESTOP:
    case GLP_EMIPGAP: {
      const std::string why = ret == GLP_ETMLIM
                                  ? "time limit " + std::to_string(limits.time_limit) + " s reached"
                              : budget.hit ? "node limit " + std::to_string(limits.node_limit) + " reached"
                                           : "stopped";
      const bool has_best = mip_status == GLP_FEAS || mip_status == GLP_OPT;
      stopped_by_limit(solution, "glpk", why, has_best);
      if (has_best) take_values();
      return solution;
    }
    default:
      solution.status = MipStatus::failed;
      solution.message = "glpk: glp_intopt failed with code " + std::to_string(ret) + " on " + std::to_string(n) +
                         " columns, " + std::to_string(model.rows.size()) + " rows";
      return solution;
  }
}

}  // namespace city3d::detail
