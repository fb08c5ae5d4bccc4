#!/usr/bin/env bash
# Installs what sensorlight needs on Debian/Ubuntu: the Vulkan loader, lavapipe (Mesa's CPU driver, used when
# there is no GPU), the Khronos validation layer (the tests run under it), and Debian's shaderc/glslang/
# SPIRV-Tools libraries that build.rs compiles the shaders with. Idempotent; needs root or sudo.
#
#   scripts/setup.sh [--lavapipe-backports]
#
# --lavapipe-backports also fetches Mesa 25's lavapipe from Debian's bookworm-backports and unpacks it beside
# the system driver (it replaces nothing and adds no apt source: the package list is read into a private
# directory). Debian stable's lavapipe (Mesa 22.3) renders layer i + 1 for multiview's view i, so the
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
)

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

if ! command -v cargo >/dev/null; then
    echo "setup: cargo not found; install Rust (https://rustup.rs) and run this again" >&2
    exit 1
fi

# Mesa 25's lavapipe, unpacked into a directory of its own with an ICD manifest naming it by absolute path.
if $backports; then
    dir="${SENSORLIGHT_LAVAPIPE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/sensorlight/lavapipe-backports}"
    if [ -f "$dir/lvp_icd.json" ]; then
        echo "setup: backports lavapipe already in $dir"
    else
        mkdir -p "$dir/apt/lists/partial" "$dir/apt/archives/partial"
        echo "deb http://deb.debian.org/debian bookworm-backports main" >"$dir/apt/sources.list"
        apt_private=(-o "Dir::Etc::SourceList=$dir/apt/sources.list" -o "Dir::Etc::SourceParts=/dev/null"
            -o "Dir::State::Lists=$dir/apt/lists" -o "Dir::Cache::Archives=$dir/apt/archives"
            -o "Dir::Cache::pkgcache=" -o "Dir::Cache::srcpkgcache=" -o "Debug::NoLocking=1" -o "APT::Sandbox::User=root")
        echo "setup: reading bookworm-backports' package list into $dir/apt (no system apt source changed)"
        apt-get -q "${apt_private[@]}" update >/dev/null
        (cd "$dir" && apt-get -q "${apt_private[@]}" download -t bookworm-backports mesa-vulkan-drivers)
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
