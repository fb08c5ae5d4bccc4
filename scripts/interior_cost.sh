#!/usr/bin/env bash
# What a real interior costs against the Cornell box (docs/BENCHMARKS.md, "A real interior"), in one run on
# one machine: each scene's default render at 128 × 96, interleaved REPEAT times (Cornell, interior, Cornell,
# …) so that a shared machine's drift hits both alike, then `bench --scenes` for the cost of a sensor at
# rd 32. Prints Markdown rows: the medians of `total_seconds` and of the cache's phases from --stats-json,
# the ratio to the box, the cache's sensors against the image's pixels, the sensors' triangles.
#
#   scripts/interior_cost.sh OUT [INTERIOR.toml ...]    (default: the halls of scripts/make_hall.py; REPEAT=3)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${SENSORLIGHT:-target/release/sensorlight}
out=${1:?usage: $0 OUT [INTERIOR.toml ...]}
shift
interiors=("$@")
if [ ${#interiors[@]} -eq 0 ]; then
    for n in 40000 550000; do
        [ -f "scenes/big/hall-$n/hall.toml" ] || python3 scripts/make_hall.py "$n" >/dev/null
        interiors+=("scenes/big/hall-$n/hall.toml")
    done
fi
repeat=${REPEAT:-3}
mkdir -p "$out"
export SENSORLIGHT_CACHE_DIR="$out/cache"
box=scenes/cornell/cornell.toml

render() { # scene name k
    "$bin" render "$1" --width 128 --height 96 -o "$out/$2.exr" --no-png -q --stats-json "$out/$2-$3.json"
}
echo "| scene | triangles | render 128×96 (s) | vs the box | cache: first bounce + others (s) | cache sensors / pixels |"
echo "|---|---:|---:|---:|---:|---:|"
render "$box" box 0 # warm: strategy choice and the box's own caches
for scene in "${interiors[@]}"; do
    name=$(basename "$(dirname "$scene")")
    render "$scene" "$name" 0 # warm: the cluster hierarchy, its level-of-detail measurement
    for k in $(seq "$repeat"); do
        render "$box" box "$k"
        render "$scene" "$name" "$k"
    done
    python3 - "$name" "$out" "$repeat" "$scene" <<'PY'
import json, statistics, sys
name, out, repeat, scene = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
load = lambda n: [json.load(open(f"{out}/{n}-{k}.json")) for k in range(1, repeat + 1)]
box, runs = load("box"), load(name)
median = lambda rs, f: statistics.median(f(r) for r in rs)
t_box, t = median(box, lambda r: r["total_seconds"]), median(runs, lambda r: r["total_seconds"])
first = median(runs, lambda r: r["times"]["cache_direct_seconds"])
later = median(runs, lambda r: r["times"]["cache_bounces_seconds"])
gi, pixels = runs[0]["gi"], runs[0]["width"] * runs[0]["height"]
triangles = sum(1 for line in open(scene.replace("hall.toml", "hall.obj")) if line.startswith("f "))
print(f"| {name} | {triangles} | {t:.1f} | {t / t_box:.1f}× (box {t_box:.2f} s) | {first:.1f} + {later:.2f} | "
      f"{gi['reached']} / {pixels} = {gi['reached'] / pixels:.2f} |")
PY
done
echo
"$bin" bench --scenes "$(IFS=,; echo "$box,${interiors[*]}")" --sizes 32 --full-detail-max 1000 --repeat "$repeat"
