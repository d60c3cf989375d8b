#include "runtime/batch/mpi_module.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <vector>

namespace kanesim::batch::mpi {
namespace {

constexpr const char* kFileName = "libkanesim_batch_mpi.so";

struct Loaded {
  const ModuleApi* api = nullptr;
  std::string error;
};

std::vector<std::string> Candidates() {
  if (const char* env = std::getenv("KANESIM_MPI_MODULE"); env && *env) return {env};
  std::vector<std::string> paths;
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) paths.push_back((exe.parent_path() / kFileName).string());
#ifdef KANESIM_MPI_MODULE_PATH
  paths.emplace_back(KANESIM_MPI_MODULE_PATH);
#endif
  return paths;
}

Loaded LoadOnce() {
  Loaded out;
  std::string tried;
  for (const std::string& path : Candidates()) {
    if (!std::filesystem::exists(path)) {
      tried += "\n  " + path + " (absent)";
      continue;
    }
    // RTLD_GLOBAL: OpenMPI opens its own plugins with dlopen and they resolve symbols of
    // libmpi, which must therefore be visible to them.
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_GLOBAL);
    if (!handle) {
      tried += "\n  " + path + " (" + dlerror() + ")";
      continue;
    }
    auto entry = reinterpret_cast<EntryFunction>(dlsym(handle, kEntryPoint));
    const ModuleApi* api = entry ? entry() : nullptr;
    if (!api || api->abi_version != kAbiVersion) {
      tried += "\n  " + path + " (stale or not kanesim's MPI module)";
      dlclose(handle);
      continue;
    }
    out.api = api;  // the handle stays open for the life of the process
    return out;
  }
  out.error = std::string("cannot load kanesim's MPI library ") + kFileName + "; tried:" + tried;
  return out;
}

}  // namespace

const ModuleApi* Module(std::string* error) {
  static const Loaded loaded = LoadOnce();  // thread-safe initialisation
  if (!loaded.api && error) *error = loaded.error;
  return loaded.api;
}

}  // namespace kanesim::batch::mpi
