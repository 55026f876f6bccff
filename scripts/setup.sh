#!/usr/bin/env bash
# Installs what fluxdrive needs on a fresh Debian machine: the apt packages
# (only those missing) and the Python venv .venv with pinned versions.
# Idempotent; called by scripts/demo.sh and scripts/test.sh.
set -euo pipefail
cd "$(dirname "$0")/.."

APT_PACKAGES=(cmake ninja-build gcc g++ libcmocka-dev libcjson-dev
  gcc-arm-none-eabi libnewlib-arm-none-eabi libeigen3-dev
  python3 python3-venv clang-format clang-tidy cppcheck qemu-system-arm
  clang-14 libclang-rt-14-dev)

missing=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing apt packages: ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

stamp=.venv/.fluxdrive-lock
if [ ! -x .venv/bin/python ] || ! cmp -s tools/requirements.lock "$stamp" 2>/dev/null; then
  echo "setup: creating the Python venv .venv (pinned: tools/requirements.lock)"
  python3 -m venv .venv
  .venv/bin/python -m pip install -q --upgrade pip==24.0
  .venv/bin/python -m pip install -q -r tools/requirements.lock
  .venv/bin/python -m pip install -q --no-deps -e tools
  cp tools/requirements.lock "$stamp"
fi
