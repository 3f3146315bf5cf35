/// The ranks of a run on a cluster (MPI when built with it, else one process) and their
/// collectives.
#include "viewcells/core/ranks.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>

#include "viewcells/core/error.h"

#ifdef VIEWCELLS_MPI
#include <mpi.h>
#endif

namespace viewcells::ranks {

namespace {

int g_rank = 0, g_size = 1;
Traffic g_traffic;

#ifdef VIEWCELLS_MPI
bool g_mpi = false;

/// Started by an MPI launcher? (Open MPI's mpirun, PMI/PMIx launchers such as Slurm's srun.)
bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "SLURM_PROCID", "MPI_LOCALNRANKS"})
    if (std::getenv(v)) return true;
  return false;
}

void check(int rc, const char* what) {
  if (rc != MPI_SUCCESS) throw Error(std::string("MPI: ") + what + " failed");
}
#endif

}  // namespace

Session::Session(int* argc, char*** argv) {
#ifdef VIEWCELLS_MPI
  if (!launched_by_mpi()) return;
  int provided = 0;
  // Only the main thread calls MPI (between parallel stages).
  MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
  g_mpi = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &g_rank);
  MPI_Comm_size(MPI_COMM_WORLD, &g_size);
#else
  (void)argc, (void)argv;
  // Started by mpirun without MPI in this build: every process would run the whole command.
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
    if (const char* n = std::getenv(v); n && std::atoi(n) > 1) {
      std::fprintf(stderr,
                   "viewcells: warning: started as one of %s MPI processes, but built without MPI "
                   "(VIEWCELLS_MPI): each process runs the whole command\n",
                   n);
      break;
    }
#endif
}

Session::~Session() {
#ifdef VIEWCELLS_MPI
  if (g_mpi) MPI_Finalize();
#endif
}

void abort_all(int code) {
#ifdef VIEWCELLS_MPI
  if (g_mpi && g_size > 1) MPI_Abort(MPI_COMM_WORLD, code);
#else
  (void)code;
#endif
}

int rank() { return g_rank; }
int size() { return g_size; }
bool built_with_mpi() {
#ifdef VIEWCELLS_MPI
  return true;
#else
  return false;
#endif
}

const Traffic& traffic() { return g_traffic; }

void share(std::vector<std::string>& items, const std::function<int(size_t)>& owner) {
  if (g_size == 1) return;
#ifdef VIEWCELLS_MPI
  const auto start = std::chrono::steady_clock::now();
  // This rank's items, each as (length, bytes), in item order.
  std::string mine_bytes;
  for (uint64_t i = 0; i < items.size(); ++i) {
    if (owner(i) != g_rank) continue;
    const uint64_t n = items[i].size();
    mine_bytes.append(reinterpret_cast<const char*>(&n), sizeof n);
    mine_bytes += items[i];
  }
  if (mine_bytes.size() > static_cast<uint64_t>(INT32_MAX))
    throw Error("MPI: a rank's share of one round exceeds 2 GB; use smaller batches");
  const int len = static_cast<int>(mine_bytes.size());
  std::vector<int> lens(g_size), offsets(g_size);
  check(MPI_Allgather(&len, 1, MPI_INT, lens.data(), 1, MPI_INT, MPI_COMM_WORLD), "allgather of sizes");
  uint64_t total = 0;
  for (int r = 0; r < g_size; ++r) {
    if (total > static_cast<uint64_t>(INT32_MAX)) throw Error("MPI: one round exceeds 2 GB; use smaller batches");
    offsets[r] = static_cast<int>(total);
    total += static_cast<uint64_t>(lens[r]);
  }
  if (total > static_cast<uint64_t>(INT32_MAX)) throw Error("MPI: one round exceeds 2 GB; use smaller batches");
  std::string all(total, '\0');
  check(MPI_Allgatherv(mine_bytes.data(), len, MPI_BYTE, all.data(), lens.data(), offsets.data(), MPI_BYTE,
                       MPI_COMM_WORLD),
        "allgatherv");
  // One pass over the items, each read from its owner's data where that rank's last one ended.
  std::vector<uint64_t> pos(g_size);
  for (int r = 0; r < g_size; ++r) pos[r] = static_cast<uint64_t>(offsets[r]);
  for (uint64_t i = 0; i < items.size(); ++i) {
    const int r = owner(i);
    if (r == g_rank) continue;
    const uint64_t end = static_cast<uint64_t>(offsets[r]) + static_cast<uint64_t>(lens[r]);
    uint64_t n = 0;
    if (pos[r] + sizeof n > end) throw Error("MPI: a rank sent fewer items than it owns");
    std::memcpy(&n, all.data() + pos[r], sizeof n);
    pos[r] += sizeof n;
    if (n > end - pos[r]) throw Error("MPI: a rank's item runs past its data");
    items[i].assign(all.data() + pos[r], n);
    pos[r] += n;
  }
  g_traffic.calls += 1;
  g_traffic.bytes_sent += static_cast<uint64_t>(len);
  g_traffic.bytes_received += total - static_cast<uint64_t>(len);
  g_traffic.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
#endif
}

