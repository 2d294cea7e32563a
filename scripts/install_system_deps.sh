#!/usr/bin/env bash
# Installs Debian's libosmesa6 (headless MuJoCo rendering) when it is missing.
set -euo pipefail
if ldconfig -p 2>/dev/null | grep -q 'libOSMesa\.so'; then
    exit 0
fi
if ! command -v apt-get >/dev/null; then
    echo "libOSMesa not found and apt-get unavailable: install libosmesa6 (or set MUJOCO_GL=egl)" >&2
    exit 0
fi
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
echo "installing libosmesa6 for headless rendering"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq libosmesa6 >/dev/null
