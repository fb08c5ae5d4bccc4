#!/usr/bin/env bash
# The accuracy tables of docs/ACCURACY.md: sensorlight against its CPU oracle (`sensorlight reference`, light
# sampling + MIS, ε = 0 or as stated; path tracing for global illumination; every pixel over its square, as
# renders are by default), per-pixel relative RMSE over lit pixels, the oracle's own noise taken out ("own
# error"), over the whole image (nothing masked) and over the interior (silhouettes, emitters and the
# background masked: of R, or of images for the peer and global-illumination tables). References are made
# once into OUT and reused.
#
#   scripts/accuracy.sh OUT [every|curve|ajar|peer|gi|gi-scenes|gi-peer]...   (default: every curve ajar)
#
# every: every pixel sensed, rd 64, no filter, ε 0 — the paper's estimator against the exact one.
# curve: the shipped Cornell box at 256², ε 0.1, defaults but for rd (and dradiance): error against time.
# ajar:  the door-ajar scene, defaults against every pixel sensed.
# peer:  against Mitsuba 3's direct light (scripts/peer/mitsuba_direct.py, box filter over each pixel, ε 0)
#        at each scene's own size: PEER=DIR holding <scene>-ref.exr (made as docs/ACCURACY.md says).
# whole: the defaults on the shipped scenes, whole images (Le + Kd·R) against the oracle's pixel squares,
#        with and without --aa.
# gi:    global illumination on the shipped Cornell box at 256²: the defaults, then bounces, cache
#        resolution, cache sensor size, rd and dradiance each varied, against the path tracer (4 096 samples).
# gi-scenes: the defaults on the room, the door ajar, the small light and a 10⁶-triangle sphere in the box
#        (scripts/make_big_scenes.py 1000000), each at a stated size, against the path tracer.
# gi-peer: Mitsuba 3's path tracer (MITSUBA_PY, scripts/peer/mitsuba_direct.py --integrator path) on the
#        Cornell box at 256² at several sample counts, against the same oracle: time to equal error.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${SENSORLIGHT:-target/release/sensorlight}
out=${1:?usage: $0 OUT [every|curve|ajar]...}
shift
tables=("${@:-every curve ajar}")
peer=${PEER:-}
mkdir -p "$out"
export SENSORLIGHT_CACHE_DIR="$out/cache"

ref() { # NAME SCENE WIDTH HEIGHT SENSOR SAMPLES MODEL (--epsilon E or --bounces N|auto)
    # shellcheck disable=SC2086 # MODEL is a flag and its value
    [ -f "$out/$1-ref.exr" ] || "$bin" reference "scenes/$2" -o "$out/$1-ref.exr" --width "$3" --height "$4" \
        --sensor "$5" --samples "$6" $7 --no-png >&2
}

row() { # LABEL REFERENCE SCENE RENDER-FLAGS...
    local label=$1 reference=$2 scene=$3
    shift 3
    "$bin" render "scenes/$scene" -o "$out/$label.exr" --aovs --no-png --stats-json "$out/$label.json" "$@" \
        2>"$out/$label.log" >&2
    "$bin" compare "$out/$label.exr" "$reference" --layer "${layer-radiance}" --json "$out/$label.cmp.json" >/dev/null 2>&1
    python3 - "$label" "$out/$label.json" "$out/$label.cmp.json" "$*" <<'PY'
import json, sys
label, stats, cmp, flags = sys.argv[1], json.load(open(sys.argv[2])), json.load(open(sys.argv[3])), sys.argv[4]
def own(figures):
    return figures["own_error"] if figures["own_error"] is not None else figures["relative_rmse"]
whole, interior = cmp["whole"], cmp["interior"]
noise = "—" if whole["reference_noise"] is None else f"{100 * whole['reference_noise']:.2f} %"
print(f"| {label} | `{flags}` | {stats['sensors']} | {stats['total_seconds']:.2f} | {100 * own(whole):.2f} % | "
      f"{100 * own(interior):.2f} % | {noise} | {interior['leaked_pixels']} |")
PY
}

