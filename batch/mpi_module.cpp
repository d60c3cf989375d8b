#include "batch/mpi_module.h"

#include "util/dynamic_module.h"

namespace kanesim::batch::mpi {

#ifdef KANESIM_MPI_MODULE_PATH
static constexpr const char* kBuildPath = KANESIM_MPI_MODULE_PATH;
#else
static constexpr const char* kBuildPath = nullptr;
#endif

const ModuleApi* Module(std::string* error) {
  // global_symbols: OpenMPI opens its own plugins with dlopen and they resolve symbols of
  // libmpi, which must therefore be visible to them (RTLD_GLOBAL).
  static const auto loaded = dynamic_module::LoadTable<ModuleApi>(  // once per process, thread-safe
      {"libkanesim_batch_mpi.so", "KANESIM_MPI_MODULE", kBuildPath, kEntryPoint, "kanesim's MPI library", true}, kAbiVersion);
  if (!loaded.api && error) *error = loaded.error;
  return loaded.api;
}

}  // namespace kanesim::batch::mpi
