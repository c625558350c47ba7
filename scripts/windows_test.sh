#!/usr/bin/env bash
# The win64 FMU under wine, headless. Installs what it needs with apt-get
# (scripts/setup_windows_build.sh, then wine), builds
# scenes/single_crease.fold's FMU with `origami-fmu build --platforms
# linux64,win64` (which cross-builds the DLL, x86_64-win7-windows-gnu:
# about 6 min from scratch on 2 cores, seconds when up to date), checks
# the DLL imports system DLLs only, runs the library tests under wine,
# and runs tests/c_host/host.c twice on that FMU: compiled with MinGW-w64
# under wine against binaries/win64, and natively against binaries/linux64.
# Both must pass every check, and their outputs over 100 steps agree within
# 1e-9 of each output's scale (scripts/compare_outputs.py).
set -euo pipefail
cd "$(dirname "$0")/.."
start=$SECONDS
bash scripts/setup_windows_build.sh
if ! dpkg -s wine wine64 >/dev/null 2>&1; then
  echo "installing wine" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq >&2
  apt-get install -y -qq --no-install-recommends wine wine64 >&2
fi
target=x86_64-win7-windows-gnu
tmp=$(mktemp -d)
# wine: a prefix of its own (made on the first start), no display, no
# debug output, no Mono or Gecko installer; its server ends with the test.
export WINEPREFIX="$tmp/wine" WINEDEBUG=-all WINEDLLOVERRIDES="mscoree,mshtml="
unset DISPLAY WAYLAND_DISPLAY
trap 'wineserver -k >/dev/null 2>&1 || true; rm -rf "$tmp"' EXIT
wineboot --init >/dev/null 2>&1 || true

cargo build --release --locked 2>&1 | tail -n 1
echo "== win64: origami-fmu build --platforms linux64,win64"
t=$SECONDS
if ! target/release/origami-fmu build scenes/single_crease.fold -o "$tmp/sc.fmu" \
  --platforms linux64,win64 2>"$tmp/build.log"; then
  tail -n 40 "$tmp/build.log"
  exit 1
fi
echo "win64: FMU built in $((SECONDS - t)) s"
python3 -m zipfile -e "$tmp/sc.fmu" "$tmp/sc"
dll="$tmp/sc/binaries/win64/origami_fmu.dll"
test -f "$tmp/sc/binaries/linux64/origami_fmu.so"
# System DLLs only: no MinGW runtime (libgcc_s, libwinpthread) to ship, and
# no bcryptprimitives.dll (Windows 10 and newer; wine 8 lacks it).
imports=$(x86_64-w64-mingw32-objdump -p "$dll" | sed -n 's/^\tDLL Name: //p' | sort -u | tr '\n' ' ')
echo "win64: origami_fmu.dll ($(stat -c %s "$dll") bytes) imports $imports"
for name in $imports; do
  case "${name,,}" in
    kernel32.dll | ntdll.dll | msvcrt.dll | ws2_32.dll | userenv.dll | advapi32.dll | bcrypt.dll | \
      api-ms-win-*.dll) ;;
    *) echo "win64: origami_fmu.dll imports $name, not a system DLL of Windows 7" >&2; exit 1 ;;
  esac
done

echo "== win64: library tests under wine"
# The same environment and std crates as the build above (src/cli/platforms.rs),
# so that std and the dependencies built there are used as they are.
t=$SECONDS
RUSTC=/usr/bin/rustc RUSTC_BOOTSTRAP=1 \
  CARGO_TARGET_X86_64_WIN7_WINDOWS_GNU_LINKER=x86_64-w64-mingw32-gcc \
  CARGO_TARGET_X86_64_WIN7_WINDOWS_GNU_RUNNER=wine \
  /usr/bin/cargo test --release --locked --lib --target "$target" -Zbuild-std=std,panic_unwind,test
echo "win64: library tests built and run in $((SECONDS - t)) s"

echo "== win64: the C host under wine, and natively against linux64"
cc -std=gnu11 -O1 -Wall -Wextra -Werror -o "$tmp/host" tests/c_host/host.c -ldl -lm
x86_64-w64-mingw32-gcc -std=gnu11 -O1 -Wall -Wextra -Werror -o "$tmp/host.exe" tests/c_host/host.c -lm
"$tmp/host" "$tmp/sc" "$tmp/linux64.csv"
wine "$tmp/host.exe" "$tmp/sc" "$tmp/win64.csv"
python3 scripts/compare_outputs.py "$tmp/linux64.csv" "$tmp/win64.csv" 1e-9
echo "windows_test: passed in $((SECONDS - start)) s"
