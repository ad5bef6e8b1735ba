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
                "caustica-conformance:cpu_reference" "caustica-conformance:optics_closed_form"; do
        pkg=${spec%%:*}; t=${spec##*:}
        exe=$(cargo test --release -p "$pkg" --test "$t" --no-run --message-format=json 2>/dev/null |
              grep -o '"executable":"[^"]*"' | tail -n 1 | cut -d'"' -f4)
        cp "$exe" ".devbin/$t"
    done
    exe=$(cargo bench -p caustica-opencl --bench photon_throughput --no-run --message-format=json 2>/dev/null |
          grep -o '"executable":"[^"]*"' | tail -n 1 | cut -d'"' -f4)
    cp "$exe" .devbin/opencl_photon_throughput
    strip .devbin/caustica .devbin/backend_diff .devbin/device_layout .devbin/cross_backend \
          .devbin/cpu_reference .devbin/optics_closed_form .devbin/opencl_photon_throughput
    (cd .devbin && ls ocl-icd-libopencl1_*.deb >/dev/null 2>&1 || apt-get download ocl-icd-libopencl1)
    du -sh .devbin
    exit 0
fi

OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
B=$PWD/.devbin
dpkg -x "$B"/ocl-icd-libopencl1_*.deb /tmp/ocl
export LD_LIBRARY_PATH=/tmp/ocl/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
lib=$(find / -xdev \( -name 'libnvidia-opencl.so.1' -o -name 'libnvidia-opencl.so.*' \) 2>/dev/null | head -n 1)
mkdir -p /etc/OpenCL/vendors
echo "$lib" > /etc/OpenCL/vendors/nvidia.icd
echo "ICD: $lib"
nvidia-smi -L
run() { echo "=== $*"; "$@" 2>&1 | tee -a "$OUT/log.txt"; echo "=== exit ${PIPESTATUS[0]}"; }
cd "$B"
run ./caustica backends
run ./device_layout
CAUSTICA_REQUIRE_BACKENDS=cpu,opencl run ./cross_backend
CAUSTICA_REQUIRE_BACKENDS=cpu,opencl run ./cpu_reference
run ./optics_closed_form
run ./backend_diff 960x540 512x512
CAUSTICA_BENCH_GRID=1024 run ./opencl_photon_throughput --bench
for s in sphere cornell; do
    for b in opencl cpu; do
        run ./caustica render --scene $s --backend $b --photons 2048x2048 --size 1920x1080 --out "/tmp/r/$s-$b"
        # the second frame: programs built, caches warm
        run ./caustica render --scene $s --backend $b --photons 2048x2048 --size 1920x1080 --out "/tmp/r/$s-$b"
        cp "/tmp/r/$s-$b/stats.json" "$OUT/$s-$b.json"
    done
done
