#include "flat/diagnostic_codes.h"

namespace kanesim::flat {

const char* DiagCodeString(DiagCode c) {
  switch (c) {
#define KANESIM_X(e, code, summary) \
  case DiagCode::e:                 \
    return code;
    KANESIM_DIAGNOSTICS(KANESIM_X)
#undef KANESIM_X
  }
  return "?";
}

const char* DiagCodeSummary(DiagCode c) {
  switch (c) {
#define KANESIM_X(e, code, summary) \
  case DiagCode::e:                 \
    return summary;
    KANESIM_DIAGNOSTICS(KANESIM_X)
#undef KANESIM_X
  }
  return "?";
}

}  // namespace kanesim::flat
