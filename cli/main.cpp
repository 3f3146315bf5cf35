// The viewcells command line: a thin layer over the library (see commands.cpp).
#include "commands.h"

#include <iostream>

#include "viewcells/core/ranks.h"
#include "viewcells/core/interrupt.h"

int main(int argc, char** argv) {
  // Under mpirun or srun (with VIEWCELLS_MPI), every rank runs the same command; rank 0 writes
  // the files and the output.
  viewcells::ranks::Session session(&argc, &argv);
  if (!viewcells::ranks::writer()) std::cout.setstate(std::ios::failbit);
  // Ctrl-C ends a long stage with an error and leaves the outputs as they were. On several
  // ranks mpirun or srun stop them all: one rank leaving a collective alone would hang the rest.
  if (viewcells::ranks::size() == 1) viewcells::install_interrupt_handlers();
  const int rc = viewcells::cli::run(argc, argv);
  // An error on one rank (a corrupt message, say) would leave the others waiting in a
  // collective, and MPI_Finalize with them: end them all.
  if (rc != 0 && viewcells::ranks::size() > 1) viewcells::ranks::abort_all(rc);
  return rc;
}
