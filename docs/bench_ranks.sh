#!/bin/bash
# The 3D example (NX × NX/4 × NX/4 cells, STEPS steps of k = 1/64) on the iterative path: one
# threaded process against `mpirun -n 2` with one thread per rank, two interleaved pairs
# (docs/distributed.md, "Measured"), and for each pair the parallel efficiency and the memory
# ratio. Needs a release build with `--features mpi`; B= names another binary.
# Usage: bash docs/bench_ranks.sh NX STEPS   (98k: 72 8; 972k: 156 2)
set -u
B=${B:-target/release/thermocontact}
NX=$1; NY=$((NX / 4)); ST=$2; T=$(python3 -c "print($ST / 64)")
DIR=$(mktemp -d)
S="$(dirname "$0")/../scenarios/paper3d.toml --set mesh.nx=$NX --set mesh.ny=$NY --set mesh.nz=$NY
   --set time.steps=$ST --set time.final_time=$T --set output.times=[$T] --set output.vtk=false
   --set solver.linear=\"iterative\""
for _ in 1 2; do
  rm -rf "$DIR"/one "$DIR"/ranks
  /usr/bin/time -f "%e %M" -o "$DIR"/one.time $B run $S --out "$DIR"/one --quiet > /dev/null 2>&1
  OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1 /usr/bin/time -f "%e %M" -o "$DIR"/ranks.time \
    mpirun --allow-run-as-root -n 2 $B run $S --out "$DIR"/ranks --quiet > /dev/null 2>&1
  for run in one ranks; do
    python3 - "$DIR" "$run" "$NX" <<'PY'
import json, sys
folder, run, nx = sys.argv[1:]
s = json.load(open(f"{folder}/{run}/summary.json"))
t = s["timings"]
wall, rss = open(f"{folder}/{run}.time").read().split()[-2:]
label = "1 process" if run == "one" else "2 ranks  "
print(f"nx={nx} {label} set-up {t['assembly'] + t['factorization']:.2f} s, "
      f"per step {t['time_stepping'] / s['steps']:.2f} s, solves {t['linear_solves']:.2f} s, "
      f"Newton {s['newton_iterations']}, Krylov {s['krylov_iterations']}, wall {wall} s, "
      f"peak RSS {int(rss) // 1024} MiB")
PY
  done
  python3 - "$DIR" <<'PY'
import json, sys
folder = sys.argv[1]
step = {r: (lambda s: s["timings"]["time_stepping"] / s["steps"])(json.load(open(f"{folder}/{r}/summary.json")))
        for r in ("one", "ranks")}
rss = {r: int(open(f"{folder}/{r}.time").read().split()[-1]) for r in ("one", "ranks")}
print(f"  pair: parallel efficiency {step['one'] / step['ranks']:.2f} (1 process's time per step over the "
      f"2 ranks'), memory per rank {rss['ranks'] / rss['one']:.2f} of the 1 process's")
PY
done
rm -rf "$DIR"
