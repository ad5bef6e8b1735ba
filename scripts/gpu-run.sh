#!/bin/bash
# The GPU measurements and checks, run on the GPU machine (NVIDIA, no Rust toolchain
# there) from binaries built here. CONTRIBUTING.md, "Running on the GPU machine", walks
# through it; every GPU figure in the docs names the section that reproduces it.
set -uo pipefail
cd "$(dirname "$0")/.."

usage() {
    cat <<'EOF'
Usage:
  scripts/gpu-run.sh --build SECTION...  (here) build what the sections run into .devbin/,
                                         stripped and gzipped for the device tool's carry
  scripts/gpu-run.sh SECTION...          (there, carry [".devbin"]) run them; $OUT/log.txt

Sections:
  suite        the conformance suite on every backend (SUITE_PARTS=kernels,frames,stiff,hostile)
  frames       Sspm's, CausticMap's and PhotonGi's frame benchmarks at the README's settings
  sspm         Sspm's checks, both filters, the fused deposit against the separate pass
  caustic-map  CausticMap's checks and stiff cases; every setting, Fresnel split and gather
  adaptive     AdaptiveCaustics (ADAPTIVE_PARTS=checks,frames by default; table,footprint,screen)
  photon-gi    PhotonGi's checks and stiff cases, its frames at the chapter's two settings
               with each schedule of trace_indirect (CAUSTICA_BENCH_GI_SCHEDULES,
               CAUSTICA_BENCH_GI_QUEUE; PHOTON_GI_TIMES_ONLY=1 skips the checks)
  dispersion   spectral dispersion against the CPU on every backend, the prism's closed forms
  dynamic      moving lights and instances, deformations, the non-blocking loop (frame_loop)
  traversal    indirect launches checked, AdaptiveCaustics' device traversal timed, host waits
               (TRAVERSAL_TIMES_ONLY=1 skips the checks; TRAVERSAL_START_GRIDS="64 16")
  update       an update's host time: update_cost (Vulkan, no frames), frame_loop 1920x1080
  hang         loops the parallel conformance suite; a hung run's threads are recorded
  experiment   kernel variants timed without a rebuild (EXP_* below, CONTRIBUTING.md)

Variables: BENCH_BACKENDS (vulkan,wgpu,opencl); CAUSTICA_BENCH_* pass through to the
benches. experiment: EXP_BENCH=sspm|caustic-map|photon-gi|adaptive, EXP_LANG=opencl|wgsl, EXP_DIR
(a folder of variant folders of changed kernel files; default .devbin/exp, .devbin/wexp),
EXP_OPTIONS ("opts;opts": OpenCL build options, each a variant), EXP_ENVS ("VAR=VALUE ...;...":
environments, each a variant, e.g. CAUSTICA_OPENCL_RELAXED=atrous_filter), EXP_SASS=1 (ptxas counts,
SASS in $OUT/sass.tgz), EXP_FRAMES, EXP_SETTINGS. hang: HANG_RUNS (8), HANG_AFTER (60 s);
update: UPDATE_BASE=1 (a baseline build's examples copied as .devbin/update_cost_base and
.devbin/frame_loop_base after --build, which empties .devbin's gzipped files, or before
it as plain files, which it strips and gzips; run in turns with this build's);
CAUSTICA_SKIP_BACKENDS and CAUSTICA_SERIALIZE_DRIVERS pass through to the suite.
EOF
}
case "${1:-}" in ""|-h|--help) usage; exit 0 ;; esac
SECTIONS="suite frames sspm caustic-map adaptive photon-gi dispersion dynamic traversal update hang experiment"
for s in "$@"; do case " --build $SECTIONS " in *" $s "*) ;; *) echo "unknown section '$s'" >&2; exit 2 ;; esac; done

