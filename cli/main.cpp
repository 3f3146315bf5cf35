// The viewcells command line: a thin layer over the library (see commands.cpp).
#include "commands.h"

#include <iostream>

#include "viewcells/core/cluster.h"

int main(int argc, char** argv) {
  // Under mpirun or srun (with VIEWCELLS_MPI), every rank runs the same command; rank 0 writes
  // the files and the output.
  viewcells::cluster::Session session(&argc, &argv);
  if (!viewcells::cluster::writer()) std::cout.setstate(std::ios::failbit);
  return viewcells::cli::run(argc, argv);
}
