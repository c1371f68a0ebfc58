#!/usr/bin/env bash
# CI step: the README's commands, in the README's order, run as written in a scratch folder
# (with `sphdisk` = target/release/sphdisk), so that a documented command that breaks fails
# CI. Every command line in a ```sh block that calls sphdisk, `cargo run` or a script of
# scripts/ is taken; the rules below skip the few that cannot run here (installs, MPI,
# benchmarks, runs of many minutes, whose analyses the tests cover) or shorten a long run
# with extra `--set` keys that keep the files later commands read. A command the rules do
# not name runs as written (under a time limit): a new README command is checked as soon
# as it is written.
#
# Usage: scripts/readme_commands.sh [path/to/sphdisk]   (default target/release/sphdisk)
# RAYON_NUM_THREADS limits the threads of each run (default: all cores).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
exe="$(realpath "${1:-$root/target/release/sphdisk}")"
limit="${README_COMMAND_LIMIT:-300}"   # seconds per command

# pattern (extended regex on the command) ~ action ~ what
#   skip: not run (the reason is printed); set: run with these arguments appended.
rules=(
    '^cargo (build|install|test)~skip~the build and the tests are CI steps of their own'
    '^sudo ~skip~system packages (the MPI step of CI installs them)'
    'features mpi~skip~the MPI step of CI builds and runs it'
    '^mpirun ~skip~the MPI step of CI runs mpirun'
    ' bench ~skip~a benchmark'
    'superhump_scan\.sh~skip~a series of 200-orbit runs'
    'run problems/disk3d\.toml~set~--set time.end=0.04 --set output.interval=0.01'
    'run problems/cv2d_steady\.toml~set~--set time.end=62.83185307179586'
    'run problems/overflow3d(_cool)?\.toml~set~--set time.end=3.1416'
    'run problems/(oy_car|superhump|outbursts)\.toml~skip~tens of minutes (tests/cv_analyse.rs, superhump_cli.rs, outbursts.rs run the analyses on short runs)'
    'runs/hump2d~skip~18 minutes (tests/lightcurve_cli.rs runs the light curve analysis)'
    'runs/(oy_car|superhump|outbursts)~skip~needs a run of tens of minutes (above)'
    'problems/sedov2d\.toml --set output\.files_per_snapshot~set~--set particles.n=48'
)

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/bin" "$work/target/release"
ln -s "$exe" "$work/bin/sphdisk"
ln -s "$exe" "$work/target/release/sphdisk"
ln -s "$root/problems" "$work/problems"
ln -s "$root/scripts" "$work/scripts"
export PATH="$work/bin:$PATH"

# The command lines of the README's ```sh blocks, comments cut.
mapfile -t commands < <(awk '
    /^```/ { inblock = !inblock; next }
    inblock && /^(cargo|sphdisk|target\/release\/sphdisk|python3 scripts\/|scripts\/|mpirun|sudo)/ {
        sub(/[ \t]+#.*/, ""); print
    }' "$root/README.md")

# Seconds since $1 (from `date +%s%N`), to a tenth.
since() {
    local ds=$((($(date +%s%N) - $1) / 100000000))
    printf '%d.%d' $((ds / 10)) $((ds % 10))
}

cd "$work"
failed=0
total_start=$(date +%s%N)
for cmd in "${commands[@]}"; do
    action=run extra=""
    for rule in "${rules[@]}"; do
        IFS='~' read -r pattern act what <<<"$rule"
        if [[ "$cmd" =~ $pattern ]]; then
            if [[ "$act" == skip ]]; then
                action=skip extra="$what"
            else
                extra="$what"
            fi
            break
        fi
    done
    if [[ "$action" == skip ]]; then
        printf 'skip   %s   (%s)\n' "$cmd" "$extra"
        continue
    fi
    # `cargo run --release -- ARGS` is the binary CI built.
    line="${cmd/#cargo run --release --/sphdisk}"
    [[ -n "$extra" ]] && line="$line $extra"
    start=$(date +%s%N)
    if timeout "$limit" bash -c "$line" >"$work/out.txt" 2>&1 </dev/null; then
        printf 'ok     %6s s  %s\n' "$(since "$start")" "$line"
    else
        rc=$?
        printf 'FAILED %6s s  %s  (exit %s)\n' "$(since "$start")" "$line" "$rc"
        tail -n 20 "$work/out.txt" | sed 's/^/    /'
        failed=1
    fi
done
printf 'README commands: %s s in all\n' "$(since "$total_start")"
exit "$failed"
