// libFuzzer entry point over the batch readers: a sweep file (sweep.toml), a golden spec
// (NAME.toml), a list of scenarios (--list CSV) and a stored golden output (NAME.csv), each
// given the same bytes. Any input must end in a result or a message, never a crash, hang,
// leak, overflowed conversion or undefined behaviour. What a reader accepts is then used
// as the program would: scenarios combined (sweep), settings text formatted (golden), the
// trajectory written back and read again (it must round-trip).
// The file name anchors relative paths in a folder that does not exist, so a `list =`
// path cannot reach the machine's files except by an absolute path, which must be a
// regular file of bounded size.
// Run: build-fuzz/tests/fuzz/kanesim_fuzz_toml CORPUS_DIR (seeds: tests/fuzz/corpus_toml/)
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "batch/golden.h"
#include "batch/scenario.h"
#include "batch/sweep_toml.h"

namespace {

constexpr const char* kPath = "/nonexistent-kanesim-fuzz/spec.toml";

void Sweep(const std::string& text) {
  using namespace kanesim::batch;
  SweepFileSpec spec;
  std::string err;
  if (!ReadSweepTomlText(kPath, text, &spec, &err)) return;
  std::vector<std::string> names;
  std::vector<Scenario> scenarios;
  if (spec.blocks.empty()) return;
  CombineBlocks(spec.blocks, &names, &scenarios, &err);
}

void Golden(const std::string& text) {
  using namespace kanesim::batch;
  GoldenSpec spec;
  std::string err;
  if (ReadGoldenSpecText(kPath, text, &spec, &err)) (void)SettingsText(spec);
}

void List(const std::string& text) {
  using namespace kanesim::batch;
  Block block;
  std::string err;
  ReadListCsvText("/nonexistent-kanesim-fuzz/list.csv", text, &block, &err);
}

void Stored(const std::string& text) {
  using namespace kanesim::batch;
  Trajectory t, back;
  std::string err;
  if (!ReadTrajectoryCsvText("/nonexistent-kanesim-fuzz/g.csv", text, &t, &err)) return;
  // What was accepted is finite and in increasing time; written and read again it is
  // the same (17 digits round-trip).
  if (!ReadTrajectoryCsvText("again.csv", FormatTrajectoryCsv(t), &back, &err) || back.t != t.t || back.rows != t.rows)
    std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  Sweep(text);
  Golden(text);
  List(text);
  Stored(text);
  return 0;
}
