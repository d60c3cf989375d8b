// Helpers shared by `kanesim sweep` and `kanesim test`: option names to engine enums,
// run defaults from the experiment annotation (the same rules as `kanesim run`), and a
// terminal progress line.
#pragma once

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fmt/core.h>
#include <string>

#include "runtime/engine.h"
#include "runtime/flat/mechanism.h"
#include "runtime/sim/simulate.h"

namespace kanesim::cli {

inline rt::SolverPath SolverFromName(const std::string& s) {
  if (s == "dense") return rt::SolverPath::Dense;
  if (s == "sparse") return rt::SolverPath::Sparse;
  if (s == "recursive") return rt::SolverPath::Recursive;
  return rt::SolverPath::Auto;
}

// The integrator names of --integrator (run, sweep, test) and of `integrator = ...` in
// sweep and golden files; the CLI11 lists in cmd_run.cpp and cmd_sweep.cpp say the same.
inline constexpr const char* kIntegratorNames = "auto, ida, cvode, cvode-bdf, arkode, dop853";

inline rt::IntegratorKind IntegratorFromName(const std::string& s) {
  if (s == "ida") return rt::IntegratorKind::IDA;
  if (s == "cvode" || s == "cvode-bdf") return rt::IntegratorKind::CVODE;
  if (s == "arkode") return rt::IntegratorKind::ARKODE;
  if (s == "dop853") return rt::IntegratorKind::DOP853;
  return rt::IntegratorKind::Auto;
}

inline bool IsIntegratorName(const std::string& s) {
  return s == "auto" || s == "cvode-bdf" || IntegratorFromName(s) != rt::IntegratorKind::Auto;
}

// Times and tolerances: given values (NaN = not given) over the experiment annotation
// over the defaults, exactly as `kanesim run` resolves them (atol defaults to rtol).
inline sim::SimOptions ResolveSimOptions(const flat::Experiment& ex, double start, double stop, double interval,
                                         double rtol, double atol, const std::string& integrator) {
  sim::SimOptions so;
  if (!std::isnan(start)) so.start_time = start;
  so.stop_time = !std::isnan(stop) ? stop : ex.stop_time;
  if (!std::isnan(interval)) so.interval = interval;
  else if (ex.has_interval) so.interval = ex.interval;
  so.rtol = !std::isnan(rtol) ? rtol : ex.tolerance;
  so.atol = !std::isnan(atol) ? atol : so.rtol;
  so.integrator = IntegratorFromName(integrator);
  so.cvode_bdf = integrator == "cvode-bdf";
  return so;
}

// "[=====     ] 37/100  2 failed  ETA 12 s" on stderr, only on a terminal, at most ten
// times a second; erased by Finish().
class CountProgress {
 public:
  explicit CountProgress(bool enabled) : enabled_(enabled && isatty(STDERR_FILENO)) {}
  ~CountProgress() { Finish(); }
  void Update(int done, int failed, int total, double elapsed) {
    if (!enabled_) return;
    auto now = std::chrono::steady_clock::now();
    if (drawn_ && done < total && now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    drawn_ = true;
    constexpr int kWidth = 30;
    double frac = total > 0 ? static_cast<double>(done) / total : 1.0;
    std::string bar(static_cast<size_t>(frac * kWidth), '=');
    bar.resize(kWidth, ' ');
    std::string eta = done > 0 ? fmt::format("ETA {:.0f} s", elapsed / done * (total - done)) : "ETA ?";
    fmt::print(stderr, "\r\033[K[{}] {}/{}  {} failed  {}", bar, done, total, failed, eta);
    std::fflush(stderr);
  }
  void Finish() {
    if (drawn_) std::fputs("\r\033[K", stderr);
    drawn_ = false;
  }

 private:
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace kanesim::cli
