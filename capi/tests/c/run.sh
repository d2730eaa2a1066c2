#!/usr/bin/env bash
# Builds the C library, checks the committed header is what cbindgen
# generates, compiles the C tests with the system `cc` against the shared and
# the static library, and runs them under valgrind memcheck (any error or leak
# fails). Needs cbindgen 0.29 and valgrind on PATH (.ci/run installs them):
#   cargo install cbindgen --version 0.29.2 --locked
#   apt-get install valgrind        (Debian/Ubuntu; brew install valgrind elsewhere)
# Usage: capi/tests/c/run.sh [MATERIALS [PAIRS]]   (3 rows per pair: R, G, B)
set -euo pipefail
cd "$(dirname "$0")/../../.."
materials=${1:-34}
pairs=${2:-10}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

for tool in cbindgen valgrind; do
  command -v "$tool" >/dev/null || {
    echo "capi/tests/c/run.sh needs $tool on PATH:" >&2
    case $tool in
      cbindgen) echo "  cargo install cbindgen --version 0.29.2 --locked" >&2 ;;
      valgrind) echo "  apt-get install valgrind (Debian/Ubuntu), or your system's package" >&2 ;;
    esac
    exit 1
  }
done
cbindgen --version | grep -q ' 0\.29\.' || {
  echo "capi/tests/c/run.sh needs cbindgen 0.29 (found $(cbindgen --version)):" >&2
  echo "  cargo install cbindgen --version 0.29.2 --locked" >&2
  exit 1
}
cbindgen --config capi/cbindgen.toml --crate twoscale-capi --output "$out/twoscale.h"
if ! diff -u capi/include/twoscale.h "$out/twoscale.h"; then
  echo "capi/include/twoscale.h is stale: regenerate it with" >&2
  echo "  cbindgen --config capi/cbindgen.toml --crate twoscale-capi --output capi/include/twoscale.h" >&2
  exit 1
fi

cargo build -p twoscale-capi -p generator --release --locked
lib=target/release
cflags=(-std=c11 -Wall -Wextra -Werror -pedantic -O2 -g -I capi/include)
for t in misuse query_rows small_stack material_file spectral; do
  cc "${cflags[@]}" "capi/tests/c/$t.c" -L "$lib" -ltwoscale_capi -Wl,-rpath,"$PWD/$lib" \
    -lm -lpthread -o "$out/$t"
done
# The static library links on its own with the system libraries Rust's std needs.
cc "${cflags[@]}" capi/tests/c/misuse.c "$lib/libtwoscale_capi.a" \
  -lgcc_s -lutil -lrt -lpthread -lm -ldl -lc -o "$out/misuse-static"
"$out/misuse-static" tables

memcheck=(valgrind --error-exitcode=1 --leak-check=full
  --errors-for-leak-kinds=definite,indirect,possible -q)
"${memcheck[@]}" "$out/misuse" tables
"$out/query_rows" rows "$materials" "$pairs" 2026 > "$out/rows.csv"
"$lib/generator" query brdf --tables tables < "$out/rows.csv" > "$out/answered.csv"
"${memcheck[@]}" "$out/query_rows" compare "$out/answered.csv" "$materials" "$pairs"
"${memcheck[@]}" "$out/small_stack"
"${memcheck[@]}" "$out/material_file" check "$out"
"${memcheck[@]}" "$out/spectral"

# docs/c-api.md verbatim: its one ```c block saved as example.c at the root
# and the ```sh block of "Build and link" run there (it builds and runs
# ./example and ./example-static); each prints three positive values. Then
# the example once more under memcheck.
snippet=(example.c example example-static)
for f in "${snippet[@]}"; do
  if [ -e "$f" ]; then
    echo "$f exists at the root; move it away (the docs/c-api.md check writes it)" >&2
    exit 1
  fi
done
trap 'rm -rf "$out" "${snippet[@]}"' EXIT
awk '/^```c$/{on=1; next} /^```$/{on=0} on' docs/c-api.md > example.c
awk '/^## /{section=($0 == "## Build and link")} section && /^```sh$/{on=1; next}
  on && /^```$/{exit} on' docs/c-api.md > "$out/build-and-link.sh"
grep -q 'example-static' "$out/build-and-link.sh"
bash -euo pipefail "$out/build-and-link.sh" | tee "$out/example.txt"
test "$(wc -l < "$out/example.txt")" -eq 2
awk '{ if (!($3 > 0 && $4 > 0 && $5 > 0)) exit 1 }' "$out/example.txt"
"${memcheck[@]}" ./example > /dev/null
