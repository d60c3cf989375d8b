// One loader for kanesim's optional shared modules: the mesh importer (assimp), the
// viewer's HTTP server (cpp-httplib) and the MPI mode of sweeps (OpenMPI). Each is a
// MODULE library that the kanesim binary opens with dlopen the first time a command needs
// it, so that a run that needs none of them maps none of their libraries at start.
//
// Where a module is looked for, in order (the first that opens and passes `accept` wins):
//   1. $ENV_VARIABLE when set, and then nowhere else (tests point it at a missing file);
//   2. beside the running executable;
//   3. <executable's directory>/<kInstalledModuleDir>, the layout `cmake --install` writes
//      (bin/kanesim and lib/kanesim/lib*.so);
//   4. the build tree's copy (a path compiled in by CMake).
#pragma once

#include <functional>
#include <string>

namespace kanesim::dynamic_module {

struct Spec {
  const char* file_name;          // e.g. "libkanesim_viz_http.so"
  const char* env_variable;       // e.g. "KANESIM_VIZ_HTTP_MODULE"
  const char* build_path;         // the build tree's copy, or nullptr
  const char* entry_point;        // the extern "C" function that returns the module's table
  const char* what;               // for messages, e.g. "the viewer's HTTP server library"
  bool global_symbols = false;    // RTLD_GLOBAL (OpenMPI's own plugins resolve libmpi's symbols)
};

// Opens the first candidate whose entry point `accept` takes: `accept` gets the entry
// point's address, calls it through its own function type and returns whether the table
// it got is the one this build expects (its ABI version). The handle then stays open for the
// life of the process. Returns false with *error listing every path tried and why not.
bool Open(const Spec& spec, const std::function<bool(void* entry)>& accept, std::string* error);

// A module's table of functions, or why there is none.
template <class Api>
struct Loaded {
  const Api* api = nullptr;
  std::string error;
};

// The common case: the entry point is `const Api* entry()` and the table's first field,
// `abi_version`, must equal this build's. Call once per process (a function-local static).
template <class Api>
Loaded<Api> LoadTable(const Spec& spec, int abi_version) {
  Loaded<Api> out;
  Open(
      spec,
      [&out, abi_version](void* entry) {
        const Api* api = reinterpret_cast<const Api* (*)()>(entry)();
        if (!api || api->abi_version != abi_version) return false;
        out.api = api;
        return true;
      },
      &out.error);
  return out;
}

}  // namespace kanesim::dynamic_module
