#!/bin/sh
# Installs what caustica's backends need on Debian bookworm, idempotently:
#   OpenCL: PoCL (pocl-opencl-icd) and the ICD loader (ocl-icd-libopencl1; the backend
#   opens libOpenCL.so.1 at run time, so no dev package is needed), from bookworm;
#   Vulkan/wgpu: Mesa's lavapipe with ray tracing (mesa-vulkan-drivers from
#   bookworm-backports), the Vulkan loader and the Khronos validation layer.
# Run as root it installs what is missing and does nothing when all is there; run as
# another user it prints what to install. The bookworm-backports source reuses the URI
# of the machine's existing bookworm source, so no mirror host name is written here.
set -eu

BOOKWORM_PKGS="pocl-opencl-icd ocl-icd-libopencl1 clinfo libvulkan1 vulkan-tools vulkan-validationlayers"
BACKPORTS_PKGS="mesa-vulkan-drivers"
BACKPORTS_LIST=/etc/apt/sources.list.d/caustica-bookworm-backports.sources

missing() {
    for p in "$@"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || echo "$p"
    done
}

# Mesa from backports reports VK_KHR_ray_tracing_pipeline; bookworm's Mesa 22 does not.
mesa_is_backport() {
    dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null | grep -q "bpo12"
}

# URI of the first enabled Debian bookworm source, deb822 or one-line format.
debian_uri() {
    for f in /etc/apt/sources.list.d/*.sources; do
        [ -f "$f" ] || continue
        awk 'BEGIN{RS=""} /Suites:[^\n]*bookworm( |\n|$)/ && !/Enabled: *no/ {
                 if (match($0, /URIs: *[^ \n]+/)) { s = substr($0, RSTART, RLENGTH);
                 sub(/URIs: */, "", s); print s; exit } }' "$f"
    done | head -n 1
    for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
        [ -f "$f" ] || continue
        awk '$1 == "deb" && $0 ~ / bookworm / { for (i = 2; i <= NF; i++)
                 if ($i ~ /^[a-z]+:\/\//) { print $i; exit } }' "$f"
    done | head -n 1
}

need_main=$(missing $BOOKWORM_PKGS)
need_bpo=""
mesa_is_backport || need_bpo=$BACKPORTS_PKGS

if [ -z "$need_main" ] && [ -z "$need_bpo" ]; then
    echo "install-drivers: everything is installed"
    exit 0
fi

if [ "$(id -u)" != 0 ]; then
    echo "install-drivers: not root; as root, install:"
    [ -n "$need_main" ] && echo "  apt-get install $need_main"
    [ -n "$need_bpo" ] && echo "  apt-get install -t bookworm-backports $need_bpo   (add bookworm-backports to your apt sources first)"
    exit 0
fi

export DEBIAN_FRONTEND=noninteractive
if [ -n "$need_bpo" ] && [ ! -f "$BACKPORTS_LIST" ]; then
    uri=$(debian_uri | head -n 1)
    if [ -z "$uri" ]; then
        echo "install-drivers: no bookworm source in /etc/apt to derive bookworm-backports from" >&2
        exit 1
    fi
    printf 'Types: deb\nURIs: %s\nSuites: bookworm-backports\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' \
        "$uri" >"$BACKPORTS_LIST"
fi
apt-get update -q
# shellcheck disable=SC2086
[ -n "$need_main" ] && apt-get install -y -q --no-install-recommends $need_main
# shellcheck disable=SC2086
[ -n "$need_bpo" ] && apt-get install -y -q --no-install-recommends -t bookworm-backports $need_bpo
echo "install-drivers: done"
