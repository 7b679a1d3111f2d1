#!/usr/bin/env bash
# ctest Package.SourcesListed: CMake lists the sources (no globbing), so a file not listed would
# be left out silently (a test file not run at all). Every src/**/*.cpp and cli/*.cpp is named in
# CMakeLists.txt, every tests/unit/**/*_test.cpp in tests/CMakeLists.txt, and every listed file
# exists. Usage: sources_listed.sh SOURCE_DIR
set -euo pipefail
cd "$1"
status=0
listed() {  # listed CMAKEFILE PREFIX FILE...: each FILE (relative to PREFIX) is named in CMAKEFILE
  local cmake=$1 prefix=$2
  shift 2
  for f in "$@"; do
    if ! grep -qE "(^|[[:space:]])${f#"$prefix"}([[:space:]]|\)|$)" "$cmake"; then
      echo "$f is not listed in $cmake" >&2
      status=1
    fi
  done
}
mapfile -t lib < <(find src cli -name '*.cpp' | sort)
mapfile -t tests < <(find tests/unit -name '*_test.cpp' | sort)
listed CMakeLists.txt "" "${lib[@]}"
listed tests/CMakeLists.txt tests/ "${tests[@]}"
# And the other way: what is listed exists.
for f in $(sed -n '/^set(ORTHOMECH_LIB_SOURCES/,/)/p; /^add_library(orthomech_cli_objects/,/)/p' \
  CMakeLists.txt | grep -oE '(src|cli)/[A-Za-z0-9_/]+\.cpp'); do
  [ -f "$f" ] || { echo "CMakeLists.txt lists $f, which does not exist" >&2; status=1; }
done
for f in $(grep -oE 'unit/[A-Za-z0-9_/]+_test\.cpp' tests/CMakeLists.txt); do
  [ -f "tests/$f" ] || { echo "tests/CMakeLists.txt lists $f, which does not exist" >&2; status=1; }
done
[ $status -eq 0 ] && echo "${#lib[@]} library and CLI sources, ${#tests[@]} test files: all listed"
exit $status
