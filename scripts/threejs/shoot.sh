#!/usr/bin/env bash
# Screenshots a `sensorlight bake` .glb as a real glTF client shows it: three.js (view.html) in headless
# Chromium, WebGL through SwiftShader (no GPU or display needed), the glb's camera, each surface its base
# colour × its lightmap plus any emission, LinearToneMapping at the exposure, sRGB output.
#
#   scripts/threejs/shoot.sh GLB OUT.png [--width W] [--height H] [--exposure E] [--timeout S] [--verbose]
#
# W×H default to 640×480, E to 1, S (seconds for the page to finish) to 120. The lightmap EXRs are found
# beside the glb (extras.lightmap.uri of each material). --verbose prints the page's summary (sizes, lightmaps,
# WebGL renderer, timings) on stderr. Exit status: 0 when OUT.png is written; 3, with a one-line reason on
# stderr, where Chromium, python3 or three.js (scripts/threejs/node_modules: scripts/setup.sh installs it) is
# missing, Chromium cannot start, or WebGL is unavailable in it (callers skip their test on 3); 1 with the
# page's error otherwise (a glb or lightmap three.js cannot read, a material with neither lightmap nor
# emission, ...); 2 for bad arguments. $CHROMIUM names another Chromium/Chrome binary.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)

usage() { sed -n '6p' "$0" | sed 's/^#   //'; }
die() { echo "shoot: $*" >&2; exit 2; }
skip() { echo "shoot: $*" >&2; exit 3; }
fail() { echo "shoot: $*" >&2; exit 1; }

glb="" out="" width=640 height=480 exposure=1 timeout=120 verbose=false
positional=()
while [ $# -gt 0 ]; do
    case "$1" in
        --width) [ $# -ge 2 ] || die "--width needs a value"; width=$2; shift 2 ;;
        --height) [ $# -ge 2 ] || die "--height needs a value"; height=$2; shift 2 ;;
        --exposure) [ $# -ge 2 ] || die "--exposure needs a value"; exposure=$2; shift 2 ;;
        --timeout) [ $# -ge 2 ] || die "--timeout needs a value"; timeout=$2; shift 2 ;;
        --width=*) width=${1#*=}; shift ;;
        --height=*) height=${1#*=}; shift ;;
        --exposure=*) exposure=${1#*=}; shift ;;
        --timeout=*) timeout=${1#*=}; shift ;;
        --verbose|-v) verbose=true; shift ;;
        -h|--help) sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        -*) die "unknown option '$1' (usage: $(usage))" ;;
        *) positional+=("$1"); shift ;;
    esac