header() {
    echo
    echo "| case | flags | sensors | seconds | whole image: own error | interior: own error | oracle noise (whole) | leaked px |"
    echo "|---|---|---|---|---|---|---|---|"
}

for table in ${tables[*]}; do
    case "$table" in
    every)
        echo "### Every pixel sensed, rd 64, no filter, ε 0"
        header
        every=(--tile 1 --dradiance 0 --filter-radius 0 --epsilon 0 --sensor-size 64)
        for c in "cornell cornell/cornell.toml 96 96 hemicube" "cornell-frustum cornell/cornell.toml 96 96 frustum" \
            "small-light small-light/small-light.toml 160 120 hemicube" "room room/room.toml 128 96 hemicube"; do
            read -r name scene w h sensor <<<"$c"
            ref "$name" "$scene" "$w" "$h" "$sensor" 16384 "--epsilon 0"
            for estimator in paper exact; do
                row "$name-$estimator" "$out/$name-ref.exr" "$scene" --estimator "$estimator" --sensor "$sensor" \
                    --width "$w" --height "$h" "${every[@]}"
            done
        done
        ;;
    curve)
        echo "### Error against time: the shipped Cornell box, 256², ε 0.1"
        header
        ref cornell256 cornell/cornell.toml 256 256 hemicube 4096 "--epsilon 0.1"
        r="$out/cornell256-ref.exr"
        for rd in 64 128 256; do row "paper-rd$rd" "$r" cornell/cornell.toml --estimator paper --sensor-size "$rd"; done
        for rd in 16 32 64; do row "exact-rd$rd" "$r" cornell/cornell.toml --estimator exact --sensor-size "$rd"; done
        row "exact-rd32-d0.1" "$r" cornell/cornell.toml --estimator exact --sensor-size 32 --dradiance 0.1
        row "exact-rd64-d0.1" "$r" cornell/cornell.toml --estimator exact --sensor-size 64 --dradiance 0.1
        ;;
    ajar)
        echo "### Door ajar (160 × 120, ε 0): defaults against every pixel sensed"
        header
        ref door-ajar door-ajar/door-ajar.toml 160 120 hemicube 16384 "--epsilon 0"
        size=(--width 160 --height 120 --epsilon 0)
        row ajar-every "$out/door-ajar-ref.exr" door-ajar/door-ajar.toml "${size[@]}" --tile 1 --dradiance 0 --filter-radius 0
        row ajar-defaults "$out/door-ajar-ref.exr" door-ajar/door-ajar.toml "${size[@]}"
        cp "$out/ajar-every.exr" "$out/ajar-every-copy.exr" # compare refuses an output that is also an input
        row ajar-defaults-vs-every "$out/ajar-every-copy.exr" door-ajar/door-ajar.toml "${size[@]}"
        ;;
    whole)
        echo "### Whole images at the defaults, against the oracle's pixel squares"
        header
        layer=""
        ref cornell256-gi cornell/cornell.toml 256 256 hemicube 4096 "--bounces auto"
        row whole-cornell "$out/cornell256-gi-ref.exr" cornell/cornell.toml
        row whole-cornell-aa-off "$out/cornell256-gi-ref.exr" cornell/cornell.toml --aa off
        ref small-light-gi small-light/small-light.toml 160 120 hemicube 4096 "--bounces auto"
        row whole-small-light "$out/small-light-gi-ref.exr" small-light/small-light.toml --width 160 --height 120
        row whole-small-light-aa-off "$out/small-light-gi-ref.exr" small-light/small-light.toml --width 160 \
            --height 120 --aa off
        ref small-light-d small-light/small-light.toml 320 240 hemicube 1024 "--epsilon 0"
        row whole-small-light-direct "$out/small-light-d-ref.exr" small-light/small-light.toml --epsilon 0
        row whole-small-light-direct-aa-off "$out/small-light-d-ref.exr" small-light/small-light.toml --epsilon 0 \
            --aa off
        ;;
    peer)
        echo "### Against Mitsuba 3 (direct light, ε 0, box filter, each scene's own size)"
        header
        layer="" # Mitsuba writes the image (Le + albedo·R), not R
        for scene in cornell small-light door-ajar room; do
            reference="${peer:?set PEER to the directory of the Mitsuba references}/$scene-ref.exr"
            row "$scene-mitsuba-defaults" "$reference" "$scene/$scene.toml" --epsilon 0
            row "$scene-mitsuba-every-rd64" "$reference" "$scene/$scene.toml" --epsilon 0 --tile 1 --dradiance 0 \
                --filter-radius 0 --sensor-size 64
        done
        ;;
    gi)
        echo "### Global illumination: the shipped Cornell box, 256², against the path tracer"
        header
        ref cornell256-gi cornell/cornell.toml 256 256 hemicube 4096 "--bounces auto"
        r="$out/cornell256-gi-ref.exr"
        layer=""
        s=cornell/cornell.toml
        row gi-defaults "$r" $s
        for b in 1 2 4; do row "gi-bounces$b" "$r" $s --bounces "$b"; done
        for n in 8 32; do row "gi-cache$n" "$r" $s --cache-resolution "$n"; done
        for n in 8 32; do row "gi-cache-rd$n" "$r" $s --cache-sensor-size "$n"; done
        for n in 16 64; do row "gi-rd$n" "$r" $s --sensor-size "$n"; done
        row gi-d0.1 "$r" $s --dradiance 0.1
        row gi-every "$r" $s --tile 1 --dradiance 0
        row paper-eps0.1 "$r" $s --epsilon 0.1
        row direct "$r" $s --bounces 0
        ;;
    gi-scenes)
        echo "### Global illumination: the defaults on the other scenes, against the path tracer"
        header
        layer=""
        ref room-gi room/room.toml 160 120 hemicube 4096 "--bounces auto"
        row gi-room "$out/room-gi-ref.exr" room/room.toml --width 160 --height 120
        ref small-light-gi small-light/small-light.toml 160 120 hemicube 4096 "--bounces auto"
        row gi-small-light "$out/small-light-gi-ref.exr" small-light/small-light.toml --width 160 --height 120
        ref door-ajar-gi door-ajar/door-ajar.toml 80 60 hemicube 262144 "--bounces auto"
        row gi-door-ajar "$out/door-ajar-gi-ref.exr" door-ajar/door-ajar.toml --width 80 --height 60
        row gi-door-ajar-program-defaults "$out/door-ajar-gi-ref.exr" door-ajar/door-ajar.toml --width 80 --height 60 \
            --cache-resolution 16 --sensor-size 32
        if [ -f scenes/big/sphere-1000000/scene.toml ]; then
            ref big-gi big/sphere-1000000/scene.toml 64 64 hemicube 4096 "--bounces auto"
            row gi-big "$out/big-gi-ref.exr" big/sphere-1000000/scene.toml --width 64 --height 64
        fi
        ;;
    gi-peer)
        echo "### Mitsuba 3's path tracer on the Cornell box, 256², against the same oracle"
        echo
        echo "| spp | seconds | own error | relative RMSE |"
        echo "|---|---|---|---|"
        ref cornell256-gi cornell/cornell.toml 256 256 hemicube 4096 "--bounces auto"
        for spp in 256 1024 4096; do
            m="$out/mitsuba-path-$spp.exr"
            seconds=$("${MITSUBA_PY:-python3}" scripts/peer/mitsuba_direct.py scenes/cornell/cornell.toml -o "$m" \
                --integrator path --max-depth -1 --spp "$spp" --pixel-sampling box | sed -n 's/.*total \([0-9.]*\) s.*/\1/p')
            "$bin" compare "$m" "$out/cornell256-gi-ref.exr" --json "$m.json" >/dev/null 2>&1
            python3 - "$spp" "$seconds" "$m.json" <<'PY'
import json, sys
spp, seconds, cmp = sys.argv[1], float(sys.argv[2]), json.load(open(sys.argv[3]))
whole = cmp["whole"]
print(f"| {spp} | {seconds:.1f} | {100 * whole['own_error']:.2f} % | {100 * whole['relative_rmse']:.2f} % |")
PY
        done
        ;;
    *) echo "unknown table '$table'" >&2; exit 2 ;;
    esac
done
