#!/usr/bin/env bash
# The C host test: packs the square scene's FMU with the release build,
# unpacks it, compiles tests/c_host/host.c with cc and runs it, natively
# and then under valgrind (memcheck: invalid reads and writes, uses of
# uninitialized values, leaks; any of them fails the test). Installs
# valgrind with apt-get when missing (a fresh Debian machine, as root).
# No suppressions: the one block left at exit is the dynamic loader's
# thread-local storage for the library (still reachable, not an error).
# Then the Rust test of freeing after a panic (tests/fmi_free.rs), under
# valgrind as well.
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v valgrind >/dev/null 2>&1; then
  echo "installing valgrind" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq >&2
  apt-get install -y -qq valgrind >&2
fi
cargo build --release --locked 2>&1 | tail -n 1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
target/release/origami-fmu build tests/fmpy/scenes/square.json -o "$tmp/square.fmu" >/dev/null
python3 -m zipfile -e "$tmp/square.fmu" "$tmp/square"
cc -std=gnu11 -O1 -g -Wall -Wextra -Werror -o "$tmp/host" tests/c_host/host.c -ldl -lm
# Natively first: a plain failure reads more easily than valgrind's.
"$tmp/host" "$tmp/square"
valgrind --quiet --error-exitcode=1 --leak-check=full \
  --errors-for-leak-kinds=definite,indirect,possible \
  --show-leak-kinds=definite,indirect,possible \
  "$tmp/host" "$tmp/square"
echo "c_host: no valgrind errors"
# Freeing after a panic cannot be provoked from C (there is no panic to
# reach): tests/fmi_free.rs kills an instance through the library's guard
# and frees its states; run that test binary under valgrind too.
free_test=$(cargo test --release --locked --test fmi_free --no-run --message-format=json 2>/dev/null |
  python3 -c 'import json, sys
for line in sys.stdin:
    m = json.loads(line)
    if m.get("reason") == "compiler-artifact" and m["target"]["name"] == "fmi_free" and m.get("executable"):
        print(m["executable"])')
valgrind --quiet --error-exitcode=1 --leak-check=full \
  --errors-for-leak-kinds=definite,indirect,possible \
  --show-leak-kinds=definite,indirect,possible \
  "$free_test"
echo "fmi_free: no valgrind errors (a dead instance frees its states)"