std::vector<std::string> exchange(std::vector<std::string> to) {
  if (to.size() != static_cast<size_t>(g_size)) throw Error("MPI: an exchange needs one message per rank");
  if (g_size == 1) return to;
#ifdef VIEWCELLS_MPI
  const auto start = std::chrono::steady_clock::now();
  std::vector<int> send_lens(g_size), send_offsets(g_size), recv_lens(g_size), recv_offsets(g_size);
  std::string send;
  for (int r = 0; r < g_size; ++r) {
    if (r == g_rank) continue;
    if (send.size() + to[r].size() > static_cast<uint64_t>(INT32_MAX))
      throw Error("MPI: a rank's share of one exchange exceeds 2 GB; use smaller batches");
    send_offsets[r] = static_cast<int>(send.size());
    send_lens[r] = static_cast<int>(to[r].size());
    send += to[r];
  }
  check(MPI_Alltoall(send_lens.data(), 1, MPI_INT, recv_lens.data(), 1, MPI_INT, MPI_COMM_WORLD), "alltoall of sizes");
  uint64_t total = 0;
  for (int r = 0; r < g_size; ++r) {
    recv_offsets[r] = static_cast<int>(total);
    total += static_cast<uint64_t>(recv_lens[r]);
    if (total > static_cast<uint64_t>(INT32_MAX)) throw Error("MPI: one exchange exceeds 2 GB; use smaller batches");
  }
  std::string recv(total, '\0');
  check(MPI_Alltoallv(send.data(), send_lens.data(), send_offsets.data(), MPI_BYTE, recv.data(), recv_lens.data(),
                      recv_offsets.data(), MPI_BYTE, MPI_COMM_WORLD),
        "alltoallv");
  std::vector<std::string> from(g_size);
  for (int r = 0; r < g_size; ++r)
    from[r] = r == g_rank ? std::move(to[r]) : recv.substr(static_cast<size_t>(recv_offsets[r]), recv_lens[r]);
  g_traffic.calls += 1;
  g_traffic.bytes_sent += send.size();
  g_traffic.bytes_received += total;
  g_traffic.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return from;
#else
  return to;
#endif
}

void share(std::vector<std::string>& items, uint64_t first) {
  const uint64_t n = static_cast<uint64_t>(g_size);
  share(items, [&](size_t i) { return static_cast<int>((first + i) % n); });
}

namespace {

#ifdef VIEWCELLS_MPI
template <class T>
void reduce(std::vector<T>& v, MPI_Datatype type, MPI_Op op) {
  if (g_size == 1 || v.empty()) return;
  const auto start = std::chrono::steady_clock::now();
  // In pieces of at most 2^30 elements (MPI counts are int).
  for (size_t at = 0; at < v.size(); at += size_t{1} << 30) {
    const int n = static_cast<int>(std::min(v.size() - at, size_t{1} << 30));
    check(MPI_Allreduce(MPI_IN_PLACE, v.data() + at, n, type, op, MPI_COMM_WORLD), "allreduce");
  }
  g_traffic.calls += 1;
  // What a ring allreduce moves per rank: about twice the vector.
  g_traffic.bytes_sent += 2 * v.size() * sizeof(T);
  g_traffic.bytes_received += 2 * v.size() * sizeof(T);
  g_traffic.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}
#endif

}  // namespace

#ifdef VIEWCELLS_MPI
void sum(std::vector<uint16_t>& v) { reduce(v, MPI_UINT16_T, MPI_SUM); }
void sum(std::vector<uint32_t>& v) { reduce(v, MPI_UINT32_T, MPI_SUM); }
void sum(std::vector<uint64_t>& v) { reduce(v, MPI_UINT64_T, MPI_SUM); }
void bit_or(std::vector<uint8_t>& v) { reduce(v, MPI_UINT8_T, MPI_BOR); }
void bit_or(std::vector<uint64_t>& v) { reduce(v, MPI_UINT64_T, MPI_BOR); }
bool agree(bool value) {
  if (g_size == 1) return value;
  int v = value ? 1 : 0;
  check(MPI_Bcast(&v, 1, MPI_INT, 0, MPI_COMM_WORLD), "broadcast");
  return v != 0;
}
#else
void sum(std::vector<uint16_t>&) {}
void sum(std::vector<uint32_t>&) {}
void sum(std::vector<uint64_t>&) {}
void bit_or(std::vector<uint8_t>&) {}
void bit_or(std::vector<uint64_t>&) {}
bool agree(bool value) { return value; }
#endif


}  // namespace viewcells::ranks
