// kanesim: the command line. Subcommands register themselves; only main picks exit codes.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <cstring>
#include <new>

#ifdef __GLIBC__
#include <malloc.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#endif

#include "cli/cmd_linearize.h"
#include "cli/common.h"
#include "cli/scene.h"

namespace {

// Fresh memory is the front end's largest cost after its instructions: each new 4 KB page
// costs 1.5-4 us here (docs/benchmarks/2026-11-29_front_end_pass7.md), and loading a robot
// touches a few MB. By default malloc maps each block over 128 KB apart and unmaps it when
// freed, so every doubling of a large vector (the expression pool, the parameters) touched
// new pages; on the heap the old ones are reused by what is allocated next.
void KeepLargeBlocksOnTheHeap() {
#ifdef __GLIBC__
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 64 << 20);
#endif
}

// A command that loads a model: the heap is grown ahead once and the 2 MB-aligned part of
// the growth marked for transparent huge pages, so what the front end allocates next comes
// mostly as 2 MB pages, one fault each instead of 512 (where the system allows them: with
// transparent huge pages off the advice changes nothing). Virtual memory only: a page
// still costs nothing until touched.
void GrowHeapInHugePages() {
#if defined(__GLIBC__) && defined(MADV_HUGEPAGE) && !defined(__SANITIZE_ADDRESS__)
  constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;
  constexpr std::size_t kAhead = std::size_t{8} << 20;
  const auto old_end = reinterpret_cast<std::uintptr_t>(sbrk(0));
  char* block = static_cast<char*>(std::malloc(kAhead));
  if (!block) return;
  asm volatile("" : : "r"(block) : "memory");  // kept: the compiler may drop a malloc only freed
  const auto begin = reinterpret_cast<std::uintptr_t>(block);
  const auto end = begin + kAhead;  // malloc wrote the next chunk's header here
  const auto new_end = reinterpret_cast<std::uintptr_t>(sbrk(0));
  // Only a block that grew the heap (not a mapping of its own, nor another allocator's);
  // the 2 MB region holding `end` is left out, its first page already touched.
  const std::uintptr_t from = (old_end + kHuge - 1) & ~(kHuge - 1);
  const std::uintptr_t to = end & ~(kHuge - 1);
  const bool advised = new_end > old_end && end > old_end && end <= new_end && from < to &&
                       madvise(reinterpret_cast<void*>(from), to - from, MADV_HUGEPAGE) == 0;
  std::free(block);  // back into the heap's top, which stays (trim threshold above)
  // Below the first 2 MB boundary the heap still comes in 4 KB pages, and a small model
  // would fit there whole: a block that ends at the boundary, kept and never touched,
  // moves what is allocated next up to it. The top chunk begins at `block`'s header.
  constexpr std::uintptr_t kHeader = 2 * sizeof(std::size_t);
  const std::uintptr_t top = begin - kHeader;
  if (!advised || from - top < 4 * kHeader) return;
  static void* filler = nullptr;  // reachable: not a leak
  filler = std::malloc(from - top - sizeof(std::size_t));  // a chunk of exactly from - top
  if (filler != block) {  // not carved from the top (a free chunk fitted): no use
    std::free(filler);
    filler = nullptr;
  }
#endif
}

}  // namespace

int main(int argc, char** argv) {
  KeepLargeBlocksOnTheHeap();
  CLI::App app{"kanesim: mechanisms in a Modelica-like language, simulated by Kane's method"};
  app.set_version_flag("--version", std::string("kanesim ") + KANESIM_VERSION);
  app.require_subcommand(1);
  int exit_code = kanesim::cli::kExitOk;
  // Every subcommand by name and description (all the top level's help and errors need);
  // the options only of the one named on the command line, its first word not starting
  // with '-' (the top level has flags only). Registering every option of every command
  // was ~1.2 M instructions of each process start (sweep's alone 0.5 M).
  struct Command {
    const char* name;
    void (*add)(CLI::App&, int*, bool);
  };
  const Command commands[] = {{"check", kanesim::cli::AddCheckCommand},   {"run", kanesim::cli::AddRunCommand},
                              {"sweep", kanesim::cli::AddSweepCommand},   {"test", kanesim::cli::AddTestCommand},
                              {"linearize", kanesim::cli::AddLinearizeCommand}, {"view", kanesim::cli::AddViewCommand},
                              {"import", kanesim::cli::AddImportCommand},
                              {"export", kanesim::cli::AddExportCommand},
                              {"units", kanesim::cli::AddUnitsCommand}};
  const char* named = "";
  for (int i = 1; i < argc && !*named; ++i)
    if (argv[i][0] != '-') named = argv[i];
  for (const Command& c : commands) c.add(app, &exit_code, std::strcmp(named, c.name) == 0);
  if (*named) GrowHeapInHugePages();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int rc = app.exit(e);
    return rc == 0 ? kanesim::cli::kExitOk : kanesim::cli::kExitModelError;
  } catch (const std::bad_alloc&) {
    // A last resort: the front end's limits (docs/language.md) keep models within memory.
    std::fprintf(stderr,
                 "kanesim: error: out of memory\n"
                 "  hint: a smaller model, or more memory; the limits are in docs/language.md\n");
    return kanesim::cli::kExitModelError;
  }
  return exit_code;
}
