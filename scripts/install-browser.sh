#!/usr/bin/env bash
# Install Debian's Chromium and its driver for the viewer page's browser test
# (tests/service/test_page.py), unless they are there. `make test` runs it; needs root
# (or sudo) for apt-get. Nothing downloads a browser of its own.
set -euo pipefail
missing=()
command -v chromium >/dev/null 2>&1 || missing+=(chromium)
command -v chromedriver >/dev/null 2>&1 || missing+=(chromium-driver)
((${#missing[@]})) || exit 0
sudo=()
if [[ $(id -u) -ne 0 ]]; then
    command -v sudo >/dev/null 2>&1 || {
        echo "install-browser: need root to apt-get install ${missing[*]}" >&2
        exit 1
    }
    sudo=(sudo)
fi
echo "installing ${missing[*]} (Debian packages, for the browser test)"
"${sudo[@]}" apt-get update -q >/dev/null
"${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends \
    "${missing[@]}" >/dev/null
