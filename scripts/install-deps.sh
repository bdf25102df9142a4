#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
#
# Installs the Debian 12 packages pliant needs, and only those that are missing.
# Idempotent: a second run installs nothing and takes about a second.
# Usage: scripts/install-deps.sh [--demo]   (as root, or with sudo available)
#   --demo  also ImageMagick, with which `pliant demo` assembles its frames into demo.gif
set -euo pipefail

packages=(
    # toolchain
    build-essential cmake ninja-build pkg-config clang clang-format libclang-rt-14-dev python3 git
    # libraries of the field
    libeigen3-dev libassimp-dev libenet-dev libzstd-dev libspdlog-dev libfmt-dev libcli11-dev
    libtomlplusplus-dev nlohmann-json3-dev libsodium-dev libomp-dev libpng-dev
    # tests and benchmarks
    libgtest-dev libgmock-dev libbenchmark-dev libopenmesh-dev
    # rendering (offscreen through EGL/OSMesa, viewer through GLFW + Dear ImGui)
    libglm-dev libglfw3-dev libimgui-dev libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri
    libosmesa6-dev xvfb
    # plots of `pliant bench`
    gnuplot-nox
)
if [ "${1:-}" = "--demo" ]; then
    packages+=(imagemagick)
fi

missing=()
for p in "${packages[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed"; then
        missing+=("$p")
    fi
done

if [ ${#missing[@]} -eq 0 ]; then
    echo "install-deps: all ${#packages[@]} packages present"
    exit 0
fi

echo "install-deps: installing ${#missing[@]} missing packages: ${missing[*]}"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
    sudo_cmd=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "install-deps: done"
