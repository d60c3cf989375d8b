#include "lang/set_argument.h"

namespace kanesim::lang {

bool ParseSetArgument(const std::string& argument, ParamOverride* out) {
  const size_t eq = argument.find('=');
  if (eq == std::string::npos || eq == 0) return false;
  out->name = argument.substr(0, eq);
  out->value = argument.substr(eq + 1);
  return true;
}

}  // namespace kanesim::lang
