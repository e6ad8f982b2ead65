#!/usr/bin/env bash
# accelcal -- builds GNU's H8/300/H8S simulator (sim/h8300 of GDB) from Debian's
# gdb-source package, with the project's decode-cache and profile patch
# (tools/h8sim/decode-cache.patch, GPL-3.0 like GDB), and checks the cache with
# self-modifying code (tools/h8sim/smc_test.c).
#
# The binary is cached outside the source tree, in
#   ${H8SIM_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/accelcal/h8sim}/<key>/run
# where <key> hashes the patch, the check program, this script and the
# gdb-source version, so a second run costs nothing; the ~310 MB of GDB source
# and build tree are deleted after the build.  Nothing is written into the
# repository.
#
# Usage:  tools/build_h8sim.sh          prints the path of the simulator on stdout
# Needs:  gdb-source (installed with apt-get when missing), a host C compiler,
#         make, patch; h8300-hms-gcc for the self-modifying-code check.
# Exit:   0 with the path printed; 1 with one line "build_h8sim: FAIL: ..." on stderr.
set -euo pipefail
export LC_ALL=C

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
H8DIR="$ROOT/tools/h8sim"
PATCH="$H8DIR/decode-cache.patch"
CROSS=${H8_CROSS:-h8300-hms-}
BASE=${H8SIM_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/accelcal/h8sim}
JOBS=${H8SIM_JOBS:-2}

fail() {
    echo "build_h8sim: FAIL: $*" >&2
    exit 1
}
say() { echo "build_h8sim: $*" >&2; }

tarball() { dpkg -L gdb-source 2> /dev/null | grep -E '/gdb\.tar\.xz$' | head -n 1 || true; }

TAR=$(tarball)
if [ -z "$TAR" ] || [ ! -f "$TAR" ]; then
    say "installing gdb-source (apt-get)"
    SUDO=""
    [ "$(id -u)" = 0 ] || SUDO="sudo"
    { $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq gdb-source; } \
        > /dev/null 2>&1 || fail "apt-get install gdb-source failed"
    TAR=$(tarball)
    [ -n "$TAR" ] && [ -f "$TAR" ] || fail "gdb-source installed but no gdb.tar.xz in 'dpkg -L gdb-source'"
fi
VERSION=$(dpkg-query -W -f='${Version}' gdb-source)
KEY=$(cat "$PATCH" "$H8DIR/smc_test.c" "$H8DIR/crt0.s" "${BASH_SOURCE[0]}" \
    | { cat; echo "gdb-source $VERSION"; } | sha256sum | cut -c1-16)
DEST="$BASE/$KEY"
if [ -x "$DEST/run" ] && [ -f "$DEST/smc-ok" ]; then
    echo "$DEST/run"
    exit 0
fi

for tool in cc make patch tar xz "${CROSS}gcc" python3; do
    command -v "$tool" > /dev/null || fail "'$tool' not found"
done
mkdir -p "$BASE" || fail "cannot create $BASE"
WORK=$(mktemp -d "$BASE/work.XXXXXX") || fail "cannot create a work directory in $BASE"
trap 'rm -rf "$WORK"' EXIT
LOG="$WORK/log"
t0=$(date +%s)

say "gdb-source $VERSION: unpacking $TAR"
tar -xf "$TAR" -C "$WORK" > "$LOG" 2>&1 || fail "unpacking $TAR: $(grep -v "^\s*$" "$LOG" | tail -n 1)"
[ -f "$WORK/gdb/sim/h8300/compile.c" ] || fail "$TAR has no gdb/sim/h8300/compile.c"
patch -d "$WORK/gdb" -p1 --no-backup-if-mismatch < "$PATCH" > "$LOG" 2>&1 \
    || fail "tools/h8sim/decode-cache.patch does not apply to gdb-source $VERSION: $(grep -v "^\s*$" "$LOG" | tail -n 1)"

say "configure (target h8300-elf, simulator only)"
mkdir "$WORK/build"
(cd "$WORK/build" && ../gdb/configure --target=h8300-elf --disable-gdb --disable-gdbserver \
    --disable-gprofng --disable-ld --disable-gas --disable-binutils --disable-gold \
    --disable-readline --disable-libdecnumber --disable-sim-testsuite --disable-werror \
    --disable-nls) > "$LOG" 2>&1 || fail "configure failed: $(grep -m 1 -i 'error' "$LOG" || tail -n 1 "$LOG")"

say "make all-sim -j$JOBS"
# MAKEINFO=true: no texinfo needed (bfd's doc/bfd.info is not built)
(cd "$WORK/build" && nice make -j"$JOBS" MAKEINFO=true all-sim) > "$LOG" 2>&1 \
    || fail "make all-sim failed: $(grep -m 1 -E 'error|Error' "$LOG" || tail -n 1 "$LOG")"
[ -x "$WORK/build/sim/h8300/run" ] || fail "make all-sim gave no sim/h8300/run"
mkdir "$WORK/out"
cp "$WORK/build/sim/h8300/run" "$WORK/out/run"
t1=$(date +%s)
say "built in $((t1 - t0)) s"

# ---- the decode cache against self-modifying code -----------------------------------
say "self-modifying-code check of the decode cache"
CHK="$WORK/smc"
mkdir "$CHK"
"${CROSS}gcc" -mh -mn -c -o "$CHK/crt0.o" "$H8DIR/crt0.s" > "$LOG" 2>&1 || fail "assembling crt0.s: $(head -n 1 "$LOG")"
"${CROSS}gcc" -mh -mn -O2 -std=c99 -Wall -Wextra -Werror -c -o "$CHK/smc.o" "$H8DIR/smc_test.c" > "$LOG" 2>&1 \
    || fail "compiling smc_test.c: $(head -n 1 "$LOG")"
"${CROSS}gcc" -mh -mn -nostdlib -nostartfiles -Wl,-e,_start -o "$CHK/smc.coff" "$CHK/crt0.o" "$CHK/smc.o" \
    > "$LOG" 2>&1 || fail "linking smc_test: $(head -n 1 "$LOG")"
python3 "$H8DIR/elfwrap.py" --cross "$CROSS" "$CHK/smc.coff" "$CHK/smc.elf" || fail "elfwrap.py on smc_test"
set +e
timeout 20 "$WORK/out/run" "$CHK/smc.elf" > "$LOG" 2>&1
rc=$?
H8SIM_NO_DCACHE=1 timeout 20 "$WORK/out/run" "$CHK/smc.elf" >> "$LOG" 2>&1
rc_nocache=$?
H8SIM_DCACHE_NO_INVAL=1 timeout 20 "$WORK/out/run" "$CHK/smc.elf" >> "$LOG" 2>&1
rc_noinval=$?
set -e
[ $rc_nocache -eq 0 ] || fail "smc_test fails without the cache (status $rc_nocache): the check itself is wrong"
[ $rc -eq 0 ] || fail "decode cache is stale after a store into code (smc_test status $rc, bits: 2 word 4 byte 8 long 16 eepmov)"
[ $rc_noinval -eq 30 ] || fail "smc_test does not catch a cache without invalidation (status $rc_noinval, expected 30)"
say "decode cache exact after word, byte, long and eepmov.b stores into code (without invalidation: status 30, as it must)"
touch "$WORK/out/smc-ok"

rm -rf "$DEST"
mv "$WORK/out" "$DEST" || fail "cannot move the result to $DEST"
say "cached: $DEST/run"
echo "$DEST/run"
