#!/bin/sh
# Regenerates backend-vulkan/spirv/ from the GLSL under backend-vulkan/shaders/, so that
# building the crate needs no shader compiler. Needs glslc (shaderc; Debian:
# apt-get install glslc); spirv-val and spirv-dis (apt-get install spirv-tools) are used
# when present.
#
# For every stage file directly under backend-vulkan/shaders/ (listed below) it
#   1. compiles  glslc --target-env=vulkan1.2 -O -o spirv/<stage>.spv shaders/<stage>
#      (-O keeps `precise`: spirv-opt neither drops NoContraction nor folds or
#      reassociates an operation that carries it; step 3 checks the first part);
#   2. validates spirv/<stage>.spv with spirv-val --target-env vulkan1.2;
#   3. checks with spirv-dis that every float add, sub, mul, div (and vector-times-scalar,
#      dot, mod, rem, matrix product) carries NoContraction, i.e. that `precise` reached
#      every float operation (common/prelude.glsl says why): the kernels must round as
#      the Rust reference, which never fuses a * b + c;
#   4. records one line in spirv/SOURCES.sha256.
# The struct layouts in the result are then checked against core's by
# backend-vulkan/tests/glsl_layouts.rs (cargo test -p caustica-vulkan).
#
# Hash rule (backend-vulkan/tests/spirv_sources.rs recomputes it), one line per stage:
#   <sha256 of: the stage file's bytes, followed by the bytes of every file in
#    shaders/common/ in lexical (bytewise) order of file name>  <stage file name>
# i.e. `cat shaders/<stage> shaders/common/* | sha256sum` under LC_ALL=C, two spaces
# between hash and name. Every common file counts for every stage, whether the stage
# includes it or not (simplest rule; a change to any common file marks all stages).
set -eu
export LC_ALL=C
cd "$(dirname "$0")/../backend-vulkan"
command -v glslc >/dev/null || { echo "compile-shaders: glslc not found (apt-get install glslc)" >&2; exit 1; }
have() { command -v "$1" >/dev/null; }
have spirv-val || echo "compile-shaders: spirv-val not found, SPIR-V not validated" >&2
have spirv-dis || echo "compile-shaders: spirv-dis not found, NoContraction not checked" >&2
mkdir -p spirv
manifest=spirv/SOURCES.sha256.tmp
: > "$manifest"
for stage in primary_gbuffer.rgen direct_light.rgen trace_photons.rgen caustic_map_lookup.rgen trace_indirect.rgen closest_hit.rchit \
             miss.rmiss shadow_miss.rmiss reduce_counters.comp; do
    glslc --target-env=vulkan1.2 -O -o "spirv/$stage.spv" "shaders/$stage"
    if have spirv-val; then spirv-val --target-env vulkan1.2 "spirv/$stage.spv"; fi
    if have spirv-dis; then
        spirv-dis --no-color "spirv/$stage.spv" | awk -v stage="$stage" '
            $1 == "OpDecorate" && $3 == "NoContraction" { nc[$2] = 1; next }
            $2 == "=" && $3 ~ /^Op(FAdd|FSub|FMul|FDiv|FMod|FRem|VectorTimesScalar|Dot|MatrixTimes|VectorTimesMatrix)/ {
                if (!($1 in nc)) { print "compile-shaders: " stage ": float operation without NoContraction (missing precise): " $0 > "/dev/stderr"; bad++ }
            }
            END { exit bad > 0 }'
    fi
    hash=$(cat "shaders/$stage" shaders/common/* | sha256sum | cut -d' ' -f1)
    echo "$hash  $stage" >> "$manifest"
done
mv "$manifest" spirv/SOURCES.sha256
echo "compile-shaders: $(wc -l < spirv/SOURCES.sha256) stages"
