#!/usr/bin/env bash
# What global illumination costs (docs/BENCHMARKS.md, "Global illumination"): each scene rendered at its own
# size with the defaults and with direct light only (--bounces 0), interleaved REPEAT times so that both
# see the same machine; prints a Markdown row per scene from the medians of --stats-json: the two times and
# their ratio, the cache's phases (first bounce, the others), its entries, bounces and bytes.
#
#   scripts/gi_cost.sh OUT [SCENE.toml ...]     (default: the shipped scenes; REPEAT=3)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${SENSORLIGHT:-target/release/sensorlight}
out=${1:?usage: $0 OUT [SCENE.toml ...]}
shift
scenes=("$@")
if [ ${#scenes[@]} -eq 0 ]; then
    scenes=(scenes/cornell/cornell.toml scenes/cornell-mcguire/cornell-mcguire.toml scenes/room/room.toml
        scenes/small-light/small-light.toml scenes/door-ajar/door-ajar.toml)
fi
repeat=${REPEAT:-3}
mkdir -p "$out"
export SENSORLIGHT_CACHE_DIR="$out/cache"

echo "| scene | direct only (s) | global illumination (s) | ratio | cache: first bounce + others (s) | entries reached / all, bounces | cache KiB |"
echo "|---|---|---|---|---|---|---|"
for scene in "${scenes[@]}"; do
    name=$(basename "$scene" .toml)
    for k in $(seq "$repeat"); do
        for mode in direct gi; do
            flags=()
            [ "$mode" = direct ] && flags=(--bounces 0)
            "$bin" render "$scene" -o "$out/$name-$mode.exr" --no-png -q --stats-json "$out/$name-$mode-$k.json" \
                "${flags[@]}"
        done
    done
    python3 - "$name" "$out" "$repeat" <<'PY'
import json, statistics, sys
name, out, repeat = sys.argv[1], sys.argv[2], int(sys.argv[3])
load = lambda mode: [json.load(open(f"{out}/{name}-{mode}-{k}.json")) for k in range(1, repeat + 1)]
direct, gi = load("direct"), load("gi")
median = lambda runs, f: statistics.median(f(r) for r in runs)
d, g = median(direct, lambda r: r["total_seconds"]), median(gi, lambda r: r["total_seconds"])
first = median(gi, lambda r: r["times"]["cache_direct_seconds"])
later = median(gi, lambda r: r["times"]["cache_bounces_seconds"])
c = gi[0]["gi"]
print(f"| {name} {gi[0]['width']}×{gi[0]['height']} | {d:.2f} | {g:.2f} | {g / d:.1f}× | {first:.2f} + {later:.2f} | "
      f"{c['reached']} / {c['entries']}, {c['bounces']} | {c['cache_bytes'] / 1024:.0f} |")
PY
done
