#!/bin/sh
# Builds CSM (Censi's PL-ICP [Censi2008], github.com/AndreaCensi/csm; the results' figures are
# from commit dff2557) as a CMake Release with -O3 -D_GNU_SOURCE against the
# system GSL, and this folder's driver sm_tum against its static library.
#
# Usage: tools/csm/build.sh CSM_SOURCE_DIR BUILD_DIR
# Needs cmake, a C compiler and libgsl-dev. Writes BUILD_DIR/sm_tum.
set -eu
[ $# -eq 2 ] || { echo "usage: $0 CSM_SOURCE_DIR BUILD_DIR" >&2; exit 2; }
SRC=$(cd "$1" && pwd)
mkdir -p "$2"
OUT=$(cd "$2" && pwd)
HERE=$(cd "$(dirname "$0")" && pwd)
cmake -S "$SRC" -B "$OUT/csm" -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_FLAGS="-O3 -D_GNU_SOURCE"
make -C "$OUT/csm" csm-static
cc -O3 -D_GNU_SOURCE -std=c99 -Wall -DNDEBUG \
   -I"$SRC/sm" -I"$SRC/sm/lib" -I"$OUT/csm" \
   "$HERE/sm_tum.c" -o "$OUT/sm_tum" \
   "$OUT/csm/sm/libcsm-static.a" -lgsl -lgslcblas -lm
echo "$OUT/sm_tum"
