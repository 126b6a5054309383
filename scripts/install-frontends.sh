#!/usr/bin/env bash
# Install the Debian packages the front ends' tests need, unless they are there
# (tests/frontends/): QGIS with its Python and providers for the Processing provider's
# test (qgis_process.bin), and for napari's viewer the libraries Qt loads, Mesa's
# software OpenGL and Xvfb, the virtual X display the tests draw on. `make test` runs
# it; needs root (or sudo) for apt-get.
set -euo pipefail
packages=(
    qgis python3-qgis qgis-providers
    xvfb xauth libgl1 libgl1-mesa-dri libegl1 libglib2.0-0 libdbus-1-3 libfontconfig1
    libxkbcommon-x11-0 libxcb-cursor0 libxcb-icccm4 libxcb-image0 libxcb-keysyms1
    libxcb-randr0 libxcb-render-util0 libxcb-shape0 libxcb-xinerama0 libxcb-xfixes0
    libxcb-xkb1
)
missing=()
for package in "${packages[@]}"; do
    status=$(dpkg-query -W -f='${Status}' "$package" 2>/dev/null || true)
    [[ $status == "install ok installed" ]] || missing+=("$package")
done
((${#missing[@]})) || exit 0
sudo=()
if [[ $(id -u) -ne 0 ]]; then
    command -v sudo >/dev/null 2>&1 || {
        echo "install-frontends: need root to apt-get install ${missing[*]}" >&2
        exit 1
    }
    sudo=(sudo)
fi
echo "installing ${missing[*]} (Debian packages, for the napari and QGIS tests)"
"${sudo[@]}" apt-get update -q >/dev/null
"${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends \
    "${missing[@]}" >/dev/null
