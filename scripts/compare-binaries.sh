#!/usr/bin/env bash
# Times two sensorlight binaries on the same render, interleaved (A, B, A, B, …) so that a shared, noisy
# machine's drift hits both alike, and prints each run, the medians and their ratio. The time is the
# render's own `total_seconds` (from --stats-json: G-buffer to composition, strategy choice excluded); each
# binary keeps its own strategy cache, warmed by one untimed run first.
#
#   scripts/compare-binaries.sh OLD NEW RUNS -- render ARGS…     (ARGS without -o and --stats-json)
#
# Example: scripts/compare-binaries.sh /tmp/old/sensorlight target/release/sensorlight 5 -- \
#              render scenes/cornell/cornell.toml
set -euo pipefail
if [ $# -lt 5 ] || [ "$4" != "--" ]; then
    echo "usage: $0 OLD NEW RUNS -- render ARGS..." >&2
    exit 2
fi
old=$1 new=$2 runs=$3
shift 4
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

time_of() { # binary label
    SENSORLIGHT_CACHE_DIR="$work/cache-$2" "$1" "${args[@]}" -o "$work/$2.exr" --no-png --stats-json "$work/$2.json" \
        >/dev/null 2>"$work/log" || { cat "$work/log" >&2; exit 1; }
    python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["total_seconds"])' "$work/$2.json"
}
args=("$@")
time_of "$old" old >/dev/null   # warm-up: strategy choice, pipeline caches of the driver
time_of "$new" new >/dev/null
a=() b=()
for i in $(seq "$runs"); do
    ta=$(time_of "$old" old); tb=$(time_of "$new" new)
    echo "run $i: old $ta s, new $tb s"
    a+=("$ta") b+=("$tb")
done
python3 - "${a[*]}" "${b[*]}" <<'EOF'
import statistics, sys
a = [float(x) for x in sys.argv[1].split()]
b = [float(x) for x in sys.argv[2].split()]
ma, mb = statistics.median(a), statistics.median(b)
print(f"median: old {ma:.3f} s [{min(a):.3f}–{max(a):.3f}], new {mb:.3f} s [{min(b):.3f}–{max(b):.3f}]; "
      f"new/old = {mb / ma:.3f} (old is {ma / mb:.2f}x the new time)")
EOF
