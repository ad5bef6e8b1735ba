#!/bin/sh
# Checks that a built `caustica` binary neither links nor needs the OpenCL ICD loader
# (a default build links no driver library; the OpenCL backend opens
# libOpenCL.so.1 at run time):
#   (a) readelf shows no libOpenCL among the binary's NEEDED libraries;
#   (b) with every libOpenCL.so* on this machine hidden (an empty file bind-mounted over
#       it in a private mount namespace, so dlopen fails), `caustica backends` exits 0
#       and says that opencl is unavailable because of the loader, and a CPU render of
#       the sphere scene succeeds and writes its images.
# Usage: scripts/check-no-opencl-link.sh [path/to/caustica]
#   default: $CARGO_TARGET_DIR/release/caustica, else target/release/caustica.
# Build it first: cargo build --release -p caustica
# Part (b) needs a private mount namespace: run as root (or where `unshare -r -m` works).
set -eu

cd "$(dirname "$0")/.."
bin=${1:-${CARGO_TARGET_DIR:-target}/release/caustica}
if [ ! -x "$bin" ]; then
    echo "check-no-opencl-link: no executable at $bin (cargo build --release -p caustica)" >&2
    exit 1
fi
case $bin in /*) ;; *) bin=$PWD/$bin ;; esac
command -v readelf >/dev/null || { echo "check-no-opencl-link: readelf (binutils) is missing" >&2; exit 1; }
command -v unshare >/dev/null || { echo "check-no-opencl-link: unshare (util-linux) is missing" >&2; exit 1; }

# (a) nothing links libOpenCL.
needed=$(readelf -d "$bin" | grep NEEDED || true)
if printf '%s\n' "$needed" | grep -qi libOpenCL; then
    echo "check-no-opencl-link: FAIL: $bin links the OpenCL loader:" >&2
    printf '%s\n' "$needed" | grep -i libOpenCL >&2
    exit 1
fi
echo "check-no-opencl-link: ok: $bin does not link libOpenCL"

# (b) runs without the loader. The files to hide: every libOpenCL.so* the dynamic linker
# knows (ldconfig's cache) or that lies in the usual library folders, resolved to real
# files, each once.
loaders=$( (ldconfig -p 2>/dev/null | awk '/libOpenCL\.so/ { print $NF }'
            ls /lib/*/libOpenCL.so* /usr/lib/*/libOpenCL.so* /lib/libOpenCL.so* \
               /usr/lib/libOpenCL.so* /usr/local/lib/libOpenCL.so* 2>/dev/null || true) |
          while read -r f; do readlink -f "$f"; done | sort -u)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
if [ "$(id -u)" = 0 ]; then ns="unshare -m"; else ns="unshare -r -m"; fi

# The script that runs inside the namespace; its arguments: binary, output folder, then
# the files to hide.
inner='set -eu
bin=$1; out=$2; shift 2
for f in "$@"; do mount --bind /dev/null "$f"; done
unset OPENCL_DYLIB_PATH
echo "check-no-opencl-link: hidden: ${*:-nothing (no loader installed)}"
if ! "$bin" backends >"$out/backends.txt" 2>&1; then
    cat "$out/backends.txt" >&2
    echo "check-no-opencl-link: FAIL: caustica backends failed without the OpenCL loader" >&2
    exit 1
fi
cat "$out/backends.txt"
if ! grep -Eq "^opencl +unavailable .*libOpenCL" "$out/backends.txt"; then
    echo "check-no-opencl-link: FAIL: caustica backends does not say that opencl is unavailable for want of the loader" >&2
    exit 1
fi
"$bin" render --scene sphere --technique sspm --backend cpu --photons 64x64 --out "$out/render" || {
    echo "check-no-opencl-link: FAIL: a CPU render failed without the OpenCL loader" >&2
    exit 1
}
for f in stats.json sphere_composite.png; do
    [ -s "$out/render/$f" ] || { echo "check-no-opencl-link: FAIL: the render wrote no $f" >&2; exit 1; }
done'
# shellcheck disable=SC2086
$ns sh -c "$inner" check-no-opencl-link "$bin" "$out" $loaders
echo "check-no-opencl-link: ok: without the OpenCL loader, opencl is unavailable and a CPU render works"
