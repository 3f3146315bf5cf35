#!/usr/bin/env bash
# viewcells on several MPI ranks (a VIEWCELLS_MPI build): `sample`, `pvs`, `bake` and `compare`
# under mpirun with 2 and 3 ranks (oversubscribed; `sample` also on 1) write the same files, byte
# for byte, as one process without mpirun, and the same report numbers (timings and the ranks'
# traffic aside).
# Then a rank of a checkpointing `pvs` run is killed: the run ends with an error (no hang, no
# output), and resuming from its last checkpoint on another number of ranks finishes with the
# file an uninterrupted run writes.
# Usage: mpi_test.sh VIEWCELLS_BINARY
set -uo pipefail
VC="$1"
MAPS="$(cd "$(dirname "$0")/../../data/maps/bsp" 2>/dev/null && pwd)"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none  # containers without ptrace permission
# One node's transports only: probing for others (UCX) took 0.2 s of each launch's 0.7 s, and
# this test launches mpirun 17 times.
export OMPI_MCA_pml=ob1 OMPI_MCA_btl=self,vader
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1
passed=0 failed=0
ok() { passed=$((passed + 1)); }
bad() { echo "FAIL: $*"; failed=$((failed + 1)); }
# One thread a rank, not bound to a core: the ranks share the machine's cores with each other and
# with the tests that run beside this one (mpirun binds each of one or two ranks to a core).
ranks() { local n=$1; shift; timeout 300 mpirun --oversubscribe --bind-to none -np "$n" "$VC" "$@" --threads 1; }
# A report without what may differ between runs: timings, rates, thread and rank counts (and the
# per-rank phases, one entry a rank).
numbers() {
  jq -S 'del(.cluster, .phases.per_rank) | walk(if type == "object" then with_entries(select(.key | test("seconds|per_second|time|threads|^output$|^report$") | not)) else . end)' "$1"
}
same_files() {  # WHAT A B
  if cmp -s "$2" "$3"; then ok; else bad "$1: $2 and $3 differ"; fi
}
same_numbers() {  # WHAT A B
  if diff <(numbers "$2") <(numbers "$3") >/dev/null; then ok; else bad "$1: report numbers of $2 and $3 differ: $(diff <(numbers "$2") <(numbers "$3") | head -5)"; fi
}

"$VC" -q generate office --size 1 -o office.obj || exit 1
"$VC" -q build office.obj --samples 30000 --max-cells 60 --merge-pvs samples -o office.vcells || exit 1

# One process, no MPI launcher: the reference.
# 70,000 samples: 69 batches, two rounds of sharing; the second starts at batch 64, which on
# three ranks is not rank 0's (a sampler that shared it as if it were failed there).
"$VC" -q sample office.obj --samples 70000 -o s0.vseg --report s0.json || bad "sample"
"$VC" -q pvs office.vcells --scene office.obj --cells 12 --samples 50000 --batch 5000 -o p0.pvs --report p0.json || bad "pvs"
"$VC" -q bake office.obj --cells 8 --samples 20000 --max-cells 40 --merge-samples 20000 --agvs-samples 30000 \
  -o b0.pvs --report b0.json || bad "bake"
"$VC" -q compare office.obj --methods av-s,kd-casm --max-cells 24 --samples 20000 --eval-samples 30000 -o c0 \
  || bad "compare"
