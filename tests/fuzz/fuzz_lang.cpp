// libFuzzer entry point over the language front end. Any input must end in diagnostics or
// a result, never a crash, hang, stack overflow, leak or undefined behaviour: the input is
// parsed as a .mech file (then ast::Dump), elaborated with the embedded standard library
// if it parsed, and every diagnostic is rendered. The library is parsed once per process
// (fuzz_support.h).
// Run: build-fuzz/tests/fuzz/kanesim_fuzz_lang -dict=tests/fuzz/mech.dict CORPUS_DIR
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_support.h"
#include "lang/ast.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace kanesim::lang;
  static kanesim::fuzz::StdlibOnce library;
  const std::string text(reinterpret_cast<const char*>(data), size);
  Diagnostics diags(&library.Sources());
  Program& program = library.Load(text, diags);
  if (program.files[0]) (void)ast::Dump(*program.files[0]);
  if (!diags.HasErrors()) {
    kanesim::flat::Mechanism mechanism;
    Elaborate(program, ElaborateOptions{}, &mechanism, diags);
  }
  (void)diags.RenderAll();
  return 0;
}
