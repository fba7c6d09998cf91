#!/bin/bash
# One frame of the 3D example (NX × NX/4 × NX/4 cells, one step of k = 1/64, one output) written
# whole by one process against in pieces by `mpirun -n 2` (a `.vtu` per rank and the `.pvtu`),
# RUNS interleaved pairs (docs/distributed.md, "Output: frames in pieces"): the frames' writer
# time (the slowest rank's), the output the run waited for, the files' sizes. Needs a release
# build with `--features mpi`; B= names another binary. Usage: bash docs/bench_frame.sh NX RUNS
# (972k unknowns: 156 3)
set -u
B=${B:-target/release/thermocontact}
NX=$1; NY=$((NX / 4)); RUNS=${2:-3}
DIR=$(mktemp -d)
S="$(dirname "$0")/../scenarios/paper3d.toml --set mesh.nx=$NX --set mesh.ny=$NY --set mesh.nz=$NY
   --set time.steps=1 --set time.final_time=0.015625 --set output.times=[0.015625]
   --set solver.linear=\"iterative\""
for _ in $(seq "$RUNS"); do
  rm -rf "$DIR"/one "$DIR"/ranks
  $B run $S --out "$DIR"/one --quiet > /dev/null 2>&1
  OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1 \
    mpirun --allow-run-as-root -n 2 $B run $S --out "$DIR"/ranks --quiet > /dev/null 2>&1
  for run in one ranks; do
    python3 - "$DIR/$run" "$run" <<'PY'
import glob, json, os, sys
folder, run = sys.argv[1:]
t = json.load(open(f"{folder}/summary.json"))["timings"]
files = sorted(glob.glob(f"{folder}/solution_0001*"))
sizes = " + ".join(f"{os.path.basename(f)} {os.path.getsize(f) / 1e6:.2f} MB" for f in files)
label = "1 process" if run == "one" else "2 ranks  "
print(f"{label}: frame {t['frames']:.2f} s (writer), output waited {t['output']:.2f} s; {sizes}")
PY
  done
done
rm -rf "$DIR"
