#!/bin/sh
# Checks that a library user can leave out the CLI's and the report's dependencies: the
# facade `caustica` without default features, with one backend (and with the set the
# README recommends), must neither depend on clap, indicatif, plotters nor nv-flip (FLIP's
# C++), and must build.
# Usage: scripts/check-library-features.sh
set -eu
cd "$(dirname "$0")/.."
for backend in cpu wgpu wgpu,gltf,obj,cpu; do
    deps=$(cargo tree -p caustica --no-default-features --features "$backend" -e normal --prefix none 2>/dev/null)
    for forbidden in clap indicatif plotters nv-flip; do
        if printf '%s\n' "$deps" | grep -q "^$forbidden v"; then
            echo "check-library-features: FAIL: caustica (features: $backend) depends on $forbidden" >&2
            exit 1
        fi
    done
    echo "check-library-features: caustica --no-default-features --features $backend: no clap, indicatif, plotters, nv-flip"
done
cargo check --release -p caustica --no-default-features --features cpu
echo "check-library-features: ok"
