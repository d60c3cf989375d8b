// Forward sensitivities two ways (issue 44 §2; docs/integrators.md "Parameter sensitivities"),
// on the double pendulum by rod1.L and rod2.m over 2 s:
//   augmented  kanesim's method (sim/sensitivity.cpp): the variational equations integrated
//              with the motion as one ODE [y, s_1, s_2], here by CVODES' Adams without its
//              sensitivity module, so that both rows share one integrator;
//   staggered  CVODES' forward sensitivity module: staggered corrector, the sensitivities in
//              its error test (CVodeSetSensErrCon), tolerances from the state's.
// Both get the same right-hand side of the sensitivities, (df/dy) s along s and df/dp between
// the models rebound at p +/- delta, by central differences (sim/sensitivity.cpp's steps).
// Accuracy: the largest error of s at the output instants against central differences of two
// whole runs at rtol 1e-12 (h = 1e-5), relative to the largest |s|; cost: evaluations of f
// and wall time. CVODES is CVODE plus that module (the same release): it is linked before
// the libraries kanesim's own CVODE comes from, so every CVode* symbol here is CVODES'.
//
//   build/bench/cvodes_sensitivity
#include <cvodes/cvodes.h>
#include <nvector/nvector_serial.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "compiler/compiler.h"
#include "tests/support/model_loader.h"

namespace {

using namespace kanesim;
using Workspace = std::unique_ptr<rt::Workspace, void (*)(rt::Workspace*)>;

const double kCbrtEps = std::cbrt(std::numeric_limits<double>::epsilon());
constexpr double kStop = 2.0, kInterval = 0.05;

struct Model {
  std::shared_ptr<const rt::Program> base;
  std::vector<std::shared_ptr<const rt::Program>> plus, minus;  // per parameter, at p +/- delta
  std::vector<double> delta;
};

// The right-hand side and the sensitivities' right-hand side, counting evaluations of f.
struct Rhs {
  const Model* m;
  Workspace ws, aside;
  std::vector<Workspace> ws_plus, ws_minus;
  int n;
  long evals = 0;
  std::vector<double> yp, fp, fm;

