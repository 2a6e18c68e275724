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

echo "== merge (gesweep merge of 8 shards of studies/bench/modes.toml)"
for i in 0 1 2 3 4 5 6 7; do
  "$G" run studies/bench/modes.toml -o "$WORK/shard-$i.h5" --shard "$i/8" --threads 2 -q --force
done
rm -f "$WORK/merged.h5"
/usr/bin/time -f "%e %U %S" -o "$WORK/merge.time" "$G" merge "$WORK"/shard-{0,1,2,3,4,5,6,7}.h5 -o "$WORK/merged.h5"
read -r wall user sys < "$WORK/merge.time"
/usr/bin/python3 -c "
import sys
runs, wall, cpu, b = int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3]) + float(sys.argv[4]), int(sys.argv[5])
print(f'merge: {runs} runs, {b} B in {wall:.2f} s wall ({cpu:.2f} s cpu): {runs/wall:.0f} runs/s, {b/wall/1e6:.1f} MB/s')" \
  "$(runs_of "$WORK/merged.h5")" "$wall" "$user" "$sys" "$(stat -c %s "$WORK/merged.h5")"
for i in 0 1 2 3 4 5 6 7; do "$G" run tests/mpi/scaling/open_loop_series.toml -o "$WORK/sshard-$i.h5" --shard "$i/8" --threads 2 -q --force; done
rm -f "$WORK/smerged.h5"
/usr/bin/time -f "%e %U %S" -o "$WORK/smerge.time" "$G" merge "$WORK"/sshard-{0,1,2,3,4,5,6,7}.h5 -o "$WORK/smerged.h5"
read -r wall user sys < "$WORK/smerge.time"
/usr/bin/python3 -c "
import sys
runs, wall, cpu, b = int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3]) + float(sys.argv[4]), int(sys.argv[5])
print(f'merge (series): {runs} runs, {b} B in {wall:.2f} s wall ({cpu:.2f} s cpu): {runs/wall:.0f} runs/s, {b/wall/1e6:.1f} MB/s')" \
  "$(runs_of "$WORK/smerged.h5")" "$wall" "$user" "$sys" "$(stat -c %s "$WORK/smerged.h5")"

if [ -x "$DRIVER" ]; then
  echo "== MPI runner, rank 0 writes (studies/bench/modes.toml, 1 thread per rank)"
  for n in 1 2 3; do
    rm -f "$WORK/mpi-$n.h5"
    /usr/bin/time -f "%e %U %S" -o "$WORK/mpi-$n.time" mpirun --allow-run-as-root --oversubscribe -n "$n" \
      "$DRIVER" studies/bench/modes.toml -o "$WORK/mpi-$n.h5" --threads 1 2>&1 | grep "runs in" || true
    echo "  -n $n: wall/user/sys $(cat "$WORK/mpi-$n.time")"
  done
  /usr/bin/python3 tests/slurm/compare_archives.py "$WORK/modes.h5" "$WORK/mpi-3.h5"
fi
echo "work dir: $WORK"
