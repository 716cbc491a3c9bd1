#!/usr/bin/env bash
# Set up IceBridge on a fresh Debian machine with Python 3.11 or 3.12: the system packages the node
# and its tests need (installed with apt-get only when missing), a virtual environment in
# .venv, and the project with its dev extras. Safe to run again: it only adds what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

# socat: pty pairs for the serial and Modbus RTU link tests; EGL + Mesa: headless rendering;
# xvfb: a virtual X display for the channel-window tests; gpsd: the NMEA consumer the link
# tests feed; chromium + chromium-driver: the headless browser the instructor station's tests drive
SYSTEM_PACKAGES=(socat libegl1 libgl1 libegl-mesa0 libgl1-mesa-dri xvfb gpsd chromium chromium-driver)

missing=()
for pkg in "${SYSTEM_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing system packages: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi

[ -x .venv/bin/python ] || python3 -m venv .venv
.venv/bin/python -m pip install -q --disable-pip-version-check -e '.[dev]'
echo "setup: ready (.venv)"
