#!/usr/bin/env bash
# CI step: a build for this processor (README: `RUSTFLAGS="-C target-cpu=native" cargo
# build --release`) gives the portable build's results to the bit. Rust neither fuses a
# multiply and an add nor reorders a sum unless the code says so, so wider instructions
# change the speed, not the arithmetic; this checks it on a 2D and a 3D run (the binary
# star, the stream, sinks, cooling and the light curve included).
#
# Usage: scripts/native_identical.sh [path/to/portable/sphdisk]   (default target/release/sphdisk)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
portable="$(realpath "${1:-$root/target/release/sphdisk}")"
cd "$root"
RUSTFLAGS="-C target-cpu=native" CARGO_TARGET_DIR=target/native cargo build --release --quiet
native="$root/target/native/release/sphdisk"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
for problem in "cv2d.toml --set time.end=6.283185307179586" \
    "overflow3d_cool.toml --set time.end=0.6283185307179586"; do
    name="${problem%%.toml*}"
    for build in portable native; do
        # shellcheck disable=SC2086 # the problem's --set arguments split on purpose
        "${!build}" --threads 2 run problems/$problem --out "$work/$build-$name" --quiet
    done
    for file in final.csv monitor.csv lightcurve.csv; do
        cmp "$work/portable-$name/$file" "$work/native-$name/$file"
    done
    echo "$name: final.csv, monitor.csv, lightcurve.csv identical (portable and target-cpu=native)"
done
