// libFuzzer entry point over the language front end. Any input must end in diagnostics or
// a result, never a crash, hang, stack overflow, leak or undefined behaviour:
//   1. Lex + Parse (+ ast::Dump and rendering every diagnostic),
//   2. LoadProgramFromText + Elaborate with the embedded standard library.
// Run: build-fuzz/tests/fuzz/kanesim_fuzz_lang -dict=tests/fuzz/mech.dict CORPUS_DIR
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "lang/ast.h"
#include "lang/diagnostics.h"
#include "lang/elaborate.h"
#include "lang/parser.h"
#include "lang/source.h"
#include "stdlib/stdlib.h"

namespace {

void LexAndParse(const std::string& text) {
  using namespace kanesim::lang;
  SourceManager sm;
  Diagnostics diags(&sm);
  int file = sm.Add("fuzz.mech", text);
  auto def = Parse(file, sm, diags);
  if (def) (void)ast::Dump(*def);
  (void)diags.RenderAll();
}

void LoadAndElaborate(const std::string& text) {
  using namespace kanesim::lang;
  static const std::vector<std::pair<std::string, std::string>> stdlib = kanesim::stdlib::Files();
  Program program;
  Diagnostics diags(&program.sources);
  if (LoadProgramFromText("fuzz.mech", text, stdlib, &program, diags)) {
    kanesim::flat::Mechanism mechanism;
    Elaborate(program, ElaborateOptions{}, &mechanism, diags);
  }
  (void)diags.RenderAll();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  LexAndParse(text);
  LoadAndElaborate(text);
  return 0;
}
