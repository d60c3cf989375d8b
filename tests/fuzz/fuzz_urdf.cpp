// libFuzzer entry point over the URDF importer (import/import.h): any bytes must end in a
// .mech text or located errors, never a crash, hang, leak or undefined behaviour. What the
// importer accepts must be a .mech file the language parses without an error (the text is
// written for people and the parser alike), so it is parsed too.
// Run: build-fuzz/tests/fuzz/kanesim_fuzz_urdf CORPUS_DIR (seeds: tests/fuzz/corpus_urdf/)
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "import/import.h"
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static kanesim::fuzz::StdlibOnce stdlib;
  const std::string text(reinterpret_cast<const char*>(data), size);
  kanesim::import::Options o;
  o.use_ros_package_path = false;  // mesh names are looked up in a folder that does not exist
  const kanesim::import::Result r = kanesim::import::UrdfToMech("/nonexistent-kanesim-fuzz/robot.urdf", text, o);
  if (r.ok == r.mech.empty() || r.ok != (r.num_errors == 0)) std::abort();
  if (!r.ok) {
    if (r.diagnostics.find("error[U") == std::string::npos) std::abort();  // refused without a code
    return 0;
  }
  kanesim::lang::Diagnostics diags(&stdlib.Sources());
  stdlib.Load(r.mech, diags);
  if (diags.HasErrors()) std::abort();  // the importer wrote text the parser refuses
  return 0;
}