  explicit Rhs(const Model& model)
      : m(&model), ws(rt::MakeWorkspace(*model.base)), aside(rt::MakeWorkspace(*model.base)),
        n(rt::StateSize(*model.base)), yp(static_cast<size_t>(n)), fp(yp.size()), fm(yp.size()) {
    for (size_t k = 0; k < model.plus.size(); ++k) {
      ws_plus.push_back(rt::MakeWorkspace(*model.plus[k]));
      ws_minus.push_back(rt::MakeWorkspace(*model.minus[k]));
    }
  }
  int F(double t, const double* y, double* f) {
    ++evals;
    return rt::Derivative(*m->base, *ws, t, y, f);
  }
  // sdot = (df/dy) s + df/dp_k.
  int S(double t, const double* y, const double* s, size_t k, double* sdot) {
    double ns = 0.0, ny = 0.0;
    for (int i = 0; i < n; ++i) ns = std::max(ns, std::fabs(s[i])), ny = std::max(ny, std::fabs(y[i]));
    std::fill(sdot, sdot + n, 0.0);
    if (ns > 0.0) {
      const double e = kCbrtEps * (1.0 + ny) / ns;
      for (int i = 0; i < n; ++i) yp[i] = y[i] + e * s[i];
      if (rt::Derivative(*m->base, *aside, t, yp.data(), fp.data()) != 0) return 1;
      for (int i = 0; i < n; ++i) yp[i] = y[i] - e * s[i];
      if (rt::Derivative(*m->base, *aside, t, yp.data(), fm.data()) != 0) return 1;
      evals += 2;
      for (int i = 0; i < n; ++i) sdot[i] = (fp[i] - fm[i]) / (2.0 * e);
    }
    if (rt::Derivative(*m->plus[k], *ws_plus[k], t, y, fp.data()) != 0) return 1;
    if (rt::Derivative(*m->minus[k], *ws_minus[k], t, y, fm.data()) != 0) return 1;
    evals += 2;
    for (int i = 0; i < n; ++i) sdot[i] += (fp[i] - fm[i]) / (2.0 * m->delta[k]);
    return 0;
  }
};

struct Outcome {
  std::vector<std::vector<double>> rows;  // per output instant: [y, s_1, ..., s_m]
  long steps = 0, evals = 0;
  double seconds = 0.0;
  bool ok = false;
};

// One CVODES Adams run of `size` states; `setup` adds what the variant needs.
template <typename Setup, typename Read>
Outcome RunCvodes(int size, const std::vector<double>& z0, double rtol, void* user, CVRhsFn f, Setup setup, Read read) {
  Outcome out;
  SUNContext ctx = nullptr;
  SUNContext_Create(nullptr, &ctx);
  N_Vector z = N_VNew_Serial(size, ctx);
  std::copy(z0.begin(), z0.end(), N_VGetArrayPointer(z));
  void* mem = CVodeCreate(CV_ADAMS, ctx);
  SUNNonlinearSolver nls = SUNNonlinSol_FixedPoint(z, 0, ctx);
  const auto start = std::chrono::steady_clock::now();
  bool ok = CVodeInit(mem, f, 0.0, z) == CV_SUCCESS && CVodeSStolerances(mem, rtol, rtol) == CV_SUCCESS &&
            CVodeSetUserData(mem, user) == CV_SUCCESS && CVodeSetNonlinearSolver(mem, nls) == CV_SUCCESS &&
            CVodeSetMaxNumSteps(mem, 1000000) == CV_SUCCESS && setup(mem, ctx, z);
  for (double t_out = 0.0; ok && t_out <= kStop + 1e-12; t_out += kInterval) {
    double t = 0.0;
    if (t_out > 0.0) ok = CVode(mem, t_out, z, &t, CV_NORMAL) >= 0;
    if (ok) out.rows.push_back(read(mem, t_out, N_VGetArrayPointer(z)));
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  CVodeGetNumSteps(mem, &out.steps);
  out.ok = ok;
  CVodeFree(&mem);
  SUNNonlinSolFree(nls);
  N_VDestroy(z);
  SUNContext_Free(&ctx);
  return out;
}

int PlainF(double t, N_Vector y, N_Vector ydot, void* user) {
  return static_cast<Rhs*>(user)->F(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
}

// The augmented system [y, s_1, ..., s_m].
int AugmentedF(double t, N_Vector z, N_Vector zdot, void* user) {
  Rhs& r = *static_cast<Rhs*>(user);
  const double* zz = N_VGetArrayPointer(z);
  double* dz = N_VGetArrayPointer(zdot);
  if (r.F(t, zz, dz) != 0) return 1;
  for (size_t k = 0; k < r.m->plus.size(); ++k)
    if (r.S(t, zz, zz + r.n * (k + 1), k, dz + r.n * (k + 1)) != 0) return 1;
  return 0;
}

int SensF(int ns, double t, N_Vector y, N_Vector, int is, N_Vector s, N_Vector sdot, void* user, N_Vector, N_Vector) {
  (void)ns;
  Rhs& r = *static_cast<Rhs*>(user);
  return r.S(t, N_VGetArrayPointer(y), N_VGetArrayPointer(s), static_cast<size_t>(is), N_VGetArrayPointer(sdot));
}

Model Load(const std::vector<std::string>& names) {
  auto l = test::LoadMech(std::string(KANESIM_SOURCE_DIR) + "/examples/double_pendulum.mech");
  Model m;
  auto mech = std::make_shared<const flat::Mechanism>(l->mech);
  m.base = rt::Compile(mech, {}).program;
  for (const std::string& name : names) {
    const auto i = static_cast<size_t>(mech->FindParam(name));
    const double p = flat::EvaluateParams(*mech)[i], d = kCbrtEps * std::max(std::fabs(p), 1e-3);
    m.delta.push_back(d);
    m.plus.push_back(rt::Rebind(*m.base, flat::EvaluateParams(*mech, {{i, p + d}})).program);
    m.minus.push_back(rt::Rebind(*m.base, flat::EvaluateParams(*mech, {{i, p - d}})).program);
  }
  return m;
}

}  // namespace

int main() {
  const std::vector<std::string> names = {"rod1.L", "rod2.m"};
  const Model m = Load(names);
  const int n = rt::StateSize(*m.base);
  const size_t np = names.size();
  std::vector<double> y0(static_cast<size_t>(n));
  rt::InitialState(*m.base, y0.data());  // s(0) = 0: the starts do not depend on these
  auto no_setup = [](void*, SUNContext, N_Vector) { return true; };
  auto read_z = [&](void*, double, const double* z) { return std::vector<double>(z, z + n * (np + 1)); };
  auto read_y = [&](void*, double, const double* z) { return std::vector<double>(z, z + n); };

  // The reference: (y(p + h) - y(p - h)) / 2h of whole runs at rtol 1e-12.
  const double h = 1e-5;
  std::vector<std::vector<double>> ref;  // per instant, per parameter, per state
  {
    auto l = test::LoadMech(std::string(KANESIM_SOURCE_DIR) + "/examples/double_pendulum.mech");
    const flat::Mechanism& mech = l->mech;
    for (size_t k = 0; k < np; ++k) {
      const auto i = static_cast<size_t>(mech.FindParam(names[k]));
      const double p = flat::EvaluateParams(mech)[i];
      std::vector<Outcome> runs;
      for (int sign : {1, -1}) {
        Model mm;
        mm.base = rt::Rebind(*m.base, flat::EvaluateParams(mech, {{i, p + sign * h}})).program;
        Rhs r(mm);
        runs.push_back(RunCvodes(n, y0, 1e-12, &r, PlainF, no_setup, read_y));
      }
      ref.resize(runs[0].rows.size(), std::vector<double>(static_cast<size_t>(n) * np));
      for (size_t row = 0; row < ref.size(); ++row)
        for (int j = 0; j < n; ++j)
          ref[row][k * static_cast<size_t>(n) + static_cast<size_t>(j)] =
              (runs[0].rows[row][static_cast<size_t>(j)] - runs[1].rows[row][static_cast<size_t>(j)]) / (2 * h);
    }
  }
  auto error = [&](const Outcome& o) {
    double err = 0.0, scale = 0.0;
    for (size_t row = 0; row < ref.size() && row < o.rows.size(); ++row)
      for (size_t j = 0; j < ref[row].size(); ++j) {
        err = std::max(err, std::fabs(o.rows[row][static_cast<size_t>(n) + j] - ref[row][j]));
        scale = std::max(scale, std::fabs(ref[row][j]));
      }
    return err / scale;
  };

  std::printf("double pendulum, d/d(%s, %s) over %.0f s, CVODES Adams; error: largest |s - differences of runs| "
              "/ largest |s| at %zu instants\n",
              names[0].c_str(), names[1].c_str(), kStop, ref.size());
  std::printf("%-10s %7s %8s %10s %10s %10s\n", "method", "rtol", "steps", "f evals", "time (s)", "rel. error");
  for (double rtol : {1e-6, 1e-8, 1e-10}) {
    {
      Rhs r(m);
      std::vector<double> z0(static_cast<size_t>(n) * (np + 1), 0.0);
      std::copy(y0.begin(), y0.end(), z0.begin());
      Outcome o = RunCvodes(n * static_cast<int>(np + 1), z0, rtol, &r, AugmentedF, no_setup, read_z);
      std::printf("%-10s %7.0e %8ld %10ld %10.4f %10.2e%s\n", "augmented", rtol, o.steps, r.evals, o.seconds, error(o),
                  o.ok ? "" : " (failed)");
    }
    {
      Rhs r(m);
      N_Vector* s0 = nullptr;
      std::vector<N_Vector> sens;
      auto setup = [&](void* mem, SUNContext ctx, N_Vector z) {
        s0 = N_VCloneVectorArray(static_cast<int>(np), z);
        for (size_t k = 0; k < np; ++k) N_VConst(0.0, s0[k]);
        SUNNonlinearSolver nls = SUNNonlinSol_FixedPointSens(static_cast<int>(np), z, 0, ctx);  // staggered: Ns vectors
        return CVodeSensInit1(mem, static_cast<int>(np), CV_STAGGERED, SensF, s0) == CV_SUCCESS &&
               CVodeSensEEtolerances(mem) == CV_SUCCESS && CVodeSetSensErrCon(mem, SUNTRUE) == CV_SUCCESS &&
               CVodeSetNonlinearSolverSensStg(mem, nls) == CV_SUCCESS;
      };
      auto read = [&](void* mem, double, const double* y) {
        std::vector<double> row(y, y + n);
        double t = 0.0;
        CVodeGetSens(mem, &t, s0);
        for (size_t k = 0; k < np; ++k) {
          const double* s = N_VGetArrayPointer(s0[k]);
          row.insert(row.end(), s, s + n);
        }
        return row;
      };
      Outcome o = RunCvodes(n, y0, rtol, &r, PlainF, setup, read);
      std::printf("%-10s %7.0e %8ld %10ld %10.4f %10.2e%s\n", "staggered", rtol, o.steps, r.evals, o.seconds, error(o),
                  o.ok ? "" : " (failed)");
      if (s0) N_VDestroyVectorArray(s0, static_cast<int>(np));
    }
  }
  return 0;
}
