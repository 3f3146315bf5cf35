# MPI (issue: bakes that outgrow one machine): what the ranks exchange and where the time goes,
# with 1, 2 and 4 ranks of one thread each on this machine (4 ranks oversubscribe its 2 cores:
# their compute is not faster, their traffic is what it is), and one rank of two threads, for AGVS
# (`pvs`, 1M samples in batches of 20,000, seed 1, 2,048 mutation lanes, and one lane on one rank
# for comparison) on the city of size 23 cut into 500 and 5,000 view cells, and for segment
# sampling (`sample`, 2M samples), three rounds of each. Then the strong-scaling model of docs/distributed.md from
# those measurements. Prints JSON lines and Markdown tables.
# Usage: scripts/bench.sh mpi
bench_cmake_args="-DVIEWCELLS_MPI=ON"
source scripts/bench-setup.sh
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
scene=$(bench_scene city 23)
out="$dir/mpi"
mkdir -p "$out"
level=$(bench_city_cells 1000000 5000)
lines="$out/runs.jsonl"
: >"$lines"
lanes=2048
# pvs_run RANKS THREADS CELLS NAME [LANES]: one AGVS run, its line in runs.jsonl.
pvs_run() {
  local n_lanes=${5:-$lanes}
  mpirun --oversubscribe --bind-to none -np "$1" "$vc" --threads "$2" -q pvs "$level" --scene "$scene" --cells "$3" \
    --samples 1000000 --batch 20000 --seed 1 --mutation-lanes "$n_lanes" -o "$out/$4.pvs" --report "$out/$4.json"
  jq -c --arg kind pvs --argjson cells "$3" --argjson ranks "$1" --argjson threads "$2" --argjson lanes "$n_lanes" '{kind:
    $kind, cells: $cells, lanes: $lanes, ranks: $ranks, threads: $threads, samples: .samples, seconds: .seconds,
    phases: .phases, cluster: (.cluster // {exchanges: 0, bytes_sent: 0, bytes_received: 0, exchange_seconds: 0})}' \
    "$out/$4.json" | tee -a "$lines"
}
# One lane (the default), and one rank of two threads: what drawing, the lanes and applying
# divide over a node's cores. (Ranks are not bound to cores: mpirun binds one or two ranks to one
# core each by default, and a rank's threads would then share it.) Three rounds of every
# configuration, one after another, so that a slow minute of this machine touches all of them;
# the model takes each configuration's medians.
rounds=${BENCH_MPI_ROUNDS:-3}
for round in $(seq "$rounds"); do
  for cells in 500 5000; do
    pvs_run 1 1 "$cells" "pvs-$cells-lane" 1
    pvs_run 1 2 "$cells" "pvs-$cells-1t2"
  done
  for n in 1 2 4; do
    for cells in 500 5000; do pvs_run "$n" 1 "$cells" "pvs-$cells-$n"; done
    mpirun --oversubscribe --bind-to none -np "$n" "$vc" --threads 1 -q sample "$scene" --samples 2000000 --seed 1 \
      -o "$out/s-$n.vseg" --report "$out/sample-$n.json"
    jq -c --arg kind sample --argjson ranks "$n" '{kind: $kind, ranks: $ranks, samples: .counts.samples,
      seconds: .timings.sampling_seconds, segments: .counts.valid_segments, cluster: (.cluster // {exchanges: 0,
      bytes_sent: 0, bytes_received: 0, exchange_seconds: 0})}' "$out/sample-$n.json" | tee -a "$lines"
  done
  echo "bench-mpi: round $round of $rounds done" >&2
done
for n in 2 4; do
  cmp -s "$out/s-1.vseg" "$out/s-$n.vseg" || { echo "bench-mpi: $n ranks sampled another file" >&2; exit 1; }
  for cells in 500 5000; do
    cmp -s "$out/pvs-$cells-1.pvs" "$out/pvs-$cells-$n.pvs" || { echo "bench-mpi: $n ranks: another .pvs" >&2; exit 1; }
    cmp -s "$out/pvs-$cells-1.pvs" "$out/pvs-$cells-1t2.pvs" || { echo "bench-mpi: 2 threads: another .pvs" >&2; exit 1; }
  done
done
python3 scripts/vctables.py mpi-model "$lines" | tee "$out/tables.md"
python3 scripts/vctables.py replace-section docs/distributed.md mpi "scripts/bench.sh mpi" "$out/tables.md"
