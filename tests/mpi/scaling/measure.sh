#!/bin/bash
# Measurements behind docs/scaling.md. Usage: tests/mpi/scaling/measure.sh [BUILD_DIR] [WORK_DIR]
# Prints, per study: runs, wall s, CPU s (user+sys), CPU us per run, runs/s per core (runs / CPU s),
# archive bytes and bytes per run; then merge throughput and the MPI runner against one process.
# CPU time rather than wall time: per-core rates that hold on a shared machine.
set -euo pipefail
cd "$(dirname "$0")/../../.."
BUILD=${1:-build}
WORK=${2:-$(mktemp -d /tmp/gesweep-scaling.XXXXXX)}
G=$BUILD/gesweep
DRIVER=$BUILD/tests/mpi/mpi_runner_driver
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl_vader_single_copy_mechanism=none
mkdir -p "$WORK"

runs_of() { /usr/bin/python3 -c "import h5py,sys; print(h5py.File(sys.argv[1],'r')['runs/status'].shape[0])" "$1"; }

measure() {  # label study threads
  local label=$1 study=$2 threads=$3 out=$WORK/$1.h5
  rm -f "$out"
  /usr/bin/time -f "%e %U %S" -o "$WORK/$label.time" "$G" run "$study" -o "$out" --threads "$threads" -q || true
  read -r wall user sys < "$WORK/$label.time"
  local runs bytes
  runs=$(runs_of "$out"); bytes=$(stat -c %s "$out")
  /usr/bin/python3 -c "
import sys
label, runs, wall, user, sys_, bytes_ = sys.argv[1], int(sys.argv[2]), *map(float, sys.argv[3:6]), int(sys.argv[6])
cpu = user + sys_
print(f'{label:24s} {runs:8d} runs  wall {wall:7.2f} s  cpu {cpu:7.2f} s  {1e6*cpu/runs:9.1f} us/run  '
      f'{runs/cpu:9.1f} runs/s/core  {bytes_:11d} B  {bytes_/runs:9.1f} B/run')" \
    "$label" "$runs" "$wall" "$user" "$sys" "$bytes"
}

echo "== per analysis, 1 compute thread (gesweep run STUDY -o OUT --threads 1 -q)"
measure modes            studies/bench/modes.toml 1
measure boundary         tests/slurm/requeue_study.toml 1
measure modes_open_loop  studies/bench/modes_open_loop.toml 1
measure open_loop_sum    tests/mpi/scaling/open_loop_summary.toml 1
measure open_loop_series tests/mpi/scaling/open_loop_series.toml 1
measure landing          studies/bench/landing.toml 1

merge_measure() {  # label shard-prefix [--copy]
  local label=$1 prefix=$2; shift 2
  rm -f "$WORK/$label.h5"
  /usr/bin/time -f "%e %U %S" -o "$WORK/$label.time" "$G" merge "$WORK/$prefix"-{0,1,2,3,4,5,6,7}.h5 -o "$WORK/$label.h5" -q "$@"
  read -r wall user sys < "$WORK/$label.time"
  /usr/bin/python3 -c "
import sys
label, runs, wall, cpu, b, shards = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4]) + float(sys.argv[5]), int(sys.argv[6]), int(sys.argv[7])
print(f'{label}: {runs} runs, {shards} B of shards -> {b} B in {wall:.3f} s wall ({cpu:.3f} s cpu): '
      f'{shards/wall/1e6:.0f} MB/s wall, {shards/max(cpu, 1e-9)/1e6:.0f} MB per CPU-second')" \
    "$label" "$(runs_of "$WORK/$label.h5")" "$wall" "$user" "$sys" "$(stat -c %s "$WORK/$label.h5")" \
    "$(du -cb "$WORK/$prefix"-*.h5 | tail -1 | cut -f1)"
}

echo "== merge (gesweep merge of 8 shards: virtual, the default, and --copy)"
for i in 0 1 2 3 4 5 6 7; do
  "$G" run studies/bench/modes.toml -o "$WORK/shard-$i.h5" --shard "$i/8" --threads 2 -q --force
  "$G" run tests/mpi/scaling/open_loop_series.toml -o "$WORK/sshard-$i.h5" --shard "$i/8" --threads 2 -q --force
done
merge_measure merge_virtual shard
merge_measure merge_copy shard --copy
merge_measure merge_series_virtual sshard
merge_measure merge_series_copy sshard --copy

if [ -x "$DRIVER" ]; then
  echo "== MPI (studies/bench/modes.toml, 1 thread per rank, 2 ranks per node: one writer each)"
  for n in 1 2 4; do
    rm -f "$WORK"/mpi-$n*.h5
    /usr/bin/time -f "%e %U %S" -o "$WORK/mpi-$n.time" mpirun --allow-run-as-root --oversubscribe -n "$n" \
      -x GESWEEP_RANKS_PER_NODE=2 "$DRIVER" studies/bench/modes.toml -o "$WORK/mpi-$n.h5" --threads 1 2>&1 || true
    echo "  -n $n: wall/user/sys $(cat "$WORK/mpi-$n.time")"
  done
  /usr/bin/python3 tests/slurm/compare_archives.py "$WORK/modes.h5" "$WORK/mpi-4.h5"
  echo "== writer-bound: 1,000,000 near-free runs, one process and mpirun -n 4 as 2 nodes"
  measure writer_bound tests/mpi/scaling/writer_bound.toml 1
  rm -f "$WORK"/wb-mpi*.h5
  /usr/bin/time -f "%e %U %S" -o "$WORK/wb-mpi.time" mpirun --allow-run-as-root --oversubscribe -n 4 \
    -x GESWEEP_RANKS_PER_NODE=2 "$DRIVER" tests/mpi/scaling/writer_bound.toml -o "$WORK/wb-mpi.h5" --threads 1 -q || true
  echo "  mpirun -n 4 as 2 nodes: wall/user/sys $(cat "$WORK/wb-mpi.time")"
fi
echo "work dir: $WORK"
