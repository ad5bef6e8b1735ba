#!/usr/bin/env bash
# Runs the facade's examples listed below at a reduced size (CI): each must exit 0.
# Images go to out/examples/. Usage: scripts/run-examples.sh (after the drivers are installed).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -p caustica --examples
target=${CARGO_TARGET_DIR:-target}
ex=$target/release/examples
run() { echo "== example: $*"; timeout 300 "$ex/$@"; }
# a backend picked at run time, on every backend this machine has
for backend in cpu opencl wgpu vulkan; do
    run render_png "$backend" sphere 96x54 128
done
run render_png auto ring 96x54 128
run scene_in_code 96x54 128
run load_gltf
# a glTF file from the CLI's exporter, through the example's file argument
mkdir -p out/examples
"$target/release/caustica" scenes --export jelly --format gltf > out/examples/jelly.gltf
run load_gltf out/examples/jelly.gltf 96x54 128
run embed_wgpu 96x54 128
run frame_loop 96x54 128 20
run shape_update cpu 64
run embed_ash 96x54 64
run compare_techniques cpu sphere 256
run sspm_against_light_tracer sphere 48x27 262144 2 64,128 1 mesh centre-surface
run sspm_against_light_tracer sphere 48x27 262144 2 64 1 both centre-surface 2 96
run ball_tessellation_cost sphere 96x54 64 48,96 cpu 1
echo "examples: ok"
