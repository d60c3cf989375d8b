// `kanesim units "N.m/rad" "kg.m2" ...`: each unit string as the checker reads it (its SI
// form and scale), one line each: `TEXT = SCALE * SI  [exponents m kg s A K mol cd rad]`,
// or the reason it is not a unit. Exit 1 if any string is not a unit (docs/language.md).
#include <CLI/CLI.hpp>
#include <fmt/core.h>

#include <memory>
#include <string>
#include <vector>

#include "cli/common.h"
#include "lang/lang.h"

namespace kanesim::cli {

namespace {

int UnitsCommand(const std::vector<std::string>& texts) {
  int rc = kExitOk;
  for (const std::string& t : texts) {
    lang::Unit u;
    std::string error;
    if (!lang::ParseUnit(t, &u, &error)) {
      fmt::print("{}: not a unit: {}\n", t, error);
      rc = kExitModelError;
      continue;
    }
    lang::Unit coherent = u;
    coherent.scale = 1;
    std::string exps;
    for (int i = 0; i < lang::Unit::kBase; ++i) {
      const int tw = u.twice[static_cast<size_t>(i)];
      exps += (i ? " " : "") + (tw % 2 ? fmt::format("{}", tw / 2.0) : std::to_string(tw / 2));
    }
    fmt::print("{} = {:.17g} * {}  [{}]\n", t, u.scale, coherent.ToString(), exps);
  }
  return rc;
}

}  // namespace

void AddUnitsCommand(CLI::App& app, int* exit_code, bool options) {
  CLI::App* cmd = app.add_subcommand("units", "Show unit strings as the unit check reads them (SI form and scale)");
  if (!options) return;
  auto texts = std::make_shared<std::vector<std::string>>();
  cmd->add_option("unit", *texts, "Modelica unit strings: \"N.m/rad\", \"kg.m2\", \"m/s2\", \"1\"")->required();
  cmd->callback([texts, exit_code]() { *exit_code = UnitsCommand(*texts); });
}

}  // namespace kanesim::cli