# The functions a section runs: its parts' (SUITE_PARTS, ADAPTIVE_PARTS) or its own.
parts() { local v=${1//,/ }; for p in ${v:-$2}; do echo "$3_$p"; done; }
functions() {
    case $1 in
    suite) parts "${SUITE_PARTS:-}" "kernels frames stiff hostile" suite ;;
    adaptive) parts "${ADAPTIVE_PARTS:-}" "checks frames" adaptive ;;
    *) echo "${1//-/_}" ;;
    esac
}

log() { echo "$*" | tee -a "$OUT/log.txt"; }
run() { log "=== $*"; "$@" 2>&1 | tee -a "$OUT/log.txt"; log "=== exit ${PIPESTATUS[0]}"; }
ALL=cpu,opencl,wgpu,vulkan
# check SECONDS ./TEST [ARGS]: a test binary with every backend required, one test at a time
check() { local t=$1; shift; run timeout "$t" env CAUSTICA_REQUIRE_BACKENDS=$ALL "$@" --test-threads=1; }
# bench SECONDS [VAR=VALUE...] ./BENCH [ARGS]: a frame benchmark on BENCH_BACKENDS
bench() { local t=$1; shift; run timeout "$t" env CAUSTICA_BENCH_BACKENDS="${BENCH_BACKENDS:-vulkan,wgpu,opencl}" "$@"; }
# a freshly started machine runs Vulkan 3-4x slow for about a minute: frames before timing
warm_up() { log "warm-up"; timeout 100 env CAUSTICA_BENCH_BACKENDS=vulkan,wgpu CAUSTICA_BENCH_FRAMES=20 \
    CAUSTICA_BENCH_FILTERS=density ./sspm_frame --bench > /dev/null 2>&1; }

