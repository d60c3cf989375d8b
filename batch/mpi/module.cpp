// libkanesim_batch_mpi.so: the MPI calls of `kanesim sweep --mpi` (batch/mpi_module.h).
// The only code that includes <mpi.h>; loaded with dlopen when an MPI sweep starts.

// The C API only: OpenMPI's deprecated C++ bindings would need libmpi_cxx.
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>

#include <string>

#include "batch/mpi_module.h"

namespace kanesim::batch::mpi {
namespace {

void Init(int* rank, int* size) {
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (!initialized) MPI_Init(nullptr, nullptr);
  MPI_Comm_rank(MPI_COMM_WORLD, rank);
  MPI_Comm_size(MPI_COMM_WORLD, size);
}

void Finalize() { MPI_Finalize(); }

void Send(const char* data, int size, int dest, int tag) {
  MPI_Send(data, size, MPI_CHAR, dest, tag, MPI_COMM_WORLD);
}

// Probe for the size, then receive exactly that message.
void ReceiveFrom(std::string* data, int source, int tag, int* from, int* with_tag) {
  MPI_Status st;
  MPI_Probe(source, tag, MPI_COMM_WORLD, &st);
  int count = 0;
  MPI_Get_count(&st, MPI_CHAR, &count);
  data->assign(static_cast<size_t>(count), '\0');
  MPI_Recv(data->data(), count, MPI_CHAR, st.MPI_SOURCE, st.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  if (from) *from = st.MPI_SOURCE;
  if (with_tag) *with_tag = st.MPI_TAG;
}

void ReceiveAny(std::string* data, int* source, int* tag) {
  ReceiveFrom(data, MPI_ANY_SOURCE, MPI_ANY_TAG, source, tag);
}

void Receive(std::string* data, int source, int tag) { ReceiveFrom(data, source, tag, nullptr, nullptr); }

constexpr ModuleApi kApi{kAbiVersion, Init, Finalize, Send, ReceiveAny, Receive};

}  // namespace
}  // namespace kanesim::batch::mpi

extern "C" __attribute__((visibility("default"))) const kanesim::batch::mpi::ModuleApi* kanesim_batch_mpi_api() {
  return &kanesim::batch::mpi::kApi;
}
