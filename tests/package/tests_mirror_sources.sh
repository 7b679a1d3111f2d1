#!/usr/bin/env bash
# ctest Package.TestsMirrorSources: the tests mirror the sources file for file
# (docs/architecture.md "Tests"): every src/<dir>/<name>.cpp has tests/unit/<dir>/<name>_test.cpp
# and every cli/<name>.cpp has tests/unit/cli/<name>_cli_test.cpp, except cli/main.cpp (one line
# calling cli::run, tested through run_cli_test.cpp). Usage: tests_mirror_sources.sh SOURCE_DIR
set -euo pipefail
cd "$1"
status=0
count=0
while IFS= read -r f; do
  test="tests/unit/${f#src/}"
  test="${test%.cpp}_test.cpp"
  count=$((count + 1))
  [ -f "$test" ] || { echo "$f has no $test" >&2; status=1; }
done < <(find src -name '*.cpp' | sort)
while IFS= read -r f; do
  [ "$f" = cli/main.cpp ] && continue
  test="tests/unit/cli/$(basename "$f" .cpp)_cli_test.cpp"
  count=$((count + 1))
  [ -f "$test" ] || { echo "$f has no $test" >&2; status=1; }
done < <(find cli -name '*.cpp' | sort)
[ $status -eq 0 ] && echo "$count sources, each with its test file"
exit $status