done
[ ${#positional[@]} -eq 2 ] || die "usage: $(usage)"
glb=${positional[0]} out=${positional[1]}
[[ $width =~ ^[1-9][0-9]*$ ]] || die "--width '$width' is not a positive integer"
[[ $height =~ ^[1-9][0-9]*$ ]] || die "--height '$height' is not a positive integer"
[[ $timeout =~ ^[1-9][0-9]*$ ]] || die "--timeout '$timeout' is not a positive integer"
[[ $exposure =~ ^([0-9]+\.?[0-9]*|\.[0-9]+)([eE][-+]?[0-9]+)?$ ]] || die "--exposure '$exposure' is not a number"
[ -f "$glb" ] || die "no such file: $glb"

command -v python3 >/dev/null || skip "python3 not found"
chromium=${CHROMIUM:-}
if [ -z "$chromium" ]; then
    for c in chromium chromium-browser google-chrome; do
        if command -v "$c" >/dev/null; then chromium=$c; break; fi
    done
fi
[ -n "$chromium" ] && command -v "$chromium" >/dev/null ||
    skip "Chromium not found (apt-get install chromium, or scripts/setup.sh)"
[ -f "$here/node_modules/three/build/three.module.js" ] ||
    skip "three.js is not installed in $here/node_modules (run 'npm ci' there, or scripts/setup.sh)"

state=$(mktemp -d "${TMPDIR:-/tmp}/sensorlight-shoot.XXXXXX")
server_pid="" chromium_pid=""
cleanup() {
    # Chromium runs in a process group of its own (setsid), so its helper processes go with it.
    if [ -n "$chromium_pid" ]; then
        kill -TERM -- "-$chromium_pid" 2>/dev/null || true
        for _ in 1 2 3 4 5 6 7 8 9 10; do kill -0 -- "-$chromium_pid" 2>/dev/null || break; sleep 0.1; done
        kill -KILL -- "-$chromium_pid" 2>/dev/null || true
    fi
    if [ -n "$server_pid" ]; then kill "$server_pid" 2>/dev/null || true; wait "$server_pid" 2>/dev/null || true; fi
    rm -rf "$state"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

scene_dir=$(cd "$(dirname "$glb")" && pwd)
python3 "$here/serve.py" "$here" "$scene_dir" "$state" 2>"$state/server.log" &
server_pid=$!
for _ in $(seq 100); do
    [ -f "$state/port" ] && break
    kill -0 "$server_pid" 2>/dev/null || fail "the HTTP server did not start: $(tail -n 1 "$state/server.log")"
    sleep 0.05
done
[ -f "$state/port" ] || fail "the HTTP server did not start within 5 s"
port=$(cat "$state/port")

urlencode() { python3 -c 'import sys, urllib.parse; print(urllib.parse.quote(sys.argv[1], safe=""))' "$1"; }
base="http://127.0.0.1:$port"
url="$base/view.html?glb=$(urlencode "scene/$(basename "$glb")")&width=$width&height=$height&exposure=$exposure&report=%2Fresult"

# Headless Chromium with WebGL on SwiftShader (ANGLE's CPU Vulkan backend): --enable-unsafe-swiftshader is
# what lets WebGL fall back to it since Chromium 137. --no-sandbox because root (and most containers) cannot
# use Chromium's sandbox; the page is local and trusted.
flags=(
    --headless --no-sandbox --user-data-dir="$state/profile"
    --use-angle=swiftshader --enable-unsafe-swiftshader --ignore-gpu-blocklist
    --window-size="$width,$height" --force-device-scale-factor=1 --hide-scrollbars
    --no-first-run --no-default-browser-check --disable-extensions --disable-sync --disable-default-apps
    --disable-background-networking --disable-component-update --disable-dev-shm-usage --mute-audio
)
setsid "$chromium" "${flags[@]}" "$url" >"$state/chromium.log" 2>&1 &
chromium_pid=$!

started=$SECONDS
while [ ! -f "$state/result.json" ]; do
    if ! kill -0 "$chromium_pid" 2>/dev/null; then
        wait "$chromium_pid" 2>/dev/null && status=0 || status=$?
        chromium_pid=""
        reason=$(grep -v '^\s*$' "$state/chromium.log" | grep -iv 'unexpected operator' | tail -n 1 || true)
        if grep -q '^/view.html' "$state/requests" 2>/dev/null; then
            fail "Chromium exited (status $status) before the page finished: ${reason:-no message}"
        fi
        skip "Chromium cannot start (status $status): ${reason:-no message}"
    fi
    if [ $((SECONDS - started)) -ge "$timeout" ]; then
        if ! grep -q '^/view.html' "$state/requests" 2>/dev/null; then
            reason=$(grep -v '^\s*$' "$state/chromium.log" | grep -iv 'unexpected operator' | tail -n 1 || true)
            skip "Chromium did not load the page within ${timeout} s: ${reason:-no message}"
        fi
        fail "the page did not finish within ${timeout} s (--timeout)"
    fi
    sleep 0.1
done

# The page's report: {"png": "data:image/png;base64,...", "info": {...}} or {"error": "..."}.
python3 - "$state/result.json" "$out" "$verbose" "$base" "$scene_dir" <<'EOF'
import base64, json, os, sys
result_path, out, verbose, base, scene_dir = sys.argv[1], sys.argv[2], sys.argv[3] == "true", sys.argv[4], sys.argv[5]
with open(result_path) as f:
    result = json.load(f)
if "error" in result:
    # The page's URLs of the scene's files, as the paths they are.
    message = result["error"].replace(base + "/scene/", scene_dir + "/")
    print(f"shoot: {message}", file=sys.stderr)
    sys.exit(3 if message.startswith("WebGL unavailable") else 1)
prefix = "data:image/png;base64,"
if not result.get("png", "").startswith(prefix):
    print("shoot: the page's result holds no PNG data URL", file=sys.stderr)
    sys.exit(1)
partial = out + ".partial"
with open(partial, "wb") as f:
    f.write(base64.b64decode(result["png"][len(prefix):]))
os.replace(partial, out)
if verbose:
    print(f"shoot: wrote {out}: {json.dumps(result.get('info', {}))}", file=sys.stderr)
EOF
