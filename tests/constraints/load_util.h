// Loading a .mech model (file or text) through the language front end, for the
// constraint tests, and running it into memory.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "lang/elaborate.h"
#include "runtime/engine.h"
#include "runtime/sim/simulate.h"
#include "stdlib/stdlib.h"

namespace kanesim::test {

inline const std::string kRoot = KANESIM_SOURCE_DIR;

struct Loaded {
  lang::Program program;
  flat::Mechanism mech;
  std::shared_ptr<const rt::Program> prog;
  std::vector<rt::CompileMessage> errors;
};

// Elaborates and compiles; compile errors are kept in `errors` (prog is then null).
inline std::unique_ptr<Loaded> LoadModel(const std::string& path, std::vector<lang::ParamOverride> sets = {}) {
  auto l = std::make_unique<Loaded>();
  lang::Diagnostics diags(&l->program.sources);
  bool ok = lang::LoadProgram(path, stdlib::Files(), &l->program, diags);
  lang::ElaborateOptions eo;
  eo.overrides = std::move(sets);
  ok = ok && lang::Elaborate(l->program, eo, &l->mech, diags);
  EXPECT_TRUE(ok) << diags.RenderAll();
  if (!ok) return nullptr;
  rt::CompileResult cr = rt::Compile(l->mech, {});
  l->errors = cr.errors;
  l->prog = cr.program;
  return l;
}

inline sim::MemorySink RunModel(const rt::Program& p, double stop, double interval, double tol,
                           std::vector<std::string> signals,
                           rt::IntegratorKind integrator = rt::IntegratorKind::Auto) {
  sim::SimOptions o;
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
