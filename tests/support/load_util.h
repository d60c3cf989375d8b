// Loading a .mech model (file or text) through the language front end and compiling it,
// for the tests, and running it into memory (tests/support/model_loader.h without GoogleTest).
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "compiler/compiler.h"
#include "sim/simulate.h"
#include "tests/support/model_loader.h"

namespace kanesim::test {

inline const std::string kRoot = KANESIM_SOURCE_DIR;

struct Loaded : LoadedMech {
  std::shared_ptr<const rt::Program> prog;
  std::vector<rt::CompileMessage> errors;
};

// Elaborates (a file, or `text` itself when is_text) and compiles with `options`; compile
// errors are kept in `errors` (prog is then null), language errors fail the test.
inline std::unique_ptr<Loaded> LoadModel(const std::string& path_or_text, std::vector<lang::ParamOverride> sets = {},
                                         const rt::CompileOptions& options = {}, bool is_text = false) {
  auto l = std::make_unique<Loaded>();
  std::string diags;
  const bool ok = LoadInto(l.get(), path_or_text, std::move(sets), is_text, &diags);
  EXPECT_TRUE(ok) << diags;
  if (!ok) return nullptr;
  rt::CompileResult cr = rt::Compile(l->mech, options);
  l->errors = cr.errors;
  l->prog = cr.program;
  return l;
}

inline sim::MemorySink RunModel(const rt::Program& p, double stop, double interval, double tol,
                           std::vector<std::string> signals,
                           rt::Integrator integrator = rt::Integrator::Auto, bool project_steps = false) {
  sim::SimOptions o;
  o.project_steps = project_steps;
  o.stop_time = stop;
  o.interval = interval;
  o.rtol = o.atol = tol;
  o.integrator = integrator;
  o.signals = std::move(signals);
  sim::MemorySink sink;
  sim::SimResult r = sim::Simulate(p, o, sink);
  EXPECT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
  return sink;
}

inline size_t Col(const sim::MemorySink& s, const std::string& name) {
  for (size_t i = 0; i < s.names.size(); ++i)
    if (s.names[i] == name) return i;
  ADD_FAILURE() << "no signal " << name;
  return 0;
}

}  // namespace kanesim::test
