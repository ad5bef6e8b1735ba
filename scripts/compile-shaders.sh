#!/bin/sh
# Regenerates backend-vulkan/spirv/ from the GLSL under backend-vulkan/shaders/ with
# `glslc --target-env=vulkan1.2` (Debian: apt-get install glslc), so that building the
# crate needs no shader compiler, and records in spirv/SOURCES.sha256 one line per stage:
#   sha256( stage file bytes ++ every file under shaders/common/ in lexical order )  stage
# The test backend-vulkan/tests/spirv_sources.rs recomputes that rule and fails when a
# source changed without this script being run.
set -eu
cd "$(dirname "$0")/../backend-vulkan"
command -v glslc >/dev/null || { echo "compile-shaders: glslc not found (apt-get install glslc)" >&2; exit 1; }
mkdir -p spirv
: > spirv/SOURCES.sha256
for stage in primary_gbuffer.rgen direct_light.rgen trace_photons.rgen closest_hit.rchit \
             miss.rmiss shadow_miss.rmiss reduce_counters.comp; do
    glslc --target-env=vulkan1.2 -O -o "spirv/$stage.spv" "shaders/$stage"
    if command -v spirv-val >/dev/null; then spirv-val --target-env vulkan1.2 "spirv/$stage.spv"; fi
    hash=$(cat "shaders/$stage" $(ls shaders/common/* | LC_ALL=C sort) | sha256sum | cut -d' ' -f1)
    echo "$hash  $stage" >> spirv/SOURCES.sha256
done
echo "compile-shaders: $(wc -l < spirv/SOURCES.sha256) stages"
