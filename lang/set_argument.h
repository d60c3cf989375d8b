// A `--set NAME=VALUE` argument as typed on the command line, split into the override the
// elaborator applies (lang/elaborate.h). One function for the CLI and the --set fuzzer, so
// the fuzzer follows the user's path exactly.
#pragma once

#include <string>

#include "lang/elaborate.h"

namespace kanesim::lang {

// Splits at the first '=': "rod.L=0.5" -> {"rod.L", "0.5"}. False for an argument with no
// '=' or an empty name (the value may be empty: the elaborator reports it, E210).
bool ParseSetArgument(const std::string& argument, ParamOverride* out);

}  // namespace kanesim::lang
