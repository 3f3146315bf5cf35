#pragma once
/// The ranks of one run: the processes on a cluster of machines (MPI ranks, when built with
/// VIEWCELLS_MPI and started by mpirun or srun), and the few collective operations the stages
/// need. Without MPI, or when not started by an MPI launcher, there is one process and every
/// operation is local. No MPI type appears here.
///
/// Every rank runs the same pipeline on the same data; the parallel stages split their work
/// into items with a fixed numbering that does not depend on the number of ranks (sampling
/// batches, casting chunks), each rank computes the items it owns, and share() gives every
/// rank all results in item order. What follows is then the same on every rank and the same
/// as in one process: results are identical, byte for byte, for any number of ranks. Only
/// rank 0 writes files and prints.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace viewcells::ranks {

/// While alive, the process is part of the run's ranks: initialises MPI when viewcells was
/// built with it and an MPI launcher started the process (mpirun, srun), finalises it after.
/// One per process, in main().
class Session {
 public:
  Session(int* argc, char*** argv);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;
};

/// Ends every rank of the run with `code` (MPI_Abort): after an error on one rank, which would
/// otherwise leave the others waiting in a collective. Returns only in one process.
void abort_all(int code);
int rank();  ///< 0 .. size() - 1
int size();
inline bool writer() { return rank() == 0; }
/// Whether this build can run on several ranks (VIEWCELLS_MPI).
bool built_with_mpi();

/// Item i of a fixed numbering belongs to rank i mod size().
inline bool mine(uint64_t item) { return static_cast<int>(item % static_cast<uint64_t>(size())) == rank(); }

/// items[i] holds the serialised result (core/binary_file.h's ByteWriter) of item first + i where mine(first + i); afterwards
/// every rank holds all of them. Collective: every rank calls it with the same arguments.
void share(std::vector<std::string>& items, uint64_t first = 0);
/// As above, with item i belonging to rank owner(i) (the same function on every rank).
void share(std::vector<std::string>& items, const std::function<int(size_t)>& owner);

/// All-to-all: to[r] is what this rank sends rank r (to[rank()] stays here); returns from[r],
/// what rank r sent this one. Collective: every rank calls it with size() entries.
std::vector<std::string> exchange(std::vector<std::string> to);
/// Element-wise sums and bitwise ors over all ranks, in place (every rank gets the result).
/// Collective: every rank calls them with vectors of the same length.
void sum(std::vector<uint16_t>& v);
void sum(std::vector<uint32_t>& v);
void sum(std::vector<uint64_t>& v);
void bit_or(std::vector<uint8_t>& v);
void bit_or(std::vector<uint64_t>& v);
/// Rank 0's `value` on every rank: decisions that depend on a clock (stop after S seconds,
/// write a checkpoint now) are rank 0's, so that every rank takes them at the same batch.
bool agree(bool value);

/// What the collective operations have cost this rank so far.
struct Traffic {
  uint64_t calls = 0;
  uint64_t bytes_sent = 0;      ///< this rank's own results, sent to the others
  uint64_t bytes_received = 0;  ///< the others' results
  double seconds = 0;           ///< waiting in collectives (imbalance included)
};
const Traffic& traffic();

}  // namespace viewcells::ranks
