#!/usr/bin/env bash
# ctest Package.Consumer: `cmake --install` into a temporary prefix, then the installed package as
# a user sees it: the layout (GNUInstallDirs), examples/cpp built with find_package(orthomech)
# and with pkg-config (shared and static), its peak drive against the installed CLI's JSON, and
# the installed Python module. Usage: consumer_test.sh BUILD_DIR SOURCE_DIR PYTHON
set -euo pipefail
build=$1 source=$2 python=$3
# A fixed folder in the build tree (ccache hits from one run to the next; left for inspection).
tmp=$build/tests/package/consumer
rm -rf "$tmp" && mkdir -p "$tmp"
prefix=$tmp/prefix
cmake --install "$build" --prefix "$prefix" > /dev/null
version=$(sed -n 's/^#define ORTHOMECH_VERSION "\(.*\)"$/\1/p' "$prefix/include/orthomech/version.hpp")
major_minor=${version%.*}
for f in bin/orthomech lib/liborthomech.a "lib/liborthomech.so.$major_minor" \
  "lib/liborthomech.so.$version" lib/liborthomech.so include/orthomech/version.hpp \
  include/orthomech/analysis/cycle.hpp lib/cmake/orthomech/orthomech-config.cmake \
  lib/cmake/orthomech/orthomech-config-version.cmake lib/cmake/orthomech/orthomech-targets.cmake \
  lib/pkgconfig/orthomech.pc share/orthomech/mechanisms/crank-rocker.yaml \
  share/doc/orthomech/README.md share/doc/orthomech/CHANGELOG.md share/doc/orthomech/cli.md \
  lib/python3/dist-packages/orthomech/__init__.py; do
  [ -e "$prefix/$f" ] || { echo "not installed: $f" >&2; exit 1; }
done
ls "$prefix"/lib/python3/dist-packages/orthomech/_orthomech*.so > /dev/null

mechanism=$prefix/share/orthomech/mechanisms/crank-rocker.yaml
# The oracle: the installed CLI's peak drive (SI units).
expected=$("$prefix/bin/orthomech" cycle "$mechanism" --units si --json |
  "$python" -c 'import json, sys; print(repr(json.load(sys.stdin)["peaks"]["drive"]["peak"]))')
check() {  # check LABEL OUTPUT: OUTPUT's peak drive equals the CLI's (relative 1e-12)
  "$python" - "$1" "$2" "$expected" << 'PY'
import re, sys
label, out, expected = sys.argv[1], sys.argv[2], float(sys.argv[3])
m = re.search(r"peak drive (\S+) N\*m", out)
assert m, f"{label}: no peak drive in {out!r}"
got = float(m[1])
assert abs(got - expected) <= 1e-12 * abs(expected), f"{label}: {got} != CLI {expected}"
print(f"{label}: peak drive {got} N*m = CLI's")
PY
}

launcher=()
command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# find_package(orthomech 0.x REQUIRED) with the package's own prefix only.
cmake -S "$source/examples/cpp" -B "$tmp/example" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" "${launcher[@]}" > "$tmp/configure.log" ||
  { cat "$tmp/configure.log" >&2; exit 1; }
cmake --build "$tmp/example" > "$tmp/build.log" || { cat "$tmp/build.log" >&2; exit 1; }
# The default file is the package's own crank-rocker (orthomech_MECHANISMS_DIR).
check "find_package" "$("$tmp/example/peak_drive")"
# A version the package does not provide is refused (orthomech-config-version.cmake).
mkdir -p "$tmp/v9"
printf 'cmake_minimum_required(VERSION 3.20)\nproject(v LANGUAGES CXX)\nfind_package(orthomech 9.0 REQUIRED)\n' \
  > "$tmp/v9/CMakeLists.txt"
if cmake -S "$tmp/v9" -B "$tmp/v9/build" -DCMAKE_PREFIX_PATH="$prefix" > /dev/null 2>&1; then
  echo "find_package(orthomech 9.0) accepted version $version" >&2
  exit 1
fi

# pkg-config (the .pc file is relocatable: its prefix is relative to itself).
export PKG_CONFIG_PATH=$prefix/lib/pkgconfig
[ "$(pkg-config --modversion orthomech)" = "$version" ]
compiler=(c++)
command -v ccache > /dev/null && compiler=(ccache c++)
# shellcheck disable=SC2046
"${compiler[@]}" -std=c++20 -O2 -DMECHANISMS_DIR="\"$prefix/share/orthomech/mechanisms\"" \
  -c "$source/examples/cpp/peak_drive.cpp" -o "$tmp/peak_drive.o" $(pkg-config --cflags orthomech)
# shellcheck disable=SC2046
c++ "$tmp/peak_drive.o" -o "$tmp/peak_drive_pc" $(pkg-config --libs orthomech)
check "pkg-config" "$(LD_LIBRARY_PATH=$prefix/lib "$tmp/peak_drive_pc" "$mechanism")"
# Static: liborthomech.a and its private dependencies (Requires.private, pkg-config --static).
# shellcheck disable=SC2046
c++ "$tmp/peak_drive.o" -o "$tmp/peak_drive_static" -L"$prefix/lib" -Wl,-Bstatic -lorthomech \
  -Wl,-Bdynamic $(pkg-config --static --libs orthomech | sed 's/-lorthomech//')
if ldd "$tmp/peak_drive_static" | grep -q liborthomech; then
  echo "peak_drive_static loads liborthomech.so" >&2
  exit 1
fi
check "pkg-config --static" "$("$tmp/peak_drive_static" "$mechanism")"

# The installed Python module (its RPATH finds the installed liborthomech).
cd "$tmp"
PYTHONPATH=$prefix/lib/python3/dist-packages "$python" -c "
import orthomech, sys
assert orthomech.__file__.startswith('$prefix'), orthomech.__file__
r = orthomech.cycle('$mechanism', units='si')
assert abs(r['peaks']['drive']['peak'] - $expected) <= 1e-12 * abs($expected)
print('python: peak drive', r['peaks']['drive']['peak'], 'N*m = CLI\'s')
"
