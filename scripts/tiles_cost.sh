#!/usr/bin/env bash
# What splitting a render costs (docs/BENCHMARKS.md, "Many processes"): the radiance cache's time, the single
# render's camera part (from the cache file), and the N tiles' summed render times (each from the same cache
# file), interleaved RUNS times; prints the medians and the tiles' overhead. Times are each process's own
# `total_seconds` (--stats-json: G-buffer to composition), the cache's its wall time.
#
#   scripts/tiles_cost.sh SCENE N RUNS [render flags…]
set -euo pipefail
[ $# -ge 3 ] || { echo "usage: $0 SCENE N RUNS [render flags...]" >&2; exit 2; }
scene=$1 n=$2 runs=$3
shift 3
bin=${SENSORLIGHT:-target/release/sensorlight}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
seconds() { python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["total_seconds"])' "$1"; }
cache=() single=() tiles=()
"$bin" render "$scene" -o "$work/warm.exr" -q "$@" >/dev/null   # strategy choice, driver caches
for r in $(seq "$runs"); do
    start=$(date +%s.%N)
    "$bin" cache "$scene" -o "$work/c.slc" -q "$@"
    cache+=("$(python3 -c "print($(date +%s.%N) - $start)")")
    "$bin" render "$scene" -o "$work/single.exr" -q --cache "$work/c.slc" --stats-json "$work/single.json" "$@"
    single+=("$(seconds "$work/single.json")")
    sum=0
    for i in $(seq "$n"); do
        "$bin" render "$scene" -o "$work/t$i.exr" -q --cache "$work/c.slc" --image-tile "$i/$n" \
            --stats-json "$work/t$i.json" "$@"
        sum=$(python3 -c "print($sum + $(seconds "$work/t$i.json"))")
    done
    tiles+=("$sum")
    "$bin" assemble "$work"/t*.exr -o "$work/joined.exr" -q
    cmp -s "$work/single.exr" "$work/joined.exr" || { echo "the joined tiles differ from the single render" >&2; exit 1; }
    echo "run $r: cache ${cache[-1]} s, single render ${single[-1]} s, $n tiles summed $sum s"
done
python3 - "${cache[*]}" "${single[*]}" "${tiles[*]}" "$n" <<'PY'
import statistics, sys
c, s, t = ([float(x) for x in a.split()] for a in sys.argv[1:4])
n = int(sys.argv[4])
mc, ms, mt = statistics.median(c), statistics.median(s), statistics.median(t)
print(f"median: cache {mc:.2f} s, single render {ms:.2f} s, {n} tiles summed {mt:.2f} s: {mt / ms:.2f}x the single render")
frame = mc + ms
print(f"the cache's share of a frame rendered alone: {mc / frame:.0%}")
for nodes in (4, 16, 64):
    # Amdahl: the cache once, then the tiles in parallel (nodes at a time), then the join (ignored: < 1 s).
    tiles = max(1, nodes)
    wall = mc + mt / tiles
    print(f"{nodes} nodes, {tiles} tiles at {mt / ms:.2f}x the work: {frame / wall:.1f}x faster than one process (cache {mc:.2f} s + {mt / tiles:.2f} s)")
PY
