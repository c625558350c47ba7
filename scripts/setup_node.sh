#!/usr/bin/env bash
# Installs the two JavaScript FOLD readers the fmpy suite checks
# `simulate --fold-out` files with: the FOLD format's own library (npm
# `fold`) and Rabbit Ear (npm `rabbit-ear`), pinned, into .node/ (like
# .venv; idempotent: a second run only checks). Installs Debian's nodejs
# and npm with apt-get when node or npm is missing (a fresh Debian machine,
# as root; Debian 12's Node.js 18 reads them); prints the node_modules
# folder, or exits 1 with what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."
FOLD_VERSION=0.12.0
RABBIT_EAR_VERSION=0.9.32
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
    echo "installing nodejs and npm" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >&2
    apt-get install -y -qq --no-install-recommends nodejs npm >&2
  fi
fi
for tool in node npm; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "$tool is not installed: install Node.js (with npm) to check FOLD files in JavaScript" >&2
    exit 1
  fi
done
have() {
  node -e "process.exit(require('./.node/node_modules/$1/package.json').version === '$2' ? 0 : 1)" 2>/dev/null
}
if ! have fold "$FOLD_VERSION" || ! have rabbit-ear "$RABBIT_EAR_VERSION"; then
  mkdir -p .node
  npm install --prefix .node --no-audit --no-fund --no-save --silent \
    "fold@$FOLD_VERSION" "rabbit-ear@$RABBIT_EAR_VERSION" >&2
fi
echo "$PWD/.node/node_modules"
