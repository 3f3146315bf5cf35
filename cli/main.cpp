// The viewcells command line: a thin layer over the library (see commands.cpp).
#include "commands.h"

int main(int argc, char** argv) { return viewcells::cli::run(argc, argv); }
