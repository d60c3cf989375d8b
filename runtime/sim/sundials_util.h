// Internal to runtime/sim: ownership of the SUNDIALS objects every solver needs.
#pragma once

#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>
#include <sundials/sundials_nonlinearsolver.h>

#include <string>

namespace kanesim::sim::detail {

// A SUNContext plus the vectors, matrix and solvers made in it, freed in reverse order.
class SundialsObjects {
 public:
  SundialsObjects() { ok_ = SUNContext_Create(nullptr, &ctx) == 0; }
  ~SundialsObjects() {
    if (nls) SUNNonlinSolFree(nls);
    if (ls) SUNLinSolFree(ls);
    if (A) SUNMatDestroy(A);
    if (yp) N_VDestroy(yp);
    if (y) N_VDestroy(y);
    if (ctx) SUNContext_Free(&ctx);
  }
  SundialsObjects(const SundialsObjects&) = delete;
  SundialsObjects& operator=(const SundialsObjects&) = delete;
  bool ok() const { return ok_; }

  SUNContext ctx = nullptr;
  N_Vector y = nullptr;   // state (and the solver's output)
  N_Vector yp = nullptr;  // IDA only: y'
  SUNMatrix A = nullptr;
  SUNLinearSolver ls = nullptr;
  SUNNonlinearSolver nls = nullptr;

 private:
  bool ok_ = false;
};

// "<what> [<SUNDIALS' own message>]" when SUNDIALS said something.
inline std::string WithDetail(const std::string& what, const std::string& detail) {
  return detail.empty() ? what : what + " [" + detail + "]";
}

}  // namespace kanesim::sim::detail
