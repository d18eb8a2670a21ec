/* Built by the MPI probe (CMakeLists.txt beside it); never run. */
#include <IceT.h>
#include <IceTMPI.h>
#include <mpi.h>

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  IceTCommunicator comm = icetCreateMPICommunicator(MPI_COMM_WORLD);
  icetDestroyMPICommunicator(comm);
  return MPI_Finalize();
}
