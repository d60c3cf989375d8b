// libFuzzer entry point over `--set` values: each line of the input is one command-line
// argument NAME=VALUE, split as the CLI splits it (lang::ParseSetArgument), then parsed
// and applied by the elaborator to a fixed model with parameters of every type and shape
// (kModel below: Integer with a range and structural, Real, Real[3], Real[2, 2],
// Boolean driving a conditional component, String, a constant). Any input must end in
// diagnostics or a mechanism, never a crash, hang or undefined behaviour. The model and
// the standard library are parsed once per process.
// Run: build-fuzz/tests/fuzz/kanesim_fuzz_set -dict=tests/fuzz/set.dict CORPUS_DIR
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "fuzz_support.h"
#include "lang/set_argument.h"

namespace {

// At most this many --set arguments per input: enough for every parameter twice.
constexpr int kMaxArguments = 16;

const char kModel[] = R"mech(model SetTarget "Parameters of every type and shape"
  parameter Integer N(min = 1, max = 8) = 2 "Links (structural)";
  parameter Real L(unit = "m", min = 0) = 0.5;
  parameter Real m(unit = "kg") = 1;
  parameter Real[3] g = {0, -9.81, 0};
  parameter Real[2, 2] K = [1, 0; 0, 2];
  parameter Boolean damped = true;
  parameter String label = "links";
  parameter Real d = if damped then 0.1 * K[2, 2] else 0;
  constant Real c0 = 2;
  World world(g = g);
  Revolute j[N](each axis = {0, 0, 1}, each q(start = 0.1));
  Rod links[N](each L = L, each m = m);
  RotationalDamper damp(d = d) if damped;
equation
  connect(world.frame_b, j[1].frame_a);
  for i in 1:N loop
    connect(j[i].frame_b, links[i].frame_a);
  end for;
  for i in 2:N loop
    connect(links[i - 1].frame_b, j[i].frame_a);
  end for;
  if damped then
    connect(damp.flange_b, j[1].drive);
  end if;
  annotation(experiment(StopTime = 1));
end SetTarget;
)mech";

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace kanesim::lang;
  static kanesim::fuzz::StdlibOnce library;
  static const bool parsed = [] {
    Diagnostics diags(&library.Sources());
    library.Load(kModel, diags);
    if (diags.HasErrors()) __builtin_trap();  // the target model must load cleanly
    return true;
  }();
  (void)parsed;
  ElaborateOptions options;
  std::istringstream lines(std::string(reinterpret_cast<const char*>(data), size));
  std::string line;
  while (std::getline(lines, line) && options.overrides.size() < kMaxArguments) {
    ParamOverride o;
    if (ParseSetArgument(line, &o)) options.overrides.push_back(std::move(o));
  }
  Program& program = library.Reset();
  Diagnostics diags(&library.Sources());
  kanesim::flat::Mechanism mechanism;
  Elaborate(program, options, &mechanism, diags);
  (void)diags.RenderAll();
  return 0;
}