suite_kernels() {
    run ./device_layout; run timeout 120 ./vulkan_backend --test-threads=1
    check 400 ./cross_backend; check 120 ./cpu_reference; run ./optics_closed_form
    run ./backend_diff 960x540 512x512
    run timeout 60 ./embed_wgpu 1920x1080 2048; run timeout 60 ./embed_ash 1920x1080 2048
}
suite_frames() {
    check 240 ./frame_plan; check 240 ./every_kernel_dispatched; check 240 ./technique_seam
    check 240 ./filter_flux; check 240 ./caustic_map_frames; check 240 ./adaptive_caustics_frames
    check 240 ./photon_gi_frames; check 240 ./temporal_frames; check 240 ./instance_updates
    check 240 ./submitted_frames
}
suite_stiff() {
    check 400 ./stiff_cases --include-ignored; check 200 ./photon_gi_stiff
    run timeout 300 env CAUSTICA_REQUIRE_BACKENDS=$ALL ./stiff_table "$OUT/stability-gpu.md" --heavy
}
suite_hostile() {
    check 240 ./hostile_input; check 300 ./large_frames
    for be in vulkan wgpu opencl; do
        run timeout 120 ./caustica render --scene sphere --backend $be --size 8192x8192 --photons 1024x1024 --out "$OUT/r8192-$be"
        rm -f "$OUT/r8192-$be"/*.exr "$OUT/r8192-$be"/*.png
    done
}
frames() {
    warm_up
    bench 240 CAUSTICA_BENCH_FILTERS=density CAUSTICA_BENCH_FRAMES=10 ./sspm_frame --bench
    bench 240 CAUSTICA_BENCH_SETTINGS=0,1 CAUSTICA_BENCH_SPLITS=stochastic CAUSTICA_BENCH_GATHERS=box \
        CAUSTICA_BENCH_FRAMES=10 ./caustic_map_frame --bench
    bench 240 ./photon_gi_frame --bench
}
sspm() {
    check 200 ./cross_backend sspm; check 200 ./cross_backend density; check 120 ./filter_flux
    warm_up
    bench 240 CAUSTICA_BENCH_FILTERS=density,bilateral CAUSTICA_BENCH_FRAMES=10 ./sspm_frame --bench
    for fused in false true; do
        bench 150 CAUSTICA_BENCH_FILTERS=density CAUSTICA_BENCH_FRAMES=10 \
            CAUSTICA_BENCH_SETTINGS="{\"fused_deposit\": $fused}" ./sspm_frame --bench
    done
}
caustic_map() {
    check 200 ./cross_backend caustic; check 200 ./caustic_map_frames; check 300 ./stiff_cases
    bench 500 CAUSTICA_BENCH_SETTINGS="${CAUSTICA_BENCH_SETTINGS:-0,1,2}" CAUSTICA_BENCH_FRAMES=10 \
        CAUSTICA_BENCH_SPLITS="${CAUSTICA_BENCH_SPLITS:-stochastic,deterministic}" \
        CAUSTICA_BENCH_GATHERS="${CAUSTICA_BENCH_GATHERS:-box,density}" ./caustic_map_frame --bench
}
adaptive_checks() {
    check 200 ./cross_backend adaptive; check 60 ./cluster_seed; check 240 ./adaptive_caustics_frames --nocapture
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=$ALL STIFF_CASES=small-caster,grazing-caster,light-inside-casters \
        ./stiff_table "$OUT/stiff-adaptive.md"
}
adaptive_table() { run timeout 300 ./adaptive_table vulkan "${ADAPTIVE_TOP:-8192}" "${ADAPTIVE_REFERENCE:-16384}"; }
adaptive_footprint() { run timeout 400 env ERROR_TEXELS=1,2,4 ./adaptive_table vulkan "${ADAPTIVE_TOP:-8192}" "${ADAPTIVE_REFERENCE:-16384}"; }
adaptive_frames() { bench 400 ./adaptive_frame; }
adaptive_screen() {
    run timeout 400 ./caustica report --scenes sphere,cornell --backends "${REPORT_BACKENDS:-vulkan,opencl}" \
        --techniques sspm,caustic-map,adaptive-caustics,adaptive-caustics:deposit=screen \
        --budgets 512x512,1024x1024,2048x2048,4096x4096 --repeats 3 --reference-noise 0.01 --out "$OUT/report-adaptive-screen"
}
photon_gi() {
    if [ -z "${PHOTON_GI_TIMES_ONLY:-}" ]; then
        check 200 ./cross_backend photon_gi; check 240 ./photon_gi_frames --nocapture; check 200 ./photon_gi_stiff
        check 120 ./photon_plan; check 200 ./photon_gi_schedules --nocapture
    fi
    # trace_indirect's schedules (CAUSTICA_BENCH_GI_SCHEDULES=auto,single_kernel,waves,sorted_waves;
    # waves CAUSTICA_BENCH_GI_WAVES, queues CAUSTICA_BENCH_GI_QUEUE), each timed at every setting
    bench 500 CAUSTICA_BENCH_SETTINGS="${CAUSTICA_BENCH_SETTINGS:-high,low}" \
        CAUSTICA_BENCH_GI_SCHEDULES="${CAUSTICA_BENCH_GI_SCHEDULES:-auto,single_kernel,waves,sorted_waves}" \
        ./photon_gi_frame --bench
}
dispersion() { check 300 ./spectral_dispersion; run ./optics_closed_form --nocapture; }
dynamic() {
    warm_up
    bench 240 CAUSTICA_BENCH_DEFORM=0 ./dynamic_frame --bench; bench 300 ./dynamic_frame --bench
    check 200 ./instance_updates --nocapture; check 200 ./submitted_frames --nocapture
    run timeout 60 ./frame_loop 1920x1080 2048 100; run timeout 60 ./frame_loop 1920x1080 1024 100
}
traversal() {
    if [ -z "${TRAVERSAL_TIMES_ONLY:-}" ]; then
        check 120 ./indirect_launches; check 60 ./cluster_seed; check 240 ./submitted_frames
        check 300 ./adaptive_caustics_frames
    fi
    warm_up
    # each start grid (TRAVERSAL_START_GRIDS) a run; each level's time by kernel
    for g in ${TRAVERSAL_START_GRIDS:-64}; do
        bench 400 CAUSTICA_BENCH_START_GRID="$g" CAUSTICA_BENCH_KERNELS=1 \
            CAUSTICA_BENCH_SIZES="${CAUSTICA_BENCH_SIZES:-2048,4096}" ./adaptive_frame
    done
    run timeout 90 ./frame_loop 1920x1080 2048 60
}
update() {
    # UPDATE_BASE=1: also a baseline build's update_cost_base and frame_loop_base, in
    # turns with this build's, twice: host times drift by tens of percent between runs on
    # one host, so only turns of one run compare
    local r base=""
    [ "${UPDATE_BASE:-}" = 1 ] && base=1
    for r in 1 ${base:+2}; do
        if [ -n "$base" ]; then
            run timeout 60 ./update_cost_base vulkan 200; run timeout 90 ./frame_loop_base 1920x1080 2048 60
        fi
        run timeout 60 ./update_cost vulkan 200; run timeout 90 ./frame_loop 1920x1080 2048 60
    done
}
hang() {
    # elfutils' eu-stack from .devbin (the device image has no gdb) names a hung thread's calls
    for f in "$B"/{elfutils,libdw1,libelf1,libasm1}_*.deb; do [ -f "$f" ] && dpkg -x "$f" /tmp/eu; done
    local hung=0 k pid rc start
    for k in $(seq 1 "${HANG_RUNS:-8}"); do
        start=$(date +%s); ./cross_backend > /tmp/hang.log 2>&1 & pid=$!
        for _ in $(seq 1 "${HANG_AFTER:-60}"); do kill -0 "$pid" 2>/dev/null || break; sleep 1; done
        if ! kill -0 "$pid" 2>/dev/null; then
            wait "$pid"; rc=$?
            log "hang: run $k: exit $rc in $(( $(date +%s) - start )) s ($(grep -E '^test result' /tmp/hang.log | tail -n 1))"
            continue
        fi
        hung=$((hung + 1)); log "hang: run $k hung; last: $(grep -E '^test |\*\*\*' /tmp/hang.log | tail -n 1)"
        { nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv
          for t in /proc/$pid/task/*; do
              echo "thread ${t##*/} $(cat "$t/comm") state=$(awk '{print $3}' "$t/stat") wchan=$(cat "$t/wchan" 2>/dev/null)"
          done
          [ -x /tmp/eu/usr/bin/eu-stack ] && LD_LIBRARY_PATH=/tmp/eu/usr/lib/x86_64-linux-gnu \
              timeout 60 /tmp/eu/usr/bin/eu-stack -p "$pid" -m -s 2>&1 | head -n 600
        } | tee -a "$OUT/log.txt"
        kill -9 "$pid"; wait "$pid" 2>/dev/null
    done
    log "hang: $hung of ${HANG_RUNS:-8} runs hung (serialize=${CAUSTICA_SERIALIZE_DRIVERS:-1} skip=${CAUSTICA_SKIP_BACKENDS:-})"
}
experiment() {
    local var=CAUSTICA_OPENCL_KERNEL_DIR be=opencl dir=${EXP_DIR:-$B/exp} cmd=(env)
    [ "${EXP_LANG:-opencl}" = wgsl ] && var=CAUSTICA_WGSL_KERNEL_DIR be=${BENCH_BACKENDS:-vulkan,wgpu} dir=${EXP_DIR:-$B/wexp}
    case ${EXP_BENCH:-sspm} in
    sspm) cmd+=(CAUSTICA_BENCH_FILTERS=density ${EXP_SETTINGS:+"CAUSTICA_BENCH_SETTINGS=$EXP_SETTINGS"} ./sspm_frame) ;;
    caustic-map) cmd+=(CAUSTICA_BENCH_SETTINGS="${EXP_SETTINGS:-0,1}" CAUSTICA_BENCH_SPLITS=stochastic CAUSTICA_BENCH_GATHERS=box ./caustic_map_frame) ;;
    photon-gi) cmd+=(CAUSTICA_BENCH_SETTINGS="${EXP_SETTINGS:-high,low}" ./photon_gi_frame) ;;
    # the fused finest level against the slots and the dense trace on `sphere`
    adaptive) cmd+=(CAUSTICA_BENCH_SCENES=sphere CAUSTICA_BENCH_SIZES="${EXP_SETTINGS:-2048}" \
        CAUSTICA_BENCH_FUSED=1,0 CAUSTICA_BENCH_KERNELS=1 ./adaptive_frame) ;;
    esac
    rm -rf /tmp/sass && mkdir -p /tmp/sass
    variant() {  # NAME KERNEL_DIR OPTIONS [VAR=VALUE...]
        local e=(env CAUSTICA_BENCH_BACKENDS="$be" CAUSTICA_BENCH_FRAMES="${EXP_FRAMES:-10}" CAUSTICA_BENCH_WARMUP_MS=1500)
        [ -n "$2" ] && e+=("$var=$2")
        [ -n "$3" ] && e+=("CAUSTICA_OPENCL_OPTIONS=$3")
        local v; for v in "${@:4}"; do e+=("$v"); done
        [ -n "${EXP_SASS:-}" ] && mkdir -p "/tmp/sass/$1" && e+=("CAUSTICA_OPENCL_DUMP_DIR=/tmp/sass/$1")
        log "experiment: $1"; run timeout 200 "${e[@]}" "${cmd[@]}" --bench
    }
    variant base "" ""
    for d in "$dir"/*/; do [ -d "$d" ] && variant "$(basename "$d")" "$d" ""; done
    IFS=';' read -ra opts <<< "${EXP_OPTIONS:-}"
    for o in "${opts[@]}"; do variant "options$(echo "$o" | tr -c 'A-Za-z0-9=\n-' _)" "" "$o"; done
    IFS=';' read -ra envs <<< "${EXP_ENVS:-}"
    # shellcheck disable=SC2086 # each entry's VAR=VALUE words, split on spaces
    for v in "${envs[@]}"; do variant "env_$(echo "$v" | tr -c 'A-Za-z0-9=\n-' _)" "" "" $v; done
    [ -n "${EXP_SASS:-}" ] || return 0
    # NVIDIA's program binaries are PTX text with a trailing NUL: ptxas gives registers,
    # stack and spills, cuobjdump the SASS
    PTXAS=$(command -v ptxas || ls /usr/local/cuda*/bin/ptxas 2>/dev/null | head -n 1)
    CUOBJ=$(command -v cuobjdump || ls /usr/local/cuda*/bin/cuobjdump 2>/dev/null | head -n 1)
    for f in /tmp/sass/*/*.bin; do
        [ -f "$f" ] && [ -n "$PTXAS" ] || continue
        n=${f%.bin}; tr -d '\000' < "$f" > "$n.ptx"
        timeout 120 "$PTXAS" -arch=sm_90 -v "$n.ptx" -o "$n.cubin" > "$n.ptxas.txt" 2>&1
        log "ptxas ${n#/tmp/sass/}: $(grep -E 'entry|Used|spill|stack' "$n.ptxas.txt" | tr '\n' ' ')"
        [ -f "$n.cubin" ] && [ -n "$CUOBJ" ] && timeout 120 "$CUOBJ" -sass "$n.cubin" > "$n.sass" 2>&1
    done
    (cd /tmp && tar czf "$OUT/sass.tgz" sass)
}

if [ "$1" = "--build" ]; then
    shift; [ $# -gt 0 ] || { usage; exit 2; }
    set -e
    T=${CARGO_TARGET_DIR:-target}/release
    mkdir -p .devbin && rm -f .devbin/*.gz
    cargo build --release -p caustica && cp "$T/caustica" .devbin/
    # every ./binary the sections' functions name (warm_up runs sspm_frame), but a
    # baseline build's (*_base, copied in by hand)
    bins=$(for s in "$@"; do for f in $(functions "$s"); do declare -f "$f" | grep -q warm_up && echo sspm_frame
        declare -f "$f" | grep -oE '\./[a-z_]+' | cut -c3-; done; done | { grep -vxE 'caustica|.*_base' || true; } | sort -u)
    # the executable cargo names in its JSON messages (a bench's own: deps/<name>-<hash>)
    exe() { grep -o '"executable":"[^"]*/'"$1"'-[^"]*"' | tail -n 1 | cut -d'"' -f4; }
    for b in $bins; do
        case $b in
        embed_*|frame_loop|update_cost|*_table|backend_diff) cargo build --release --example "$b"; f=$T/examples/$b ;;
        *_frame) f=$(cargo bench --bench "$b" --no-run --message-format=json | exe "$b") ;;
        *) f=$(cargo test --release --test "$b" --no-run --message-format=json | exe "$b") ;;
        esac
        [ -n "$f" ] || { echo "cargo named no executable for $b" >&2; exit 1; }
        cp "$f" ".devbin/$b"
    done
    # (folders, such as the experiments' variants, stay as they are)
    cd .devbin && for f in *; do [ -f "$f" ] || continue; case $f in *.deb|*.gz) ;; *) strip "$f"; gzip -9 -f "$f" ;; esac; done
    ls ocl-icd-libopencl1_*.deb >/dev/null 2>&1 || apt-get download ocl-icd-libopencl1
    ls libglvnd0_*.deb >/dev/null 2>&1 || apt-get download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2
    case " $* " in *" hang "*) ls elfutils_*.deb >/dev/null 2>&1 || apt-get download elfutils libdw1 libelf1 libasm1 ;; esac
    # the device tool carries .devbin with the repository's files (tracked, and untracked
    # but not ignored): 64 MiB in all
    tracked=$(cd .. && git ls-files -z --cached --others --exclude-standard | xargs -0r cat 2>/dev/null | wc -c || true)
    total=$(( $(du -sb . | cut -f1) + tracked ))
    echo ".devbin and the tracked files: $(( total / 1048576 )) MiB"
    if [ "$total" -gt $(( 64 * 1048576 )) ]; then
        echo "over the device tool's 64 MiB carry: build fewer sections or parts, or move out what this run does not use; the largest:"
        ls -S ./*.gz | head -n 5
    fi
    exit 0
fi

OUT=${OUT:-/tmp/out} B=$PWD/.devbin
mkdir -p "$OUT" && gunzip -f "$B"/*.gz 2>/dev/null; chmod +x "$B"/* 2>/dev/null
# The OpenCL ICD loader with an ICD file naming the driver's libnvidia-opencl.so; the
# Vulkan loader and the GL dispatch libraries NVIDIA's Vulkan ICD needs (libglvnd).
dpkg -x "$B"/ocl-icd-libopencl1_*.deb /tmp/ocl
for f in "$B"/lib{vulkan1,glvnd0,egl1,opengl0,gl1,glx0,gles2}_*.deb; do [ -f "$f" ] && dpkg -x "$f" /; done
ldconfig
export LD_LIBRARY_PATH=/tmp/ocl/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json; [ -f "$icd" ] && export VK_DRIVER_FILES=$icd
lib=$(find / -xdev -name 'libnvidia-opencl.so*' 2>/dev/null | head -n 1)
mkdir -p /etc/OpenCL/vendors && echo "$lib" > /etc/OpenCL/vendors/nvidia.icd
cd "$B"

nvidia-smi -L | tee -a "$OUT/log.txt"; log "OpenCL ICD: ${lib:-}"; run ./caustica backends
for s in "$@"; do for f in $(functions "$s"); do log "##### $s: $f"; "$f"; done; done
