// The boundary between kanesim_runtime (no MPI) and the MPI module libkanesim_batch_mpi.so
// (OpenMPI), which `sweep --mpi` loads with dlopen (RunSweepMpi, sweep_mpi.cpp): a kanesim
// that never runs an MPI sweep never maps libmpi and the libraries it brings (docs/sweeps.md,
// "MPI"; the start-up times in docs/benchmarks.md).
//
// The module only moves bytes between ranks; the manager/worker protocol stays in
// sweep_mpi.cpp. Both sides are built together by this project's CMake, so the table of
// functions crosses the boundary as a C++ struct; kAbiVersion guards against a stale module.
#pragma once

#include <string>

namespace kanesim::batch::mpi {

inline constexpr int kAbiVersion = 1;

struct ModuleApi {
  int abi_version;
  // MPI_Init unless already initialized; this process's rank and the number of ranks in
  // MPI_COMM_WORLD.
  void (*init)(int* rank, int* size);
  void (*finalize)();
  // Blocking send of `size` bytes to rank `dest` with `tag`.
  void (*send)(const char* data, int size, int dest, int tag);
  // Blocking receive of the next message from any rank with any tag: its bytes, sender, tag.
  void (*receive_any)(std::string* data, int* source, int* tag);
  // Blocking receive of the next message from `source` with `tag`.
  void (*receive)(std::string* data, int source, int tag);
};

// The entry point the module exports (extern "C" so that dlsym finds it by this name).
inline constexpr const char* kEntryPoint = "kanesim_batch_mpi_api";
using EntryFunction = const ModuleApi* (*)();

// The module, loaded once per process (thread-safe). Null with *error set when it cannot be
// found or is stale. Where: $KANESIM_MPI_MODULE when set (and nowhere else), otherwise the
// directory of the running executable, then the build tree's copy.
const ModuleApi* Module(std::string* error);

}  // namespace kanesim::batch::mpi
