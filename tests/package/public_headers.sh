#!/usr/bin/env bash
# ctest Package.PublicHeaders: the public headers (include/orthomech) name no type of the private
# dependencies (Ipopt, NLopt, spdlog, yaml-cpp, Cairo, SQLite, muParser, nlohmann::json, Boost,
# MPI, OpenMP): a user of the installed package needs Eigen only. (The build's
# orthomech_header_check target compiles every header alone with Eigen's include path only.)
# Usage: public_headers.sh SOURCE_DIR
set -euo pipefail
include=$1/include/orthomech
# The code of the headers (comments stripped: they may name the libraries the library uses).
pattern='Ipopt|IpTNLP|SmartPtr|nlopt|spdlog|fmt::|YAML::|yaml_cpp|cairo_|sqlite3|mu::|nlohmann|boost::|MPI_|omp_|pragma omp'
found=$(find "$include" -name '*.hpp' | sort | while read -r h; do
  sed 's://.*$::' "$h" | grep -nE "$pattern" | sed "s|^|$h:|" || true
done)
if [ -n "$found" ]; then
  echo "$found"
  echo "public headers name a private dependency (above)" >&2
  exit 1
fi
# Every #include <...> of a public header is the standard library, Eigen or orthomech's own.
bad=$(grep -rhoE '#include <[^>]+>' "$include" | sed 's/#include <\(.*\)>/\1/' |
  grep -vE '^(Eigen/|orthomech/)' | grep -E '[./]' | grep -vE '^(sys/)' || true)
if [ -n "$bad" ]; then
  echo "public headers include: $bad" >&2
  exit 1
fi
echo "$(find "$include" -name '*.hpp' | wc -l) public headers: Eigen and the standard library only"
