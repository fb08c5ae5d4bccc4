#!/usr/bin/env bash
# Installs what sensorlight needs on Debian/Ubuntu: the Vulkan loader, lavapipe (Mesa's CPU driver, used when
# there is no GPU), the Khronos validation layer (the tests run under it), and Debian's shaderc/glslang/
# SPIRV-Tools libraries that build.rs compiles the shaders with, and what the live viewer's window needs (X11's
# keyboard library; Xvfb and xwd, a virtual display and its screenshots, for the viewer's tests). Idempotent;
# needs root or sudo.
#
#   scripts/setup.sh [--lavapipe-backports]
#
# --lavapipe-backports also fetches Mesa 25's lavapipe from Debian's backports (bookworm-backports on Debian
# 12) and unpacks it beside the system driver (it replaces nothing and adds no apt source: the package list is
# read into a private directory). The backports source is derived from the machine's own apt sources: the
# mirror and suite name its Debian main archive entry uses (a local mirror included; apt's proxy settings
# apply as to any apt command), with "-backports" appended. SENSORLIGHT_BACKPORTS_SOURCE="deb URI SUITE main"
# overrides it. Debian stable's lavapipe (Mesa 22.3) renders layer i + 1 for multiview's view i, so the
# multiview strategy fails its self-check there; Mesa 25's passes it. Use it with
#   export VK_DRIVER_FILES=$SENSORLIGHT_LAVAPIPE_DIR/lvp_icd.json   (default ~/.cache/sensorlight/lavapipe-backports)
set -euo pipefail

backports=false
for arg in "$@"; do
    case "$arg" in
        --lavapipe-backports) backports=true ;;
        -h|--help) sed -n '2,13p' "$0"; exit 0 ;;
        *) echo "setup: unknown option '$arg' (see --help)" >&2; exit 2 ;;
    esac
done

packages=(
    libvulkan1 libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers vulkan-tools
    libshaderc-dev glslang-dev spirv-tools
    pkg-config build-essential
    libxkbcommon-x11-0 xvfb x11-apps
    # A private single-node cluster for `sensorlight slurm` and its tests (scripts/slurm-local.sh).
    slurm-wlm munge
    # The real glTF client for `sensorlight bake`'s lightmaps: three.js in headless Chromium (scripts/threejs).
    chromium nodejs
)
# npm too, unless there is one already: NodeSource's nodejs package bundles npm and conflicts with Debian's.
command -v npm >/dev/null || packages+=(npm)

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi

missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
    echo "setup: installing ${missing[*]}"
    $sudo env DEBIAN_FRONTEND=noninteractive apt-get update -q
    $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
else
    echo "setup: system packages already installed"
fi

# three.js for scripts/threejs, as its package-lock.json pins it (reinstalled when the lock is newer than what
# npm last installed).
threejs="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/threejs"
if [ ! -f "$threejs/node_modules/.package-lock.json" ] || [ "$threejs/package-lock.json" -nt "$threejs/node_modules/.package-lock.json" ]; then
    echo "setup: installing three.js into scripts/threejs/node_modules (npm ci)"
    # Only the three.js client's tests need it, and they skip, saying why, without it: a registry out of
    # reach is a warning, not the end of the setup.
    (cd "$threejs" && npm ci --no-audit --no-fund --loglevel=error >/dev/null) ||
        echo "setup: warning: npm ci failed in scripts/threejs; the three.js tests will be skipped" >&2
else
    echo "setup: three.js already installed in scripts/threejs/node_modules"
fi

if ! command -v cargo >/dev/null; then
    echo "setup: cargo not found; install Rust (https://rustup.rs) and run this again" >&2
    exit 1
fi

