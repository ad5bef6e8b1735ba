#!/usr/bin/env bash
# bevy_caustica in CI: finds a toolchain that builds Bevy 0.20 (rust-version 1.97.1):
# stable >= 1.97.1 as is, else a nightly >= 1.97 with --ignore-rust-version. With neither
# it fails, loudly: it is never skipped. Then builds and runs the crate's tests (unit
# tests and headless Bevy apps on the machine's adapter, lavapipe without a GPU).
set -euo pipefail
cd "$(dirname "$0")/.."

version_of() { # "cargo 1.97.0-nightly (...)" -> 1.97.0
    "$@" --version 2>/dev/null | awk '{print $2}' | cut -d- -f1
}
at_least() { # at_least HAVE WANT
    [ -n "$1" ] && [ "$(printf '%s\n%s\n' "$2" "$1" | sort -V | head -n1)" = "$2" ]
}

stable=$(version_of cargo || true)
nightly=$(version_of cargo +nightly || true)
if at_least "$stable" 1.97.1; then
    cargo=(cargo)
    flags=()
    echo "bevy_caustica: stable cargo $stable"
elif at_least "$nightly" 1.97.0; then
    cargo=(cargo +nightly)
    flags=(--ignore-rust-version)
    echo "bevy_caustica: cargo +nightly $nightly with --ignore-rust-version (stable is ${stable:-absent})"
else
    echo "ERROR: bevy_caustica needs Rust >= 1.97.1 (Bevy 0.20.1's rust-version) or a nightly" >&2
    echo "       >= 1.97 (built with --ignore-rust-version); found stable '${stable:-none}'," >&2
    echo "       nightly '${nightly:-none}'. Install one: rustup toolchain install nightly" >&2
    exit 1
fi

start=$(date +%s)
"${cargo[@]}" test "${flags[@]}" --no-run
built=$(date +%s)
"${cargo[@]}" test "${flags[@]}" -- --test-threads 1
tested=$(date +%s)
# the example, headless and small (its debug build came with the tests)
"${cargo[@]}" run "${flags[@]}" --example glass_ball -- \
    --frames 20 --size 320x192 --out target/ci-glass-ball
done_at=$(date +%s)
echo "bevy_caustica: build $((built - start)) s, tests $((tested - built)) s, example $((done_at - tested)) s"
