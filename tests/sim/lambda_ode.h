// An ODE from a lambda, for the integrator tests: counts its evaluations and remembers the
// largest t it was asked for; its failure cause is "test failure cause".
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <utility>

#include "sim/integrator.h"

namespace kanesim::sim {

class LambdaOde final : public OdeSystem {
 public:
  using Fn = std::function<int(double, const double*, double*)>;
  LambdaOde(int n, Fn f) : n_(n), f_(std::move(f)) {}
  int Size() const override { return n_; }
  int Rhs(double t, const double* y, double* ydot) override {
    ++evals;
    max_t = std::max(max_t, t);
    return f_(t, y, ydot);
  }
  std::string FailureCause() const override { return "test failure cause"; }
  long evals = 0;
  double max_t = -INFINITY;

 private:
  int n_;
  Fn f_;
};

}  // namespace kanesim::sim
