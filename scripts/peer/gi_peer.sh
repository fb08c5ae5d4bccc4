#!/usr/bin/env bash
# The oracle's global illumination against Mitsuba 3's path tracer: docs/ACCURACY.md, "The global-illumination
# oracle". Each case renders the oracle once and Mitsuba twice (two seeds: their difference / √2 is Mitsuba's
# own noise), all through the pixel centres, and compares images (Le + Kd·R) with `sensorlight compare`
# (Mitsuba as the image, the oracle as the reference, so the oracle's noise is stated and taken out).
#
#   MITSUBA_PY=/work/venv-mitsuba/bin/python scripts/peer/gi_peer.sh OUT [CASE]...
#
# CASE is NAME:SCENE:WIDTH:HEIGHT:BOUNCES (BOUNCES a count or auto; Mitsuba's depth is BOUNCES + 2, or -1);
# default: cornell and room at 8 bounces and until converged. SAMPLES (oracle, default 16384) and SPP
# (Mitsuba, default 16384) set the sample counts. Prints one Markdown row per case; files stay in OUT.
set -euo pipefail
cd "$(dirname "$0")/../.."
bin=${SENSORLIGHT:-target/release/sensorlight}
py=${MITSUBA_PY:-python3}
out=${1:?usage: $0 OUT [NAME:SCENE:WIDTH:HEIGHT:BOUNCES]...}
shift
cases=("$@")
if [ ${#cases[@]} -eq 0 ]; then
    cases=(cornell-8:cornell/cornell.toml:128:128:8 cornell-auto:cornell/cornell.toml:128:128:auto
        room-8:room/room.toml:128:96:8 room-auto:room/room.toml:128:96:auto)
fi
samples=${SAMPLES:-16384}
spp=${SPP:-16384}
mkdir -p "$out"

seconds() { python3 -c 'import sys, time; print(f"{time.time() - float(sys.argv[1]):.1f}")' "$1"; }

echo "| case | oracle: samples, seconds, noise | Mitsuba: spp, seconds, noise | relative RMSE | beyond both noises | bias |"
echo "|---|---|---|---|---|---|"
for c in "${cases[@]}"; do
    IFS=: read -r name scene w h bounces <<<"$c"
    depth=$([ "$bounces" = auto ] && echo -1 || echo $((bounces + 2)))
    start=$(date +%s.%N)
    "$bin" reference "scenes/$scene" -o "$out/$name-oracle.exr" --width "$w" --height "$h" --bounces "$bounces" \
        --samples "$samples" --no-png 2>"$out/$name-oracle.log"
    oracle_s=$(seconds "$start")
    mitsuba_s=()
    for seed in 0 1; do
        start=$(date +%s.%N)
        "$py" scripts/peer/mitsuba_direct.py "scenes/$scene" -o "$out/$name-mitsuba-$seed.exr" --width "$w" \
            --height "$h" --integrator path --max-depth "$depth" --spp "$spp" --seed "$seed" \
            --pixel-sampling box >"$out/$name-mitsuba-$seed.log"
        mitsuba_s+=("$(seconds "$start")")
    done
    "$bin" compare "$out/$name-mitsuba-0.exr" "$out/$name-oracle.exr" --json "$out/$name.cmp.json" >/dev/null 2>&1
    "$bin" compare "$out/$name-mitsuba-1.exr" "$out/$name-mitsuba-0.exr" --json "$out/$name.seeds.json" \
        >/dev/null 2>&1
    python3 - "$name" "$bounces" "$depth" "$samples" "$oracle_s" "$spp" "${mitsuba_s[0]}" "$out/$name.cmp.json" \
        "$out/$name.seeds.json" <<'PY'
import json, math, sys
name, bounces, depth, samples, oracle_s, spp, mitsuba_s = sys.argv[1:8]
cmp, seeds = json.load(open(sys.argv[8])), json.load(open(sys.argv[9]))
cmp, seeds = cmp["whole"], seeds["whole"]  # whole images: both renderers integrate each pixel's square
oracle_noise = cmp["reference_noise"]
mitsuba_noise = seeds["relative_rmse"] / math.sqrt(2)  # two independent renders of equal noise
rmse = cmp["relative_rmse"]
beyond = math.sqrt(max(0.0, rmse**2 - oracle_noise**2 - mitsuba_noise**2))
print(f"| {name} (`--bounces {bounces}` ↔ depth {depth}) | {samples}, {oracle_s} s, {100 * oracle_noise:.2f} % | "
      f"{spp}, {mitsuba_s} s, {100 * mitsuba_noise:.2f} % | {100 * rmse:.2f} % | {100 * beyond:.2f} % | "
      f"{100 * cmp['relative_bias']:+.2f} % |")
PY
done
