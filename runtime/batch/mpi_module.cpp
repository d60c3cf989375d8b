#include "runtime/batch/mpi_module.h"

#include "runtime/util/dynamic_module.h"

namespace kanesim::batch::mpi {
namespace {

struct Loaded {
  const ModuleApi* api = nullptr;
  std::string error;
};

Loaded LoadOnce() {
  dynamic_module::Spec spec;
  spec.file_name = "libkanesim_batch_mpi.so";
  spec.env_variable = "KANESIM_MPI_MODULE";
#ifdef KANESIM_MPI_MODULE_PATH
  spec.build_path = KANESIM_MPI_MODULE_PATH;
#else
  spec.build_path = nullptr;
#endif
  spec.entry_point = kEntryPoint;
  spec.what = "kanesim's MPI library";
  // OpenMPI opens its own plugins with dlopen and they resolve symbols of libmpi, which
  // must therefore be visible to them (RTLD_GLOBAL).
  spec.global_symbols = true;
  Loaded out;
  dynamic_module::Open(
      spec,
      [&out](void* entry) {
        const ModuleApi* api = reinterpret_cast<EntryFunction>(entry)();
        if (!api || api->abi_version != kAbiVersion) return false;
        out.api = api;
        return true;
      },
      &out.error);
  return out;
}

}  // namespace

const ModuleApi* Module(std::string* error) {
  static const Loaded loaded = LoadOnce();  // thread-safe initialisation
  if (!loaded.api && error) *error = loaded.error;
  return loaded.api;
}

}  // namespace kanesim::batch::mpi
