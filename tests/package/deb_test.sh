#!/usr/bin/env bash
# ctest Package.Deb: `cpack -G DEB` makes orthomech_<version>_amd64.deb with its runtime
# dependencies declared; extracted into a temporary root (dpkg-deb -x) it runs: --version, a
# cycle on a bundled mechanism (the same JSON as the build's CLI) and the Python module.
# Usage: deb_test.sh BUILD_DIR PYTHON VERSION
set -euo pipefail
build=$1 python=$2 version=$3
cd "$build"
rm -f "package/orthomech_${version}_amd64.deb"
cpack -G DEB > cpack.log 2>&1 || { cat cpack.log >&2; exit 1; }
deb=package/orthomech_${version}_amd64.deb
[ -f "$deb" ] || { echo "no $deb" >&2; ls package >&2; exit 1; }
dpkg-deb -I "$deb" > deb-info.txt
depends=$(sed -n 's/^ Depends: //p' deb-info.txt)
echo "Depends: $depends"
for lib in libc6 libstdc++6 libyaml-cpp libnlopt libcairo2 libfontconfig1 libsqlite3 libmuparser \
  libklu1 libspqr coinor-libipopt; do
  grep -q "$lib" <<< "$depends" || { echo "$deb does not depend on $lib" >&2; exit 1; }
done
recommends=$(sed -n 's/^ Recommends: //p' deb-info.txt)
echo "Recommends: $recommends"
grep -q "python3-numpy" <<< "$recommends" || { echo "no python3-numpy in Recommends" >&2; exit 1; }
grep -q "libopenmpi3" <<< "$recommends" || { echo "no libopenmpi3 in Recommends" >&2; exit 1; }
tmp=$build/tests/package/deb
rm -rf "$tmp" && mkdir -p "$tmp"
dpkg-deb -x "$deb" "$tmp/root"
usr=$tmp/root/usr
export LD_LIBRARY_PATH=$usr/lib
want=$("$build/orthomech" --version)
got=$("$usr/bin/orthomech" --version)
[ "$got" = "$want" ] || { echo "--version: '$got', want '$want'" >&2; exit 1; }
echo "$got"
mechanism=$usr/share/orthomech/mechanisms/crank-rocker.yaml
cmp <("$usr/bin/orthomech" cycle "$mechanism" --json --steps 90 | grep -v '"file"') \
  <("$build/orthomech" cycle "$mechanism" --json --steps 90 | grep -v '"file"')
# Cairo is opened at run time (no ELF file names it): the packaged CLI draws through it.
"$usr/bin/orthomech" render "$mechanism" -o "$tmp/r.png"
head -c 4 "$tmp/r.png" | od -An -c | grep -q 'P   N   G' || { echo "render wrote no PNG" >&2; exit 1; }
table=$("$usr/bin/orthomech" cycle "$mechanism" --steps 90)
head -n 3 <<< "$table"
cd "$tmp"
PYTHONPATH=$usr/lib/python3/dist-packages "$python" -c "
import orthomech
assert orthomech.__file__.startswith('$usr'), orthomech.__file__
print('python', orthomech.__version__, orthomech.info('$mechanism')['dof'], 'dof')
"
