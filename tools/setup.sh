#!/usr/bin/env bash
# Installs what springmass needs on a Debian 12 machine and creates the project's Python
# environment (.venv, pinned by tools/requirements.txt). Idempotent: when everything is
# present it only checks, which takes a second or two.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)

packages=(build-essential cmake ninja-build pkg-config git
          libsundials-dev libgsl-dev libsuitesparse-dev libjansson-dev libblas3 liblapack3
          python3 python3-venv patchelf zip unzip locales)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  sudo=""
  [ "$(id -u)" = 0 ] || sudo=sudo
  echo "setup: installing ${missing[*]}"
  $sudo apt-get update -qq
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

venv=$root/.venv
requirements=$root/tools/requirements.txt
stamp=$venv/.requirements-installed
if [ ! -x "$venv/bin/python" ]; then
  echo "setup: creating the Python environment in .venv"
  /usr/bin/python3 -m venv "$venv"
fi
if ! cmp -s "$requirements" "$stamp"; then
  echo "setup: installing the pinned Python packages"
  "$venv/bin/python" -m pip install -q --disable-pip-version-check -r "$requirements"
  cp "$requirements" "$stamp"
fi
