#!/usr/bin/env bash
# Regenerates what docs/ shows from `caustica report` and `caustica render`, on the CPU
# backend: the error-against-run-time folders docs/report-<technique>/ (each emptied
# first, so that it holds only what this script writes) and README's picture.
#
#   scripts/make-report-docs.sh [images] [sspm] [caustic-map] [adaptive-caustics] [photon-gi]
#
# No argument runs them all: hours on two cores, the references converging first. The
# references are cached under out/report-references/ and shared by the reports. Each
# command is printed before it runs. `images` needs ImageMagick (`montage`, `mogrify`). CAUSTICA=path
# runs that binary instead of building the CLI first.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -z "${CAUSTICA:-}" ]; then
    cargo build --release -p caustica
    CAUSTICA=${CARGO_TARGET_DIR:-target}/release/caustica
fi
cache=out/report-references
mkdir -p out

run() { echo "+ caustica $*" >&2; "$CAUSTICA" "$@"; }
# report FOLDER ARGS...: a report written into docs/FOLDER, emptied first
report() { local dir=docs/$1; shift; rm -rf "$dir"; run report --backends cpu --cache "$cache" --out "$dir" "$@"; }

images() {
    # each technique on a scene that makes its point, 320x180, composed 2x2 into
    # docs/images/techniques.png: Sspm the prism's spectrum on its screen; CausticMap the
    # ball's caustic seen through the ball (its atlas holds the light where the camera
    # sees it through glass); AdaptiveCaustics the pool floor's caustic network seen
    # through the water; PhotonGi the Cornell box's colour bleeding
    local out=out/images
    rm -rf "$out"
    run render --backend cpu --scene prism --technique sspm --size 320x180 --photons 2048x2048 --out $out/sspm
    run render --backend cpu --scene sphere --technique caustic-map --size 320x180 --photons 1024x1024 --out $out/caustic-map
    run render --backend cpu --scene pool --technique adaptive-caustics --size 320x180 --photons 1024x1024 --out $out/adaptive-caustics
    run render --backend cpu --scene cornell --technique photon-gi --size 320x180 --photons 2048x2048 --out $out/photon-gi
    montage $out/sspm/prism_composite.png $out/caustic-map/sphere_composite.png \
        $out/adaptive-caustics/pool_composite.png $out/photon-gi/cornell_composite.png \
        -tile 2x2 -geometry +2+2 -background white docs/images/techniques.png
    mogrify -shave 2x2 docs/images/techniques.png  # white 4-pixel gaps, no outer margin
}

sspm() {
    report report-sspm --scenes sphere,sphere-sun,ring,cornell,pool,prism,jelly --techniques sspm \
        --budgets 256x256,512x512,1024x1024,2048x2048,4096x4096 --filters density,bilateral --repeats 3 \
        --reference-noise 0.01
    # `sphere` at two larger sizes: only their records are kept
    for size in 960x540 1920x1080; do
        run report --scenes sphere --techniques sspm --backends cpu --budgets 2048x2048 \
            --filters density,bilateral --repeats 3 --reference-noise 0.01 --size $size \
            --cache "$cache" --out out/report-sspm-$size
        cp out/report-sspm-$size/report.json docs/report-sspm/sphere-$size.json
    done
}

caustic_map() {
    report report-caustic-map --scenes sphere,cornell,sphere-sun --techniques caustic-map \
        --budgets 256x256,512x512,1024x1024,2048x2048 --filters density,box --repeats 3 --reference-noise 0.01
}

adaptive_caustics() {
    report report-adaptive-caustics --scenes sphere,cornell,sphere-sun --techniques sspm,caustic-map,adaptive-caustics \
        --budgets 256x256,512x512,1024x1024,2048x2048 --repeats 3 --reference-noise 0.01
}

photon_gi() {
    # the printed table is kept too (docs/photon-gi.md shows it)
    local args=(--scenes cornell,rooms --techniques photon-gi,photon-gi:temporal=false,sspm,caustic-map
                --budgets 128x128,256x256,512x512 --size 160x90 --repeats 3 --reference-noise 0.05)
    report report-photon-gi "${args[@]}" > out/report-photon-gi-table.md
    { echo "Command: \`caustica report ${args[*]} --backends cpu\` ($(date +%F); photon-gi against the"
      echo "indirect reference, sspm and caustic-map against the light tracer and the caustic reference)."
      echo; cat out/report-photon-gi-table.md; } \
        > docs/report-photon-gi/table.md
}

for part in ${*:-images sspm caustic-map adaptive-caustics photon-gi}; do
    case $part in
    images|sspm|caustic-map|adaptive-caustics|photon-gi) "${part//-/_}" ;;
    *) echo "unknown part '$part' (images, sspm, caustic-map, adaptive-caustics, photon-gi)" >&2; exit 2 ;;
    esac
done
