#include "runtime/kane.h"

namespace kanesim::rt {

struct SparsePattern {};
struct SparseSymbolic {};
struct SparseNumeric {};
void DestroySparseSymbolic(SparseSymbolic* s) { delete s; }
void DestroySparseNumeric(SparseNumeric* s) { delete s; }
bool BuildSparse(Program&, std::string* error) {
  *error = "not implemented";
  return false;
}
void InitSparseWorkspace(const Program&, Workspace&) {}
int SolveSparse(const Program&, Workspace& ws) {
  ws.error = "sparse path not implemented";
  return -1;
}

}  // namespace kanesim::rt
