#!/usr/bin/env bash
# Runs the explicit PMB benchmark in spinesim and in LAMMPS (peri/pmb) on the same machine, one
# after the other, on 1 and 2 cores, and prints the throughput ratio (docs/benchmarks.md).
#
#   run_lammps_comparison.sh [points_per_side [steps [repeats]]]
#
# Environment: SPINESIM (default: <repo>/build/bin/spinesim), LMP (default: lmp), MPIRUN
# (default: mpirun), CORES (default: "1 2"), OUT (default: a fresh directory under /tmp),
# OMP_WAIT_POLICY for spinesim (default: passive), MIN_RATIO (when set, exit 1 unless every
# core count's median ratio reaches it).
# spinesim uses OMP_NUM_THREADS threads, LAMMPS (this build has no OPENMP package) MPI ranks.
# Each repeat is a same-minute pair (spinesim, then LAMMPS); the script prints every pair's
# ratio with the 1-minute load and the min / median / max ratio per core count.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/../../.." && pwd)"
n="${1:-30}"
steps="${2:-200}"
repeats="${3:-1}"
SPINESIM="${SPINESIM:-$repo/build/bin/spinesim}"
LMP="${LMP:-lmp}"
MPIRUN="${MPIRUN:-mpirun}"
CORES="${CORES:-1 2}"
OUT="${OUT:-$(mktemp -d /tmp/pd_lammps_comparison.XXXXXX)}"
scene="$repo/applications/benchmarks/pd_explicit_throughput.prm"
mkdir -p "$OUT"
if [ "$(id -u)" = 0 ]; then
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
fi
command -v "$LMP" >/dev/null || { echo "LAMMPS binary '$LMP' not found (apt-get install lammps)"; exit 2; }
case "$("$LMP" -h 2>/dev/null)" in *peri/pmb*) ;; *) false ;; esac || { echo "'$LMP' lacks the PERI package (peri/pmb)"; exit 2; }
[ -x "$SPINESIM" ] || { echo "spinesim binary '$SPINESIM' not found (set SPINESIM=)"; exit 2; }

figure() { # figure <summary.json> <name>
  sed -n "/\"$2\"/,/}/p" "$1" | sed -n 's/.*"value": *\([-+0-9.eE]*\).*/\1/p' | head -1
}
load1() { uptime | sed 's/.*load average: //' | cut -d, -f1; }

# spinesim's OpenMP threads wait passively (sleep) at barriers unless told otherwise: on a
# shared machine a spinning waiter burns the core the late thread needs (docs/benchmarks.md).
WAIT_POLICY="${OMP_WAIT_POLICY:-passive}"
echo "# PMB throughput comparison: ${n}^3 particles, $steps steps, $repeats repeat(s), OMP_WAIT_POLICY=$WAIT_POLICY"
echo "# host $(hostname), $(nproc) cores; load before: $(uptime | sed 's/.*load average: //')"
echo "# output in $OUT"
echo "# each repeat runs spinesim then LAMMPS back to back; ratio = spinesim / LAMMPS particle-steps/s"
printf "%-6s %-7s %-16s %-16s %-8s %s\n" cores repeat spinesim_ps/s lammps_ps/s ratio "load(1min) before/after"
failed=""
for cores in $CORES; do
  ratios=""
  for r in $(seq 1 "$repeats"); do
    before=$(load1)
    dir="$OUT/spinesim_${cores}_$r"
    OMP_WAIT_POLICY=$WAIT_POLICY OMP_NUM_THREADS=$cores "$SPINESIM" run "$scene" --output "$dir" --force --progress off --threads "$cores" \
      --set "Benchmark/Lattice points per side=$n" --set "Benchmark/Steps=$steps" \
      > "$dir.log" 2>&1 || { echo "spinesim failed, see $dir.log"; exit 1; }
    ours=$(figure "$dir/summary.json" particle_steps_per_s)
    vars=$(cat "$dir/lammps_vars.txt")
    lmp_cmd=("$LMP")
    [ "$cores" -gt 1 ] && lmp_cmd=("$MPIRUN" -np "$cores" "$LMP")
    # shellcheck disable=SC2086
    (cd "$OUT" && OMP_NUM_THREADS=1 "${lmp_cmd[@]}" -in "$here/in.peri_pmb" -log none $vars \
      > "$OUT/lammps_${cores}_$r.log" 2>&1) || { echo "LAMMPS failed, see $OUT/lammps_${cores}_$r.log"; exit 1; }
    loop=$(sed -n 's/^Loop time of \([0-9.eE+-]*\) on .* for \([0-9]*\) steps with \([0-9]*\) atoms.*/\1 \2 \3/p' \
      "$OUT/lammps_${cores}_$r.log")
    theirs=$(echo "$loop" | awk '{ printf "%.6g", $2 * $3 / $1 }')
    ratio=$(awk -v a="$ours" -v b="$theirs" 'BEGIN { printf "%.2f", a / b }')
    ratios="$ratios $ratio"
    printf "%-6s %-7s %-16.4g %-16.4g %-8s %s / %s\n" "$cores" "$r" "$ours" "$theirs" "$ratio" "$before" "$(load1)"
  done
  summary=$(echo "$ratios" | tr ' ' '\n' | sed '/^$/d' | sort -g | awk -v c="$cores" '{ a[++n] = $1 }
    END { printf "# %s core(s): ratio min %s, median %s, max %s over %d repeat(s)\n", c, a[1], a[int((n + 1) / 2)], a[n], n }')
  echo "$summary"
  median=$(echo "$summary" | sed 's/.*median \([0-9.]*\),.*/\1/')
  if [ -n "${MIN_RATIO:-}" ] && ! awk -v m="$median" -v t="$MIN_RATIO" 'BEGIN { exit !(m + 0 >= t + 0 && m != "") }'; then
    failed="$failed $cores"
  fi
done

# Same physics: the final energies (per unit particle volume) of the last 1-core runs.
ref="$OUT/spinesim_$(echo $CORES | awk '{print $1}')_1/lammps_reference.txt"
log="$OUT/lammps_$(echo $CORES | awk '{print $1}')_1.log"
ke_lmp=$(awk '/^ *Step +KinEng/ { getline; getline; print $2 }' "$log")
pe_lmp=$(awk '/^ *Step +KinEng/ { getline; getline; print $3 }' "$log")
awk -v k="$(sed -n 's/^ke //p' "$ref")" -v p="$(sed -n 's/^pe //p' "$ref")" -v K="$ke_lmp" -v P="$pe_lmp" \
  -v nb="$(sed -n 's/^bonds_broken //p' "$ref")" 'BEGIN {
    printf "# final energies per particle volume [J/m^3]: spinesim ke %.9g pe %.9g, LAMMPS ke %.9g pe %.9g\n", k, p, K, P
    printf "# relative difference of ke + pe: %.3g (spinesim broke %d bonds)\n", ((k + p) - (K + P)) / (K + P), nb
  }'
if [ -n "$failed" ]; then
  echo "# FAIL: median ratio below MIN_RATIO=$MIN_RATIO on core count(s):$failed"
  exit 1
fi
