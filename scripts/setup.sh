#!/usr/bin/env bash
# Installs what sensorlight needs on Debian/Ubuntu: the Vulkan loader, lavapipe (Mesa's CPU driver, used when
# there is no GPU), the Khronos validation layer (the tests run under it), and Debian's shaderc/glslang/
# SPIRV-Tools libraries that build.rs compiles the shaders with. Idempotent; needs root or sudo.
set -euo pipefail

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
