// Helpers shared by `kanesim sweep` and `kanesim test`: run settings named in files into a
// pipeline::RunSpec (pipeline/pipeline.h), and a terminal progress line.
#pragma once

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fmt/core.h>
#include <string>

#include "pipeline/pipeline.h"

namespace kanesim::cli {

// A sweep file's or golden spec's run settings (names as on the command line, numbers
// NaN when not given) into the spec; false with *error naming the unknown name.
inline bool SpecFromNames(const std::string& solver, const std::string& integrator, pipeline::RunSpec* spec,
                          std::string* error) {
  if (!pipeline::IntegratorFromName(integrator, &spec->integrator)) {
    *error = "integrator = \"" + integrator + "\": unknown (" + pipeline::JoinNames(pipeline::IntegratorNames()) + ")";
    return false;
  }
  if (!pipeline::SolverFromName(solver, &spec->solver)) {
    *error = "solver = \"" + solver + "\": unknown (" + pipeline::JoinNames(pipeline::SolverNames()) + ")";
    return false;
  }
  return true;
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