# The backports line for the machine's configured Debian archive: the mirror, suite and signing key of the
# first apt source (one-line `deb` lines in sources.list and *.list, deb822 stanzas in *.sources) that serves
# this release's main component under its codename or a stable alias (not -updates or -security), with
# "-backports" appended to the suite. Read from the files, not from apt's lists, which a fresh machine may
# not have yet. Arguments: the files to read (default: the machine's).
backports_source() {
    local codename found files=("$@")
    codename=$(. /etc/os-release && echo "${VERSION_CODENAME:-}")
    [ ${#files[@]} -gt 0 ] || files=(/etc/apt/sources.list /etc/apt/sources.list.d/*.list /etc/apt/sources.list.d/*.sources)
    found=$(for f in "${files[@]}"; do
        [ -f "$f" ] || continue
        case "$f" in
        *.sources) awk -v RS= -v FS='\n' '{ print "stanza"; for (i = 1; i <= NF; i++) if ($i !~ /^#/) print $i }' "$f" ;;
        *) awk '$1 == "deb" { print "line " substr($0, index($0, "deb ") + 4) }' "$f" ;;
        esac
    done | awk -v c="$codename" '
        function wanted(s) { return s == c || s ~ /^(old)*stable$/ }
        function has_main(from,   k) { for (k = from; k <= NF; k++) if ($k == "main") return 1; return 0 }
        # The first match is printed; the rest is read to the end, so the writer never meets a closed pipe.
        matched { next }
        function stanza_end() {
            if (!matched && types ~ /(^| )deb( |$)/ && enabled != "no" && components ~ /(^| )main( |$)/) {
                n = split(suites, s, " "); split(uris, u, " ")
                for (k = 1; k <= n && !matched; k++)
                    if (wanted(s[k])) { print u[1], s[k], (key ~ /^\// ? "[signed-by=" key "]" : ""); matched = 1 }
            }
            types = uris = suites = components = enabled = key = ""
        }
        $1 == "line" {
            i = 2; options = ""
            if ($2 ~ /^\[/) { while ($i !~ /\]$/ && i < NF) { options = options $i " "; i++ } options = options $i; i++ }
            if (wanted($(i + 1)) && has_main(i + 2)) { print $i, $(i + 1), options; matched = 1 }
            next
        }
        $1 == "stanza" { stanza_end(); next }
        { field = tolower($1); $1 = ""; sub(/^ +/, "") }
        field == "types:" { types = $0 } field == "uris:" { uris = $0 } field == "suites:" { suites = $0 }
        field == "components:" { components = $0 } field == "enabled:" { enabled = $0 } field == "signed-by:" { key = $0 }
        END { stanza_end() }')
    if [ -z "$found" ]; then
        echo "setup: no apt source for Debian ${codename:-(unknown release)} main is configured, so there is no" \
            "mirror to take backports from; add one, or set SENSORLIGHT_BACKPORTS_SOURCE=\"deb URI SUITE-backports main\"" >&2
        return 1
    fi
    local uri suite options
    read -r uri suite options <<<"$found"
    echo "deb ${options:+$options }$uri $suite-backports main"
}

# Mesa 25's lavapipe, unpacked into a directory of its own with an ICD manifest naming it by absolute path.
if $backports; then
    dir="${SENSORLIGHT_LAVAPIPE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/sensorlight/lavapipe-backports}"
    if [ -f "$dir/lvp_icd.json" ]; then
        echo "setup: backports lavapipe already in $dir"
    else
        mkdir -p "$dir/apt/lists/partial" "$dir/apt/archives/partial"
        source_line="${SENSORLIGHT_BACKPORTS_SOURCE:-$(backports_source)}" || exit 1
        suite=$(awk '{ for (i = 2; i <= NF; i++) if ($i !~ /^\[|\]$|=/) { print $(i + 1); exit } }' <<<"$source_line")
        echo "$source_line" >"$dir/apt/sources.list"
        apt_private=(-o "Dir::Etc::SourceList=$dir/apt/sources.list" -o "Dir::Etc::SourceParts=/dev/null"
            -o "Dir::State::Lists=$dir/apt/lists" -o "Dir::Cache::Archives=$dir/apt/archives"
            -o "Dir::Cache::pkgcache=" -o "Dir::Cache::srcpkgcache=" -o "Debug::NoLocking=1" -o "APT::Sandbox::User=root")
        echo "setup: reading $source_line's package list into $dir/apt (no system apt source changed)"
        apt-get -q "${apt_private[@]}" update >/dev/null
        (cd "$dir" && apt-get -q "${apt_private[@]}" download -t "$suite" mesa-vulkan-drivers)
        deb=$(ls "$dir"/mesa-vulkan-drivers_*.deb | head -1)
        dpkg -x "$deb" "$dir/root"
        library=$(find "$dir/root" -name libvulkan_lvp.so | head -1)
        [ -n "$library" ] || { echo "setup: $deb holds no libvulkan_lvp.so" >&2; exit 1; }
        version=$(dpkg-deb -f "$deb" Version)
        printf '{ "file_format_version": "1.0.0", "ICD": { "library_path": "%s", "api_version": "1.3.0" } }\n' \
            "$library" >"$dir/lvp_icd.json.partial"
        mv "$dir/lvp_icd.json.partial" "$dir/lvp_icd.json"
        rm -rf "$dir/apt" "$deb"
        echo "setup: lavapipe $version unpacked in $dir"
    fi
    echo "setup: use it with: export VK_DRIVER_FILES=$dir/lvp_icd.json"
fi
