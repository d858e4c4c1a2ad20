#!/bin/sh
# DEM speed comparison with LIGGGHTS 3.8 (Debian package `liggghts`; skipped where absent).
# Prints LIGGGHTS' particle-steps/s on 1 and 2 MPI ranks for tube_bank.in; compare with
# `cargo run --release -- bench --dem`, which runs the same case in partlife.
# LIGGGHTS is a peer for the comparison only: none of its code is in this repository.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
if ! command -v liggghts >/dev/null 2>&1; then
    echo "liggghts not installed (apt-get install liggghts openmpi-bin): skipped"
    exit 0
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
report() {
    # "Loop time of T on P procs for S steps with N atoms": the fill run ends with N0 atoms, the
    # timed (last) run with N1; particle-steps/s = S (N0 + N1)/2 / T (partlife counts exactly).
    grep "Loop time" "$1" | tail -2 | awk -v p="$2" 'NR == 1 { n0 = $12 } NR == 2 { printf "LIGGGHTS, %s rank(s): %d → %d atoms, %.4e particle-steps/s (loop %.1f s for %d steps)\n", p, n0, $12, $9 * (n0 + $12) / 2 / $4, $4, $9 }'
}
liggghts -in "$here/tube_bank.in" -log log1.lammps > out1.txt 2>&1
report log1.lammps 1
if command -v mpirun >/dev/null 2>&1; then
    if mpirun --allow-run-as-root -np 2 liggghts -in "$here/tube_bank.in" -log log2.lammps > out2.txt 2>&1; then
        report log2.lammps 2
    else
        echo "mpirun -np 2 failed:"; tail -5 out2.txt
    fi
fi
