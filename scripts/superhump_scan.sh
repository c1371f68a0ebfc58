#!/usr/bin/env bash
# A q series of problems/superhump.toml (issue: SU UMa superhumps against q): one 2D run per
# mass ratio, each with its initial disk reaching 3% past its own 3:1 resonance radius
# r_3:1 = 3^(-2/3) (1+q)^(-1/3) a, then `sphdisk analyse superhump` on all of them, which
# writes the table superhump_scan.csv and the plot superhump_scan.png (ε against q beside
# Patterson et al. 2005, Kato et al. 2009 and the dynamical precession at r_3:1).
#
# Usage: scripts/superhump_scan.sh [ORBITS] [Q...]
#   ORBITS  orbits per run (default 60); Q  mass ratios (default 0.05 0.1 0.15 0.2 0.25 0.35)
# Environment: SPHDISK (the binary, default target/release/sphdisk), OUT (default
# runs/superhump_scan), SET (more `KEY=VALUE` overrides for every run, separated by spaces;
# e.g. the cooler disk: SET="eos.cs=0.03 stream.cs=0.03 viscosity.alpha=0.05"), THREADS
# (per run; default: all cores). Runs already finished in OUT are analysed, not run again; a
# run that stopped part-way is resumed.
set -euo pipefail
orbits=${1:-60}
shift || true
qs=("$@")
[ ${#qs[@]} -gt 0 ] || qs=(0.05 0.1 0.15 0.2 0.25 0.35)
bin=${SPHDISK:-target/release/sphdisk}
out=${OUT:-runs/superhump_scan}
if [ ! -x "$bin" ]; then
  echo "error: $bin not found: build it with \`cargo build --release\` or set SPHDISK" >&2
  exit 2
fi
extra=()
for kv in ${SET:-}; do
  extra+=(--set "$kv")
done
threads=()
[ -z "${THREADS:-}" ] || threads=(--threads "$THREADS")
mkdir -p "$out"
end=$(awk -v n="$orbits" 'BEGIN { printf "%.15g", n * 2 * atan2(0, -1) }')
runs=()
for q in "${qs[@]}"; do
  r_out=$(awk -v q="$q" 'BEGIN { printf "%.6f", 1.03 * 3^(-2/3) * (1 + q)^(-1/3) }')
  dir="$out/q$q"
  runs+=("$dir")
  if [ -f "$dir/summary.json" ]; then
    echo "q = $q: finished run in $dir"
  elif [ -d "$dir/checkpoints" ]; then
    echo "q = $q: resuming $dir"
    "$bin" run --resume "$dir" --quiet "${threads[@]}"
  else
    echo "q = $q: $orbits orbits, initial disk to r_out = $r_out a, into $dir"
    # --force: the folder is this script's own (a run killed before its first checkpoint).
    "$bin" run problems/superhump.toml --quiet --force --out "$dir" \
      --set binary.q="$q" --set initial_disk.r_out="$r_out" --set time.end="$end" \
      "${extra[@]}" "${threads[@]}"
  fi
done
"$bin" analyse superhump "${runs[@]}" --out "$out"