for n in 1 2 3; do
  ranks "$n" -q sample office.obj --samples 70000 -o "s$n.vseg" --report "s$n.json" || bad "sample on $n ranks"
  same_files "sample, $n ranks" s0.vseg "s$n.vseg"
  same_numbers "sample, $n ranks" s0.json "s$n.json"
  # On one rank every collective returns at once: the sample above covers starting and stopping
  # under mpirun, and the commands below run as in one process.
  [ "$n" -gt 1 ] || continue
  ranks "$n" -q pvs office.vcells --scene office.obj --cells 12 --samples 50000 --batch 5000 -o "p$n.pvs" \
    --report "p$n.json" || bad "pvs on $n ranks"
  same_files "pvs, $n ranks" p0.pvs "p$n.pvs"
  same_numbers "pvs, $n ranks" p0.json "p$n.json"
  ranks "$n" -q bake office.obj --cells 8 --samples 20000 --max-cells 40 --merge-samples 20000 --agvs-samples 30000 \
    -o "b$n.pvs" --report "b$n.json" || bad "bake on $n ranks"
  same_files "bake, $n ranks" b0.pvs "b$n.pvs"
  ranks "$n" -q compare office.obj --methods av-s,kd-casm --max-cells 24 --samples 20000 --eval-samples 30000 \
    -o "c$n" || bad "compare on $n ranks"
  for f in c0/*.csv; do same_files "compare, $n ranks" "$f" "c$n/$(basename "$f")"; done
done
# REF and SGVS, the visibility filter's densities (partitioned with the cells, then combined),
# AGVS's mutation lanes (each drawn and fed by its own rank, combined at the end), and stopping
# on a measured error (every rank measures the same table and stops at the same batch).
# (Lanes also run on the city below, and in the killed and resumed run.)
for extra in "--method ref" "--method sgvs" "--filter --mutation-lanes 5" \
  "--measure-cameras 64 --measure-size 64 --measured-error 1 --mutation-lanes 9"; do
  # shellcheck disable=SC2086
  "$VC" -q pvs office.vcells --scene office.obj --cells 12 --samples 30000 --batch 5000 $extra -o x0.pvs || bad "pvs $extra"
  # shellcheck disable=SC2086
  ranks 3 -q pvs office.vcells --scene office.obj --cells 12 --samples 30000 --batch 5000 $extra -o x3.pvs ||
    bad "pvs $extra on 3 ranks"
  same_files "pvs $extra, 3 ranks" x0.pvs x3.pvs
done
# Mutation lanes on a scene of closed solids: a sample whose origin is inside one is re-cast after
# the chunk's other samples, so a chunk's bounds order its segments. Lanes dealt to the ranks
# must not move those bounds (this failed when a rank's lanes were cast as one run).
"$VC" -q generate city --size 3 -o city.obj || exit 1
"$VC" -q build city.obj --samples 30000 --max-cells 60 --merge-pvs samples -o city.vcells || exit 1
"$VC" -q pvs city.vcells --scene city.obj --cells 40 --samples 100000 --batch 20000 --mutation-lanes 100 \
  -o l0.pvs || bad "pvs with lanes on the city"
for n in 2 3; do
  ranks "$n" -q pvs city.vcells --scene city.obj --cells 40 --samples 100000 --batch 20000 --mutation-lanes 100 \
    -o "l$n.pvs" || bad "pvs with lanes on the city on $n ranks"
  same_files "pvs with lanes on the city, $n ranks" l0.pvs "l$n.pvs"
done
# A map's play space: the stationary distributions' chunks are Halton index ranges whose points
# outside it are skipped, each drawn only by the rank that casts it.
if [ -n "$MAPS" ] && [ -f "$MAPS/oa_dm2.bsp" ]; then
  "$VC" -q bake "$MAPS/oa_dm2.bsp" --cells 20 --samples 20000 --max-cells 40 --merge-pvs samples --agvs-samples 60000 \
    --near-samples 0 --mutation-lanes 3 -o m0.pvs || bad "bake on a map"
  ranks 3 -q bake "$MAPS/oa_dm2.bsp" --cells 20 --samples 20000 --max-cells 40 --merge-pvs samples --agvs-samples 60000 \
    --near-samples 0 --mutation-lanes 3 -o m3.pvs || bad "bake on a map on 3 ranks"
  same_files "bake on a map, 3 ranks" m0.pvs m3.pvs
else
  echo "mpi_test: no maps (scripts/fetch-maps.sh): the play space case is skipped"
fi
[ "$(jq -r .cluster.ranks s3.json)" = 3 ] && [ "$(jq -r .cluster.bytes_received s3.json)" -gt 0 ] && ok ||
  bad "the report of 3 ranks does not say what they exchanged: $(jq -c .cluster s3.json)"

# A rank killed in the middle of a checkpointing run (with mutation lanes: the checkpoint holds
# every rank's).
lanes="--mutation-lanes 5"
# shellcheck disable=SC2086
ranks 3 -q pvs office.vcells --scene office.obj --cells 12 --samples 1000000 --batch 5000 $lanes --save state.vagvs \
  --save-every 0.2 -o killed.pvs >/dev/null 2>killed.err &
run=$!
for _ in $(seq 600); do [ -s state.vagvs ] && break; sleep 0.1; done
[ -s state.vagvs ] && ok || bad "no checkpoint within 60 s"
victim=$(pgrep -f "^$VC -q pvs .*killed.pvs" | tail -1)
if [ -n "$victim" ]; then kill -9 "$victim"; else bad "no rank to kill (finished already?)"; fi
wait "$run"
rc=$?
[ "$rc" -ne 0 ] && [ "$rc" -ne 124 ] && ok || bad "the run with a killed rank ended with $rc (124: it hung)"
[ ! -e killed.pvs ] && ok || bad "the run with a killed rank wrote its output"
grep -q "killed\|signal 9" killed.err && ok || bad "mpirun did not say a rank was killed: $(head -c 300 killed.err)"
# The checkpoint was taken in the middle of the run.
# shellcheck disable=SC2086
saved=$("$VC" pvs office.vcells --scene office.obj --cells 12 --samples 1 --batch 5000 $lanes \
          --resume state.vagvs -o probe.pvs --report probe.json -q && jq -r .samples probe.json)
[ "${saved:-0}" -gt 0 ] && [ "${saved:-0}" -lt 1000000 ] && ok || bad "the checkpoint holds ${saved:-?} samples"
echo "mpi_test: killed a rank; the checkpoint held $saved of 1,000,000 samples"
cp state.vagvs state-copy.vagvs
# Resumed on 2 ranks: 3 oversubscribed ranks take 6 s of CPU for this run, 2 take 3.6 s.
# shellcheck disable=SC2086
ranks 2 -q pvs office.vcells --scene office.obj --cells 12 --samples 1000000 --batch 5000 $lanes \
  --resume state-copy.vagvs -o resumed.pvs || bad "resume on 2 ranks"
# shellcheck disable=SC2086
"$VC" -q pvs office.vcells --scene office.obj --cells 12 --samples 1000000 --batch 5000 $lanes -o full.pvs ||
  bad "full run"
same_files "resumed on 2 ranks after a kill on 3" full.pvs resumed.pvs

echo "mpi_test: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
