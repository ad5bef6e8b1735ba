#!/bin/bash
# Runs the GPU checks on the device machine (NVIDIA, no Rust toolchain there) from
# binaries built here: `scripts/gpu-run.sh --build` (here) strips the test, bench and CLI
# binaries into .devbin/ with the OpenCL ICD loader package; `scripts/gpu-run.sh` (there,
# through the device tool with `carry: [".devbin"]`) installs the loader and an ICD file
# naming the driver's libnvidia-opencl.so, then runs the OpenCL conformance suite, the
# photon-throughput benchmark and full-size frames, writing logs under $OUT.
set -uo pipefail
cd "$(dirname "$0")/.."

if [ "${1:-}" = "--build" ]; then
    set -e
    mkdir -p .devbin
    cargo build --release -p caustica
    cp target/release/caustica .devbin/
    cargo build --release -p caustica-conformance --example backend_diff
    cp target/release/examples/backend_diff .devbin/
    for spec in "caustica-opencl:device_layout" "caustica-conformance:cross_backend" \
                "caustica-conformance:cpu_reference" "caustica-conformance:optics_closed_form" \
                "caustica-vulkan:vulkan_backend" "caustica-conformance:frame_plan" \
                "caustica-conformance:stiff_cases" "caustica-conformance:every_kernel_dispatched" \
                "caustica-conformance:technique_seam" "caustica-conformance:hostile_input" \
                "caustica-conformance:large_frames" "caustica-conformance:filter_flux" \
                "caustica-conformance:caustic_map_frames" "caustica-conformance:adaptive_caustics_frames" \
                "caustica-conformance:submitted_frames"; do
        pkg=${spec%%:*}; t=${spec##*:}
        exe=$(cargo test --release -p "$pkg" --test "$t" --no-run --message-format=json 2>/dev/null |
              grep -o '"executable":"[^"]*"' | tail -n 1 | cut -d'"' -f4)
        cp "$exe" ".devbin/$t"
    done
    for spec in "caustica-opencl:photon_throughput:opencl_photon_throughput" "caustica:sspm_frame:sspm_frame" \
                "caustica:caustic_map_frame:caustic_map_frame" "caustica:adaptive_frame:adaptive_frame"; do
        IFS=: read -r pkg bench name <<<"$spec"
        # the bench's own executable (deps/<bench>-<hash>), not a binary built with it
        exe=$(cargo bench -p "$pkg" --bench "$bench" --no-run --message-format=json 2>/dev/null |
              grep -o '"executable":"[^"]*/deps/'"$bench"'-[^"]*"' | tail -n 1 | cut -d'"' -f4)
        cp "$exe" ".devbin/$name"
    done
    cargo build --release -p caustica --examples
    for ex in embed_wgpu embed_ash render_png frame_loop; do cp "target/release/examples/$ex" .devbin/; done
    cargo build --release -p caustica-conformance --example stiff_table --example adaptive_table
    cp target/release/examples/stiff_table target/release/examples/adaptive_table .devbin/
    strip .devbin/caustica .devbin/backend_diff .devbin/device_layout .devbin/cross_backend \
          .devbin/cpu_reference .devbin/optics_closed_form .devbin/opencl_photon_throughput \
          .devbin/sspm_frame .devbin/embed_wgpu .devbin/embed_ash .devbin/render_png .devbin/vulkan_backend .devbin/frame_plan \
          .devbin/stiff_cases .devbin/stiff_table .devbin/every_kernel_dispatched \
          .devbin/technique_seam .devbin/hostile_input .devbin/large_frames .devbin/filter_flux \
          .devbin/caustic_map_frames .devbin/caustic_map_frame .devbin/adaptive_caustics_frames \
          .devbin/adaptive_frame .devbin/adaptive_table .devbin/submitted_frames .devbin/frame_loop
    # what the device tool carries must stay under 64 MiB: the binaries travel gzipped
    (cd .devbin && for f in *; do case $f in *.deb|*.gz) ;; *) gzip -9 -f "$f" ;; esac; done)
    (cd .devbin && ls ocl-icd-libopencl1_*.deb >/dev/null 2>&1 || apt-get download ocl-icd-libopencl1)
    (cd .devbin && ls libglvnd0_*.deb >/dev/null 2>&1 || apt-get download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
    du -sh .devbin
    exit 0
fi

# Sections to run (default: all but hang): opencl wgpu vulkan plan stiff frames hostile filter
# countscan reach reachmask eq20 instances vulkanab instcheck hostcost dyn nonblock nonblock-opencl batches deform castercull corners framebench session12 dynmoves clexp cmexp giexp wgslexp session13 session14 session14gi session14tr session15 session16 session17 sass session13b hangstack seams cross photongi causticmap cmbench adaptive adaptivescreen adaptivefootprint shared adaptivebench hang
SECTIONS=${*:-opencl wgpu vulkan plan stiff frames hostile filter causticmap}
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
B=$PWD/.devbin
for f in "$B"/*.gz; do [ -f "$f" ] && gunzip -f "$f"; done
chmod +x "$B"/* 2>/dev/null
dpkg -x "$B"/ocl-icd-libopencl1_*.deb /tmp/ocl
# Vulkan loader and GL dispatch libraries (the NVIDIA Vulkan ICD, libGLX_nvidia, needs
# libglvnd), unpacked into / as the device tool's README says.
for f in "$B"/libvulkan1_*.deb "$B"/libglvnd0_*.deb "$B"/libegl1_*.deb "$B"/libopengl0_*.deb \
         "$B"/libgl1_*.deb "$B"/libglx0_*.deb "$B"/libgles2_*.deb; do
    [ -f "$f" ] && dpkg -x "$f" /
done
ldconfig
export LD_LIBRARY_PATH=/tmp/ocl/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
[ -f "$icd" ] && export VK_DRIVER_FILES=$icd
lib=$(find / -xdev \( -name 'libnvidia-opencl.so.1' -o -name 'libnvidia-opencl.so.*' \) 2>/dev/null | head -n 1)
mkdir -p /etc/OpenCL/vendors
echo "$lib" > /etc/OpenCL/vendors/nvidia.icd
echo "ICD: $lib"
nvidia-smi -L
run() { echo "=== $*"; "$@" 2>&1 | tee -a "$OUT/log.txt"; echo "=== exit ${PIPESTATUS[0]}"; }
cd "$B"
has() { case " $SECTIONS " in *" $1 "*) return 0;; esac; return 1; }
run ./caustica backends
if has opencl; then
    run ./device_layout
    run env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl ./cross_backend
    run env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl ./cpu_reference
    run ./optics_closed_form
    run ./backend_diff 960x540 512x512
    run env CAUSTICA_BENCH_GRID=1024 ./opencl_photon_throughput --bench
fi
if has wgpu; then
    run env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu ./cross_backend
    run ./backend_diff 960x540 512x512
    run timeout 60 ./embed_wgpu 1920x1080 2048
fi
if has vulkan; then
    run ./vulkan_backend
    run timeout 60 ./embed_ash 1920x1080 2048
    # the parallel run is known to hang NVIDIA's driver (see the issue notes): bounded
    run timeout 60 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend --test-threads=1
    run ./backend_diff 960x540 512x512
fi
if has plan; then
    run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./frame_plan --test-threads=1
    run timeout 120 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./every_kernel_dispatched --test-threads=1
    run timeout 120 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./technique_seam --test-threads=1
    run timeout 60 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cpu_reference --test-threads=1
fi
if has stiff; then
    run timeout 400 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./stiff_cases --test-threads=1 --include-ignored
    run timeout 300 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./stiff_table "$OUT/stability-gpu.md" --heavy
fi
if has frames; then
    run env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./sspm_frame --bench
fi
if has filter; then
    # issue 15: the density gather keeps the raw flux on every backend (per-kernel checks
    # run in the vulkan section's cross_backend)
    run timeout 120 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./filter_flux --test-threads=1
fi
if has photongi; then
    # issue 18: PhotonGi's kernels and frames against the CPU on every backend, and its
    # frame times at the chapter's high and low settings
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend photon_gi --test-threads=1
    run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./photon_gi_frames --test-threads=1 --nocapture
    run timeout 240 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./photon_gi_frame --bench
fi
if has countscan; then
    # issue 15 point 4: the count table's workgroup scans against the CPU, the flux test,
    # and the frame times of both gathers
    run timeout 120 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend density --test-threads=1
    run timeout 120 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./filter_flux --test-threads=1
    run timeout 300 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./sspm_frame --bench
fi
if has reach; then
    # issue 15 point 4: the density gather's reach grid; kernels and flux against the CPU
    # (screen and atlas), then both gathers' frame times in Sspm and CausticMap
    run timeout 120 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend density --test-threads=1
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend caustic_map --test-threads=1
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend sspm_matches_cpu_on_every --test-threads=1
    run timeout 120 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./filter_flux --test-threads=1
    run timeout 300 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./sspm_frame --bench
    run timeout 200 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} \
        CAUSTICA_BENCH_SPLITS=stochastic CAUSTICA_BENCH_GATHERS=density,box ./caustic_map_frame --bench
fi
if has cross; then
    # every per-kernel and per-frame comparison against the CPU, one test at a time
    run timeout 300 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend --test-threads=1
fi
if has seams; then
    # a new image size for every technique (issue 19 point 1), PhotonGi's importance and
    # uniform RSM sampling in the mean (issue 18 point 2), CausticMap's kernels with the
    # watertight atlas coverage
    run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./technique_seam --test-threads=1
    run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./photon_gi_frames importance --test-threads=1 --nocapture
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend caustic_map --test-threads=1
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend photon_gi --test-threads=1
fi
if has causticmap; then
    # issue 16: CausticMap's kernels and frames against the CPU on every backend, its stiff
    # cases, and its frame times at seed 001's three settings
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend caustic --test-threads=1
    run timeout 120 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./caustic_map_frames --test-threads=1
    run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./stiff_cases --test-threads=1 --nocapture
    run timeout 300 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./caustic_map_frame --bench
fi
if has adaptive; then
    # issue 17: AdaptiveCaustics' kernels and frames against the CPU on every backend, its
    # stiff cases, seed 004's Table 1 on spot-glass, and adaptive vs dense frame times
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend adaptive --test-threads=1
    run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./adaptive_caustics_frames --test-threads=1 --nocapture
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan \
        STIFF_CASES=small-caster,grazing-caster,light-inside-casters ./stiff_table "$OUT/stiff-adaptive.md"
    run timeout 240 ./adaptive_table vulkan ${ADAPTIVE_TOP:-8192} ${ADAPTIVE_REFERENCE:-16384}
    run timeout 300 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./adaptive_frame
fi
if has adaptivescreen; then
    # issue 17 point 4: the screen target's kernels and frames, and error against time of
    # the three caustic techniques with both AdaptiveCaustics targets
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend adaptive --test-threads=1
    run timeout 240 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./adaptive_caustics_frames --test-threads=1
    run timeout 240 ./caustica report --scenes sphere,cornell --backends ${REPORT_BACKENDS:-vulkan,opencl} \
        --techniques sspm,caustic-map,adaptive-caustics,adaptive-caustics:deposit=screen \
        --budgets 512x512,1024x1024,2048x2048,4096x4096 --repeats 3 --reference-noise 0.01 \
        --out "$OUT/report-adaptive-screen"
fi
if has adaptivefootprint; then
    # issue 17 point 2: the error metric's tolerance with footprint splats, on Table 1's scene
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend adaptive --test-threads=1
    run timeout 240 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./adaptive_caustics_frames --test-threads=1
    run timeout 400 env ERROR_TEXELS=1,2,4 ./adaptive_table vulkan ${ADAPTIVE_TOP:-8192} ${ADAPTIVE_REFERENCE:-16384}
fi
if has shared; then
    # the shared temporal and A-Trous passes (issue 18), set_materials and set_lights
    # (issue 19) on the GPUs
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend temporal --test-threads=1
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend atrous --test-threads=1
    run timeout 240 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./temporal_frames --test-threads=1 --nocapture
    run timeout 240 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./technique_seam --test-threads=1
    run timeout 120 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./every_kernel_dispatched --test-threads=1
fi
if has adaptivebench; then
    # issue 17: adaptive vs dense frame times alone, with per-level times
    run timeout 300 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./adaptive_frame
fi
if has reachmask; then
    # issue 16 point 6 and the G-buffer's geometric normal: every per-kernel and per-frame
    # comparison against the CPU (deposit_atlas's reach mask bitwise, primary_gbuffer's
    # geometric normal), CausticMap's frames (tiles only for reached receivers), PhotonGi's
    # stiff cases (a blind light gets no photon), the update seams, CausticMap's frame times
    run timeout 300 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend --test-threads=1
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./caustic_map_frames --test-threads=1
    [ -x ./photon_gi_stiff ] && run timeout 100 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./photon_gi_stiff --test-threads=1 --nocapture
    [ -x ./technique_seam ] && run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./technique_seam --test-threads=1
    run timeout 200 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} \
        CAUSTICA_BENCH_SPLITS=stochastic CAUSTICA_BENCH_GATHERS=box ./caustic_map_frame --bench
fi
if has eq20; then
    # issue 18 point 4 (Eq. 20): PhotonGi's kernels (the splat's direction map, the
    # correction) and frames against the CPU, its stiff cases, and its frame times
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend photon_gi --test-threads=1
    run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./photon_gi_frames --test-threads=1 --nocapture
    run timeout 100 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./photon_gi_stiff --test-threads=1
    run timeout 240 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./photon_gi_frame --bench
fi
if has instances; then
    # issue 19 point 1: the two-level acceleration structure on the GPUs: every per-kernel
    # and per-frame comparison against the CPU (generated scenes make half their casters
    # instances), moved instances against fresh techniques bitwise, the update seams; then
    # the dynamic-scene benchmark (point 6) and the static frame for comparison
    run timeout 300 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend --test-threads=1
    run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./instance_updates --test-threads=1 --nocapture
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./technique_seam --test-threads=1
    run timeout 240 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./dynamic_frame --bench
    run timeout 200 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} CAUSTICA_BENCH_FILTERS=density ./sspm_frame --bench
fi
if has vulkanab; then
    # Vulkan's Sspm frame before the two-level acceleration structure (sspm_frame_old, built
    # from 9f38028) and after, alternated on one machine: is a slowdown the change's or
    # the machine's? Then the dynamic benchmark (the in-frame TLAS refit) and PhotonGi's
    # kernel comparison with the first differing RSM texel named
    nvidia-smi --query-gpu=clocks.sm,clocks.mem,power.draw,temperature.gpu --format=csv
    for i in 1 2; do
        [ -x ./sspm_frame_old ] && run timeout 100 env CAUSTICA_BENCH_BACKENDS=vulkan CAUSTICA_BENCH_FILTERS=density ./sspm_frame_old --bench
        run timeout 100 env CAUSTICA_BENCH_BACKENDS=vulkan CAUSTICA_BENCH_FILTERS=density ./sspm_frame --bench
    done
    nvidia-smi --query-gpu=clocks.sm,clocks.mem,power.draw,temperature.gpu --format=csv
    run timeout 240 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./dynamic_frame --bench
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend photon_gi --test-threads=1
    run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./instance_updates --test-threads=1
fi
if has instcheck; then
    # issue 19 after the in-frame TLAS refit and the deferred update writes: the whole
    # cross-backend suite, moved instances against fresh techniques, the update seams, the
    # dynamic benchmark, then the stiff catalogue (instance scales 1e-4 and 1e5 among it)
    run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend --test-threads=1
    run timeout 100 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./instance_updates --test-threads=1 --nocapture
    run timeout 100 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./technique_seam --test-threads=1
    run timeout 150 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./dynamic_frame --bench
    run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./stiff_cases --test-threads=1
fi
if has hostcost; then
    # issue 19 point 3: Vulkan's pooled descriptor and query pools and its host arena;
    # a first Vulkan run warms the machine up (a fresh one runs Vulkan 3-4x slower for
    # about a minute: docs/gpu/h200-session9-vulkan-ab.log), then the frames and the
    # dynamic scene on every GPU backend
    run timeout 100 env CAUSTICA_BENCH_BACKENDS=vulkan CAUSTICA_BENCH_FILTERS=density CAUSTICA_BENCH_FRAMES=20 ./sspm_frame --bench
    run timeout 200 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} CAUSTICA_BENCH_FILTERS=density ./sspm_frame --bench
    run timeout 200 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./dynamic_frame --bench
    run timeout 100 env CAUSTICA_REQUIRE_BACKENDS=cpu,vulkan ./instance_updates --test-threads=1
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,vulkan ./cross_backend --test-threads=1
fi
if has dyn; then
    # issue 19 point 6 again after cheaper moves: warm Vulkan up, then the dynamic scene
    run timeout 100 env CAUSTICA_BENCH_BACKENDS=vulkan CAUSTICA_BENCH_FILTERS=density CAUSTICA_BENCH_FRAMES=20 ./sspm_frame --bench
    run timeout 200 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./dynamic_frame --bench
fi
if has nonblock-opencl; then
    # OpenCL's non-blocking line alone, and its submitted frames
    run timeout 150 env CAUSTICA_BENCH_BACKENDS=opencl CAUSTICA_BENCH_FILTERS=density ./sspm_frame --bench
    run timeout 100 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl ./submitted_frames --test-threads=1
fi
if has nonblock; then
    # issue 19 points 2 and 3: warm Vulkan up; the non-blocking frames against the
    # blocking ones on every backend (bitwise, several in flight); sspm_frame with its
    # pipelined line (submit, wall per frame, device passes); the wgpu host's frame loop
    run timeout 100 env CAUSTICA_BENCH_BACKENDS=vulkan CAUSTICA_BENCH_FILTERS=density CAUSTICA_BENCH_FRAMES=20 ./sspm_frame --bench
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./submitted_frames --test-threads=1 --nocapture
    run timeout 240 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} CAUSTICA_BENCH_FILTERS=density ./sspm_frame --bench
    run timeout 60 ./frame_loop 1920x1080 2048 100
    run timeout 60 ./frame_loop 1920x1080 1024 100
fi
if has batches; then
    # issue 19 point 4, the "fewer, larger batches" lever: Sspm's 2048^2 photons in one
    # batch instead of four of 2^20 (run after `nonblock`, whose sspm_frame is the default)
    run timeout 240 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} CAUSTICA_BENCH_FILTERS=density \
        CAUSTICA_BENCH_SETTINGS='{"max_photons_per_batch": 4194304}' ./sspm_frame --bench
fi
if has deform; then
    # issue 19 points 1, 4 and 6: Sspm's frame with this build's defaults (one batch of
    # 2048^2 photons; also Vulkan's warm-up); deformed instances bitwise against fresh
    # builds on every backend, Vulkan building the deformed level's BLAS only; the dynamic
    # scene with a deformation per frame
    run timeout 150 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} CAUSTICA_BENCH_FILTERS=density ./sspm_frame --bench
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./instance_updates --test-threads=1 --nocapture
    run timeout 60 ./vulkan_backend --test-threads=1
    run timeout 300 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./dynamic_frame --bench
fi
if has castercull; then
    # The first-segment caster-ball test (core's device::caster_spheres): trace_photons on
    # every backend against the CPU and against itself without the test (its notes say how
    # many photons the test ended), then Sspm's and CausticMap's frames.
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend trace_photons --test-threads=1 --nocapture
    run timeout 100 env CAUSTICA_BENCH_BACKENDS=vulkan CAUSTICA_BENCH_FILTERS=density CAUSTICA_BENCH_FRAMES=20 ./sspm_frame --bench
    run timeout 240 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} CAUSTICA_BENCH_FILTERS=density ./sspm_frame --bench
    run timeout 200 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} \
        CAUSTICA_BENCH_SPLITS=stochastic CAUSTICA_BENCH_GATHERS=box ./caustic_map_frame --bench
fi
if has corners || has session12; then
    # Triangle corners read from the node buffer's corner region (core's
    # acceleration::TRIANGLE_CORNER_VEC4S) and wgpu's kernels without naga's loop
    # bounding: the whole cross-backend suite and the instance updates, then the frames.
    run timeout 300 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend --test-threads=1
    run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./instance_updates --test-threads=1
    run timeout 100 env CAUSTICA_BENCH_BACKENDS=vulkan CAUSTICA_BENCH_FILTERS=density CAUSTICA_BENCH_FRAMES=20 ./sspm_frame --bench
    run timeout 240 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} CAUSTICA_BENCH_FILTERS=density ./sspm_frame --bench
    run timeout 200 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} \
        CAUSTICA_BENCH_SPLITS=stochastic CAUSTICA_BENCH_GATHERS=box ./caustic_map_frame --bench
fi
if has framebench; then
    # Sspm's and CausticMap's frames alone (a rerun on a warm machine)
    run timeout 240 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} CAUSTICA_BENCH_FILTERS=density ./sspm_frame --bench
    run timeout 200 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} \
        CAUSTICA_BENCH_SPLITS=stochastic CAUSTICA_BENCH_GATHERS=box ./caustic_map_frame --bench
    [ -x ./photon_gi_frame ] && run timeout 240 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./photon_gi_frame --bench
fi
if has session12; then
    # The closing run of session 12: the `corners` section above, then the dynamic scene's
    # update cost.
    run timeout 200 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./dynamic_frame --bench
fi
if has dynmoves; then
    # issue 19 point 6 as stated: light and glass objects moving, no deformation
    run timeout 100 env CAUSTICA_BENCH_BACKENDS=vulkan CAUSTICA_BENCH_FILTERS=density CAUSTICA_BENCH_FRAMES=20 ./sspm_frame --bench
    run timeout 200 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} CAUSTICA_BENCH_DEFORM=0 ./dynamic_frame --bench
fi
if has session13; then
    # Tile order of the photon grid (core's math::sampling::tiled_photon_index): the
    # cross-backend suite, then Sspm's and CausticMap's frames on every GPU backend.
    run timeout 300 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend --test-threads=1
    # a warm-up: a process's first frames on a fresh machine run 3-4x slow
    run timeout 100 env CAUSTICA_BENCH_BACKENDS=vulkan,wgpu CAUSTICA_BENCH_FRAMES=5 ./sspm_frame --bench > /dev/null 2>&1
    run timeout 240 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} CAUSTICA_BENCH_FILTERS=density ./sspm_frame --bench
    run timeout 200 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} \
        CAUSTICA_BENCH_SPLITS=stochastic CAUSTICA_BENCH_GATHERS=box ./caustic_map_frame --bench
fi
if has session13b; then
    # The relaxed-division program (backend-opencl's RELAXED_DIVISION_KERNELS): the gather
    # checks on OpenCL, a warm-up, then the frames on every GPU backend.
    run timeout 120 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl ./cross_backend density_gather sspm --test-threads=1
    run timeout 100 env CAUSTICA_BENCH_BACKENDS=vulkan,wgpu CAUSTICA_BENCH_FRAMES=5 ./sspm_frame --bench > /dev/null 2>&1
    run timeout 240 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} CAUSTICA_BENCH_FILTERS=density ./sspm_frame --bench
    run timeout 200 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} \
        CAUSTICA_BENCH_SPLITS=stochastic CAUSTICA_BENCH_GATHERS=box ./caustic_map_frame --bench
fi
if has clexp; then
    # OpenCL kernel experiments without a rebuild: every folder .devbin/exp/<name>/ (or
    # $CLEXP_DIR/<name>/, an absolute path) holds changed kernel files (backend-opencl's
    # CAUSTICA_OPENCL_KERNEL_DIR); the built-in kernels run first as `base`, with their
    # programs dumped (on NVIDIA: PTX) for ptxas.
    PTXAS=$(command -v ptxas || ls /usr/local/cuda*/bin/ptxas 2>/dev/null | head -n 1)
    for dir in base "${CLEXP_DIR:-$B/exp}"/*; do
        name=$(basename "$dir")
        mkdir -p "$OUT/ptx-$name"
        if [ "$name" = base ]; then kd=/nonexistent; else kd=$dir; fi
        run timeout 120 env CAUSTICA_OPENCL_KERNEL_DIR=$kd CAUSTICA_OPENCL_DUMP_DIR="$OUT/ptx-$name" \
            CAUSTICA_BENCH_BACKENDS=opencl CAUSTICA_BENCH_FILTERS=density CAUSTICA_BENCH_FRAMES=${EXP_FRAMES:-10} ./sspm_frame --bench
        for f in "$OUT/ptx-$name"/trace_photons*.bin; do
            [ -f "$f" ] && [ -n "$PTXAS" ] && echo "ptxas $name $(basename "$f"): $(timeout 60 "$PTXAS" -arch=sm_90 -v "$f" -o /dev/null 2>&1 | grep -E 'registers|spill|stack' | tr '\n' ' ')" | tee -a "$OUT/log.txt"
        done
    done
fi
if has cmexp; then
    # clexp for CausticMap: the built-in kernels (`base`, programs dumped) and every folder
    # under .devbin/exp/, each timed on seed 001's settings 0 and 1 (box gather) on OpenCL.
    for dir in base "$B"/exp/*; do
        name=$(basename "$dir")
        mkdir -p "$OUT/ptx-$name"
        if [ "$name" = base ]; then kd=/nonexistent; else kd=$dir; fi
        run timeout 150 env CAUSTICA_OPENCL_KERNEL_DIR=$kd CAUSTICA_OPENCL_DUMP_DIR="$OUT/ptx-$name" \
            CAUSTICA_BENCH_BACKENDS=opencl CAUSTICA_BENCH_SETTINGS=${EXP_SETTINGS:-0,1} CAUSTICA_BENCH_SPLITS=stochastic \
            CAUSTICA_BENCH_GATHERS=box CAUSTICA_BENCH_FRAMES=${EXP_FRAMES:-10} CAUSTICA_BENCH_WARMUP_MS=1500 ./caustic_map_frame --bench
        [ "$name" = base ] || rm -rf "$OUT/ptx-$name"
    done
fi
if has session14; then
    # The covered-tile gather (core::math::map_gather::TILE_FULLY_COVERED): CausticMap's
    # kernel and frame checks on every backend, its frames at seed 001's settings, then
    # OpenCL's trace under register caps (CAUSTICA_OPENCL_OPTIONS).
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend caustic_map --test-threads=1
    run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./caustic_map_frames --test-threads=1
    run timeout 300 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} \
        CAUSTICA_BENCH_SPLITS=stochastic CAUSTICA_BENCH_GATHERS=box,density ./caustic_map_frame --bench
    for r in ${REG_CAPS:-64 80 96}; do
        run timeout 100 env CAUSTICA_OPENCL_OPTIONS="-cl-nv-maxrregcount=$r" CAUSTICA_BENCH_BACKENDS=opencl \
            CAUSTICA_BENCH_SETTINGS=0 CAUSTICA_BENCH_SPLITS=stochastic CAUSTICA_BENCH_GATHERS=box \
            CAUSTICA_BENCH_FRAMES=10 CAUSTICA_BENCH_WARMUP_MS=1500 ./caustic_map_frame --bench
    done
fi
if has giexp; then
    # clexp for PhotonGi: the built-in kernels and every folder under .devbin/exp/, each
    # timed on the chapter's settings (photon_gi_frame) on OpenCL.
    for dir in base "$B"/exp/*; do
        name=$(basename "$dir")
        if [ "$name" = base ]; then kd=/nonexistent; else kd=$dir; fi
        run timeout 150 env CAUSTICA_OPENCL_KERNEL_DIR=$kd CAUSTICA_BENCH_BACKENDS=opencl \
            CAUSTICA_BENCH_SETTINGS=${EXP_SETTINGS:-high,low} CAUSTICA_BENCH_FRAMES=${EXP_FRAMES:-5} \
            CAUSTICA_BENCH_WARMUP_MS=1500 ./photon_gi_frame --bench
    done
fi
if has wgslexp; then
    # giexp for the WGSL kernels (wgpu, and Vulkan's compute kernels): the built-in texts
    # and every folder under .devbin/wexp/ (CAUSTICA_WGSL_KERNEL_DIR), each timed on the
    # chapter's settings (photon_gi_frame).
    for dir in base "$B"/wexp/*; do
        name=$(basename "$dir")
        if [ "$name" = base ]; then kd=/nonexistent; else kd=$dir; fi
        echo "wgslexp: $name" | tee -a "$OUT/log.txt"
        run timeout 150 env CAUSTICA_WGSL_KERNEL_DIR=$kd CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu} \
            CAUSTICA_BENCH_SETTINGS=${EXP_SETTINGS:-high} CAUSTICA_BENCH_FRAMES=${EXP_FRAMES:-5} \
            CAUSTICA_BENCH_WARMUP_MS=1500 ./photon_gi_frame --bench
    done
fi
if has session14gi; then
    # PhotonGi's splat with staged G-buffer loads in the relaxed-division program
    # (backend-opencl's RELAXED_DIVISION_KERNELS): its checks and frames on every backend.
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend photon_gi --test-threads=1
    run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./photon_gi_frames --test-threads=1
    run timeout 240 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./photon_gi_frame --bench
fi
if has session14tr; then
    # trace_photons' variant programs with OpenCL's default division bounds
    # (backend-opencl's RELAXED_DIVISION_VARIANTS): its checks, then OpenCL's frames.
    run timeout 120 env CAUSTICA_BENCH_BACKENDS=opencl CAUSTICA_BENCH_FILTERS=density CAUSTICA_BENCH_FRAMES=10 ./sspm_frame --bench
    run timeout 120 env CAUSTICA_BENCH_BACKENDS=opencl CAUSTICA_BENCH_SETTINGS=0,1 CAUSTICA_BENCH_SPLITS=stochastic \
        CAUSTICA_BENCH_GATHERS=box CAUSTICA_BENCH_FRAMES=10 ./caustic_map_frame --bench
    run timeout 120 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl CAUSTICA_SKIP_BACKENDS=wgpu,vulkan ./cross_backend trace_photons sspm caustic --test-threads=1
    [ -x ./stiff_cases ] && run timeout 120 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl CAUSTICA_SKIP_BACKENDS=wgpu,vulkan ./stiff_cases --test-threads=1
fi
if has session15; then
    # CausticMap's fused trace (trace_photons' FUSED_DEPOSIT variant: each stored photon
    # straight into the atlas, no separate deposit pass): its frames at seed 001's settings,
    # then its kernel, frame and stiff checks on every backend.
    run timeout 240 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} \
        CAUSTICA_BENCH_FRAMES=${EXP_FRAMES:-20} CAUSTICA_BENCH_SPLITS=stochastic \
        CAUSTICA_BENCH_GATHERS=box ./caustic_map_frame --bench
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend caustic trace_photons --test-threads=1
    run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./caustic_map_frames --test-threads=1
    [ -x ./stiff_cases ] && run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./stiff_cases --test-threads=1
fi
if has session16; then
    # PhotonGi's workgroup splat (a group walks all its splats' pixels together; `giexp`
    # with .devbin/exp/old/ times the per-photon loop it replaced on OpenCL): every
    # backend's frames and checks. Then Sspm's fused deposit (trace_photons' FUSED_DEPOSIT)
    # against the separate deposit pass, and its check on every backend.
    run timeout 240 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./photon_gi_frame --bench
    run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend photon_gi --test-threads=1
    run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./photon_gi_frames --test-threads=1
    for fused in false true; do
        run timeout 150 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} CAUSTICA_BENCH_FILTERS=density \
            CAUSTICA_BENCH_FRAMES=${EXP_FRAMES:-10} CAUSTICA_BENCH_SETTINGS="{\"fused_deposit\": $fused}" ./sspm_frame --bench
    done
    run timeout 120 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend sspm_fused --test-threads=1
    [ -x ./photon_gi_stiff ] && run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./photon_gi_stiff --test-threads=1
    [ -x ./every_kernel_dispatched ] && run timeout 120 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./every_kernel_dispatched --test-threads=1
fi
if has session17; then
    # Deposits with every low word's add before any carry, OpenCL's filter weights with
    # native functions: PhotonGi, Sspm and CausticMap frames on every backend, then the
    # checks of every kernel, frame and stiff case they touch on every backend.
    run timeout 150 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./photon_gi_frame --bench
    run timeout 150 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} CAUSTICA_BENCH_FILTERS=density \
        CAUSTICA_BENCH_FRAMES=${EXP_FRAMES:-10} ./sspm_frame --bench
    run timeout 150 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} CAUSTICA_BENCH_FRAMES=${EXP_FRAMES:-10} \
        CAUSTICA_BENCH_SETTINGS=0,1 CAUSTICA_BENCH_SPLITS=stochastic CAUSTICA_BENCH_GATHERS=box ./caustic_map_frame --bench
    run timeout 200 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./cross_backend --test-threads=1
    for t in photon_gi_frames caustic_map_frames photon_gi_stiff stiff_cases; do
        [ -x ./$t ] && run timeout 150 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./$t --test-threads=1
    done
fi
if has sass; then
    # The OpenCL programs NVIDIA's driver builds, as PTX (CAUSTICA_OPENCL_DUMP_DIR), then
    # ptxas's register and spill counts and the SASS of the trace kernels, packed into
    # $OUT/sass.tgz, to count the instructions a traversal step issues.
    PTXAS=$(command -v ptxas || ls /usr/local/cuda*/bin/ptxas 2>/dev/null | head -n 1)
    CUOBJ=$(command -v cuobjdump || ls /usr/local/cuda*/bin/cuobjdump 2>/dev/null | head -n 1)
    echo "ptxas: $PTXAS cuobjdump: $CUOBJ" | tee -a "$OUT/log.txt"
    rm -rf /tmp/sass && mkdir -p /tmp/sass/ptx
    run timeout 120 env CAUSTICA_OPENCL_DUMP_DIR=/tmp/sass/ptx CAUSTICA_BENCH_BACKENDS=opencl \
        CAUSTICA_BENCH_SETTINGS=high CAUSTICA_BENCH_FRAMES=3 CAUSTICA_BENCH_WARMUP_MS=300 ./photon_gi_frame --bench
    run timeout 120 env CAUSTICA_OPENCL_DUMP_DIR=/tmp/sass/ptx CAUSTICA_BENCH_BACKENDS=opencl \
        CAUSTICA_BENCH_FILTERS=density CAUSTICA_BENCH_FRAMES=3 CAUSTICA_BENCH_WARMUP_MS=300 ./sspm_frame --bench
    for f in /tmp/sass/ptx/*.bin; do
        n=$(basename "$f" .bin)
        # the driver's program binary is PTX text with a trailing NUL
        tr -d '\000' < "$f" > "/tmp/sass/$n.ptx"
        timeout 120 "$PTXAS" -arch=sm_90 -v "/tmp/sass/$n.ptx" -o "/tmp/sass/$n.cubin" > "/tmp/sass/$n.ptxas.txt" 2>&1
        grep -E -A3 "entry function '(trace_|splat_)" "/tmp/sass/$n.ptxas.txt" | grep -E "entry|Used|spill|stack|rror" | tee -a "$OUT/log.txt"
        [ -f "/tmp/sass/$n.cubin" ] && timeout 120 "$CUOBJ" -sass "/tmp/sass/$n.cubin" > "/tmp/sass/$n.sass" 2>&1
    done
    (cd /tmp && tar czf "$OUT/sass.tgz" sass)
fi
if has cmbench; then
    # CausticMap's frame times alone (CAUSTICA_BENCH_SPLITS / _GATHERS pick the variants)
    run timeout 400 env CAUSTICA_BENCH_BACKENDS=${BENCH_BACKENDS:-vulkan,wgpu,opencl} ./caustic_map_frame --bench
fi
if has hang; then
    # issue 19 point 5: which backends, run in parallel threads of one process, hang
    # NVIDIA's driver. HANG_SKIPS lists the CAUSTICA_SKIP_BACKENDS values to try (space-
    # separated, "-" for none), HANG_RUNS the runs of each; every run is bounded.
    for skip in ${HANG_SKIPS:-- wgpu vulkan opencl}; do
        [ "$skip" = "-" ] && skip=""
        for k in $(seq 1 "${HANG_RUNS:-3}"); do
            start=$(date +%s)
            env CAUSTICA_SKIP_BACKENDS="$skip" timeout "${HANG_TIMEOUT:-40}" ./cross_backend \
                > /tmp/hang.log 2>&1
            rc=$?
            last=$(grep -E '^test |\*\*\*' /tmp/hang.log | tail -n 1)
            echo "hang: serialize=${CAUSTICA_SERIALIZE_DRIVERS:-1} skip=[$skip] run $k: exit $rc after $(( $(date +%s) - start )) s; last line: $last" |
                tee -a "$OUT/log.txt"
        done
    done
fi
if has hangdiag; then
    # issue 19 point 5: what a hung parallel run is doing: GPU utilisation and every
    # thread's kernel wait channel and state, 25 s into a run that has not finished
    for k in $(seq 1 "${HANG_RUNS:-8}"); do
        ./cross_backend > /tmp/hangdiag.log 2>&1 &
        pid=$!
        for s in $(seq 1 25); do kill -0 "$pid" 2>/dev/null || break; sleep 1; done
        if kill -0 "$pid" 2>/dev/null; then
            echo "hangdiag: run $k hung; last line: $(grep -E '^test |\*\*\*' /tmp/hangdiag.log | tail -n 1)" | tee -a "$OUT/log.txt"
            nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv | tee -a "$OUT/log.txt"
            for t in /proc/$pid/task/*; do
                echo "thread $(basename "$t") $(cat "$t/comm") state=$(awk '{print $3}' "$t/stat") wchan=$(cat "$t/wchan" 2>/dev/null)"
            done | tee -a "$OUT/log.txt"
            dmesg 2>/dev/null | grep -i xid | tail -n 5 | tee -a "$OUT/log.txt"
            kill -9 "$pid"
            break
        fi
        wait "$pid"
        echo "hangdiag: run $k finished" | tee -a "$OUT/log.txt"
    done
fi
if has hangstack; then
    # issue 19 point 5: user-space stacks of every thread of a hung parallel run (eu-stack
    # from elfutils, unpacked from .devbin: the device image has no gdb). The driver lock
    # is off (CAUSTICA_SERIALIZE_DRIVERS=0) so that a hang is likely; at most HANG_RUNS
    # runs, stopping at the first hang.
    for f in "$B"/elfutils_*.deb "$B"/libdw1_*.deb "$B"/libelf1_*.deb "$B"/libasm1_*.deb; do
        [ -f "$f" ] && dpkg -x "$f" /tmp/eu
    done
    EU="env LD_LIBRARY_PATH=/tmp/eu/usr/lib/x86_64-linux-gnu /tmp/eu/usr/bin/eu-stack"
    for k in $(seq 1 "${HANG_RUNS:-8}"); do
        start=$(date +%s)
        env CAUSTICA_SERIALIZE_DRIVERS=0 ./cross_backend > /tmp/hangstack.log 2>&1 &
        pid=$!
        # a passing run takes 14-21 s on a warm machine, up to 3-4x that in a fresh
        # machine's first minute: HANG_AFTER (default 60 s) calls it hung
        for s in $(seq 1 "${HANG_AFTER:-60}"); do kill -0 "$pid" 2>/dev/null || break; sleep 1; done
        if kill -0 "$pid" 2>/dev/null; then
            echo "hangstack: run $k hung; last line: $(grep -E '^test |\*\*\*' /tmp/hangstack.log | tail -n 1)" | tee -a "$OUT/log.txt"
            nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv | tee -a "$OUT/log.txt"
            for t in /proc/$pid/task/*; do
                echo "thread $(basename "$t") $(cat "$t/comm") state=$(awk '{print $3}' "$t/stat") wchan=$(cat "$t/wchan" 2>/dev/null)"
            done | tee -a "$OUT/log.txt"
            timeout 60 $EU -p "$pid" -m -s 2>&1 | head -n 600 | tee -a "$OUT/log.txt"
            kill -9 "$pid"
            break
        fi
        wait "$pid"
        echo "hangstack: run $k finished in $(( $(date +%s) - start )) s ($(grep -E '^test result' /tmp/hangstack.log | tail -n 1))" | tee -a "$OUT/log.txt"
    done
fi
if has hostile; then
    # issue 14: hostile scenes on every backend, large frames, 8192x8192 where it fits
    run timeout 240 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./hostile_input --test-threads=1
    run timeout 300 env CAUSTICA_REQUIRE_BACKENDS=cpu,opencl,wgpu,vulkan ./large_frames --test-threads=1
    for be in vulkan wgpu opencl; do
        run timeout 120 ./caustica render --scene sphere --backend $be --size 8192x8192 \
            --photons 1024x1024 --out "$OUT/render-8192-$be"
        rm -f "$OUT/render-8192-$be"/*.exr "$OUT/render-8192-$be"/*.png
    done
fi
