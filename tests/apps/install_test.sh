#!/usr/bin/env bash
# `cmake --install BUILD --prefix P` into a scratch prefix, then P/bin/nimbus reads a .vdb file through
# P/LIBDIR/nimbus/libnimbus_openvdb.so, the installed module (not the build tree's): replaced by a broken
# file there, the same command fails naming it. Run by ctest (CMakeLists.txt, Install.*).
#   install_test.sh CMAKE BUILD_DIR LIBDIR VDB_FILE
set -euo pipefail
cmake=$1 build=$2 libdir=$3 vdb=$4
prefix=$(mktemp -d)
trap 'rm -rf "$prefix"' EXIT
"$cmake" --install "$build" --prefix "$prefix" > "$prefix/install.log"
module="$prefix/$libdir/nimbus/libnimbus_openvdb.so"
test -f "$module" || { echo "not installed: $module"; cat "$prefix/install.log"; exit 1; }
out=$(env -u NIMBUS_OPENVDB_MODULE "$prefix/bin/nimbus" info "$vdb")
grep -q "active voxels 25" <<< "$out" || { echo "unexpected info output: $out"; exit 1; }
echo "not a shared object" > "$module"
if err=$(env -u NIMBUS_OPENVDB_MODULE "$prefix/bin/nimbus" info "$vdb" 2>&1); then
  echo "read the file with a broken installed module: $err"; exit 1
fi
grep -qF "cannot load $module" <<< "$err" || { echo "the error does not name the installed module: $err"; exit 1; }
echo "ok: $prefix/bin/nimbus loads $module"
