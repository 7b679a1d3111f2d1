#!/usr/bin/env bash
# ctest Package.StartLoadsNoOptionalLibrary: the libraries the CLI loads at its start (ldd) include
# none of those only some commands use — Cairo and fontconfig (render, the pictures of cycle) and
# Open MPI (sweep under mpirun), opened at run time by src/io/shared_library.hpp — nor spdlog and
# fmt (compiled in); then `render` writes a PNG through the Cairo it opens itself, and a command
# that draws nothing never opens Cairo (the loader's log).
# docs/performance.md, "Andrews' squeezer: the start". Usage: start_libraries.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1 source=$2
libs=$(ldd "$build/orthomech")
echo "$(wc -l <<< "$libs") shared libraries at the start:"
awk '{print "  " $1}' <<< "$libs"
bad=$(grep -E 'libcairo|libfontconfig|libmpi|libopen-pal|libspdlog|libfmt' <<< "$libs" || true)
if [ -n "$bad" ]; then
  echo "loaded at every start, but only some commands need them:" >&2
  echo "$bad" >&2
  exit 1
fi
# Every library a process opens, at its start or later (the loader's log, LD_DEBUG=files).
opened() { LD_DEBUG=files "$@" 2>&1 >/dev/null | grep -oE 'file=[^ ]+' | sort -u; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
drawn=$(opened "$build/orthomech" render "$source/mechanisms/crank-rocker.yaml" -o "$tmp/r.png")
head -c 8 "$tmp/r.png" | od -An -tx1 | grep -q '89 50 4e 47 0d 0a 1a 0a' \
  || { echo "render wrote no PNG" >&2; exit 1; }
grep -q 'file=libcairo.so.2' <<< "$drawn" || { echo "render did not open Cairo" >&2; exit 1; }
simulated=$(opened "$build/orthomech" simulate "$source/mechanisms/pendulum.yaml" --t-end 0.1 -q)
if grep -E 'libcairo|libfontconfig|libmpi' <<< "$simulated"; then
  echo "simulate opened Cairo, fontconfig or Open MPI (above)" >&2
  exit 1
fi
echo "render opened Cairo; simulate opened neither Cairo nor Open MPI"
