#!/usr/bin/env bash
# What `origami-fmu build --platforms win64` needs on Debian 12 to
# cross-build the win64 DLL (x86_64-win7-windows-gnu, std built from its
# source): Rust 1.96 with its library source (rustc-web, cargo-web,
# rust-web-src) and the MinGW-w64 gcc that links it. Installs what is
# missing with apt-get (as root); does nothing when all is there.
set -euo pipefail
packages=(rustc-web cargo-web rust-web-src gcc-mingw-w64-x86-64)
missing=()
for p in "${packages[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq >&2
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
fi
echo "win64 cross build: /usr/bin/cargo $(/usr/bin/cargo --version | cut -d' ' -f2), $(x86_64-w64-mingw32-gcc --version | head -n 1)"
