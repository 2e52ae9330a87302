#!/usr/bin/env bash
# Installs the Node test dependencies (package-lock.json pins them) into node/node_modules,
# once: later runs compare the lock file with the one installed and do nothing if unchanged.
set -euo pipefail
cd "$(dirname "$0")"
if [[ -d node_modules ]] && cmp -s package-lock.json node_modules/.sim-installed-lock; then
  exit 0
fi
command -v npm >/dev/null || { echo "install.sh: npm is missing; run scripts/install-deps.sh" >&2; exit 1; }
npm ci --no-audit --no-fund --loglevel=error
cp package-lock.json node_modules/.sim-installed-lock
