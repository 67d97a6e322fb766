#!/usr/bin/env bash
# Installs every Debian package listed in scripts/debian-packages.txt (as root).
# Quick when everything is already installed: apt is only called for what is missing.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
mapfile -t wanted < <(grep -v '^\s*#' "$here/debian-packages.txt" | awk 'NF {print $1}')
missing=()
for pkg in "${wanted[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$pkg")
done
if ((${#missing[@]} == 0)); then
  echo "[setup] all ${#wanted[@]} Debian packages present"
  exit 0
fi
echo "[setup] installing ${#missing[@]} Debian packages: ${missing[*]}"
if [[ $(id -u) -ne 0 ]]; then
  echo "[setup] error: installing packages needs root (run the command as root)" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update -q
apt-get install -y -q --no-install-recommends "${missing[@]}"
# roslaunch needs localhost to resolve
grep -qE '^\s*127\.0\.0\.1\s.*\blocalhost\b' /etc/hosts || echo '127.0.0.1 localhost' >> /etc/hosts
