#!/usr/bin/env bash
# Installs every Debian package the project needs (the lists in scripts/deps/*.txt, plus any
# list files given as arguments). Quick when nothing is missing; needs root (or sudo) otherwise.
#
#   scripts/install-deps.sh [LIST…]          scripts/deps/*.txt and the LISTs
#   scripts/install-deps.sh --only LIST…     the LISTs alone (scripts/demo.sh: scripts/demo-deps.txt)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)

lists=("$here"/deps/*.txt)
if [[ ${1:-} == --only ]]; then
  shift
  (($# > 0)) || { echo "usage: scripts/install-deps.sh --only LIST…" >&2; exit 2; }
  lists=()
fi
mapfile -t wanted < <(cat "${lists[@]}" "$@" | sed 's/#.*//' | tr -s ' \t' '\n' | grep -v '^$' | sort -u)
missing=()
for pkg in "${wanted[@]}"; do
  # Node.js from NodeSource (as on these machines) carries its own npm, which Debian's npm
  # package conflicts with: a working node and npm on the PATH count as installed.
  case $pkg in
    nodejs) command -v node >/dev/null && continue ;;
    npm) command -v npm >/dev/null && continue ;;
  esac
  status=$(dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$pkg")
done
if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#wanted[@]} packages are installed"
  exit 0
fi

as_root=()
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null || { echo "install-deps: run as root to install: ${missing[*]}" >&2; exit 1; }
  as_root=(sudo)
fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${as_root[@]}" apt-get update -qq
"${as_root[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
