#!/usr/bin/env bash
# accelcal -- the test vectors on the seed's own instruction set: tests/c/vectors.c
# with the whole core, built for the H8/300H in normal mode (h8300-hms-gcc -mh -mn,
# the firmware's flags) at -Os and at -O2, run on GNU's H8 simulator
# (tools/build_h8sim.sh) and compared byte for byte with the host build's output.
#
# A run passes only if all of these hold: the simulator exits with status 0 (the
# program's own exit sequence; a crash, an illegal instruction or a stray sleep
# gives a signal number), within the time bound (H8SIM_TIMEOUT), its output has
# the BEGIN and END lines, the END line's count matches the lines found, and the
# lines from BEGIN to END are byte-equal to the host's.  On a difference the
# first differing vector line is named (its tag, line number, host and H8 text).
#
# The library objects link with nothing else: the vector program's own needs
# (memcpy for structure copies, __umodsi3 for a 32-bit %) are renamed in
# vectors.o only and given by tests/c/vectors_h8.c.
#
# Usage:  tools/run_h8_tests.sh            (outputs in build/h8sim/)
# Env:    H8SIM_TIMEOUT (seconds per run, default 120), H8_OPTS (default "Os O2")
# Exit:   0 = both builds identical to the host; 1 = any failure.
set -euo pipefail
export LC_ALL=C

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
OUT="$ROOT/build/h8sim"
CROSS=${H8_CROSS:-h8300-hms-}
TIMEOUT=${H8SIM_TIMEOUT:-120}
read -r -a OPTS <<< "${H8_OPTS:-Os O2}"
HOST_CC=${CC:-cc}
HOST_CFLAGS=(-std=c99 -O2 -Wall -Wextra -Werror -I"$ROOT/include")

fail() {
    echo "run_h8_tests: FAIL: $*" >&2
    exit 1
}

for tool in "${CROSS}gcc" "${CROSS}objcopy" "${CROSS}size" "$HOST_CC" python3 timeout cmp; do
    command -v "$tool" > /dev/null || fail "'$tool' not found"
done
shopt -s nullglob
CORE_SRC=("$ROOT"/csrc/*.c)
shopt -u nullglob
[ ${#CORE_SRC[@]} -gt 0 ] || fail "no sources in csrc/"

SIM=$(bash "$ROOT/tools/build_h8sim.sh") || exit 1
[ -x "$SIM" ] || fail "build_h8sim.sh gave no simulator"

rm -rf "$OUT"
mkdir -p "$OUT"

frame() { # the compared part: BEGIN line .. END line
    sed -n '/^BEGIN accelcal-vectors/,/^END accelcal-vectors/p' "$1"
}

# ---- host reference --------------------------------------------------------------------------
echo "== host build ($HOST_CC) and run"
"$HOST_CC" "${HOST_CFLAGS[@]}" -o "$OUT/vectors_host" \
    "${CORE_SRC[@]}" "$ROOT/tests/c/vectors.c" "$ROOT/tests/c/vectors_host.c" \
    || fail "host build of the vector program"
"$OUT/vectors_host" > "$OUT/host_stdout.txt" || fail "host vector program exited with an error"
frame "$OUT/host_stdout.txt" > "$OUT/vectors_host.txt"
grep -q '^END accelcal-vectors' "$OUT/vectors_host.txt" || fail "host output has no END line"

check_count() { # the END line carries the line count
    local f=$1 declared actual
    declared=$((16#$(tail -n 1 "$f" | awk '{print $3}')))
    actual=$(($(wc -l < "$f") - 2))
    [ "$declared" -eq "$actual" ] || fail "$(basename "$f"): END says $declared lines, found $actual"
}
check_count "$OUT/vectors_host.txt"

# ---- per optimisation level ------------------------------------------------------------------------
for opt in "${OPTS[@]}"; do
    D="$OUT/$opt"
    mkdir -p "$D/obj"
    CFLAGS=(-mh -mn -"$opt" -fomit-frame-pointer -std=c99 -Wall -Wextra -Werror -I"$ROOT/include")
    echo "== H8/300H build (${CROSS}gcc $("${CROSS}gcc" -dumpversion) ${CFLAGS[*]:0:4})"
    objs=()
    for src in "${CORE_SRC[@]}"; do
        o="$D/obj/$(basename "$src" .c).o"
        "${CROSS}gcc" "${CFLAGS[@]}" -c -o "$o" "$src" || fail "-$opt: compiling $(basename "$src")"
        objs+=("$o")
    done
    "${CROSS}gcc" "${CFLAGS[@]}" -c -o "$D/vectors.o" "$ROOT/tests/c/vectors.c" || fail "-$opt: compiling vectors.c"
    "${CROSS}objcopy" --redefine-sym _memcpy=_h8vec_memcpy --redefine-sym ___umodsi3=_h8vec_umodsi3 \
        "$D/vectors.o" || fail "-$opt: renaming vectors.o's helpers"
    "${CROSS}gcc" "${CFLAGS[@]}" -c -o "$D/vectors_h8.o" "$ROOT/tests/c/vectors_h8.c" || fail "-$opt: compiling vectors_h8.c"
    "${CROSS}gcc" -mh -mn -c -o "$D/crt0.o" "$ROOT/tools/h8sim/crt0.s" || fail "assembling crt0.s"
    if ! "${CROSS}gcc" -mh -mn -nostdlib -nostartfiles -Wl,-e,_start -Wl,-Map="$D/vectors.map" \
        -o "$D/vectors.coff" "$D/crt0.o" "$D/vectors.o" "$D/vectors_h8.o" "${objs[@]}" 2> "$D/link.log"; then
        sed 's/^/  /' "$D/link.log" >&2
        fail "-$opt: the vector program does not link on its own (a symbol from libc/libgcc?)"
    fi
    python3 "$ROOT/tools/h8sim/elfwrap.py" --cross "$CROSS" "$D/vectors.coff" "$D/vectors.elf" \
        || fail "-$opt: elfwrap.py"
    "${CROSS}size" "$D/vectors.coff" | sed "s#$D/##"

    echo "== run on the simulated H8/300H, normal mode (-$opt, bound ${TIMEOUT}s)"
    t0=$(date +%s.%N)
    set +e
    timeout "$TIMEOUT" "$SIM" -v "$D/vectors.elf" > "$D/h8_stdout.txt" 2> "$D/h8_stderr.txt"
    rc=$?
    set -e
    t1=$(date +%s.%N)
    secs=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }')
    if [ $rc -eq 124 ]; then
        fail "-$opt: the H8 run did not end within ${TIMEOUT}s (hang?); last line: $(grep -a -v '^$' "$D/h8_stdout.txt" | tail -n 1)"
    fi
    if [ $rc -ne 0 ]; then
        why=$(grep -a -m 1 'program stopped' "$D/h8_stderr.txt" || true)
        fail "-$opt: the simulator exited with status $rc${why:+ ($why)}; last line: $(grep -a -v '^$' "$D/h8_stdout.txt" | tail -n 1)"
    fi
    frame "$D/h8_stdout.txt" > "$D/vectors_h8.txt"
    grep -q '^BEGIN accelcal-vectors' "$D/vectors_h8.txt" || fail "-$opt: no BEGIN line in the H8 output"
    grep -q '^END accelcal-vectors' "$D/vectors_h8.txt" \
        || fail "-$opt: the H8 run ended with status 0 but before the END line (main returned early?)"
    check_count "$D/vectors_h8.txt"
    if ! cmp -s "$OUT/vectors_host.txt" "$D/vectors_h8.txt"; then
        python3 - "$OUT/vectors_host.txt" "$D/vectors_h8.txt" "$opt" >&2 << 'PY'
import sys
host = open(sys.argv[1], "rb").read().split(b"\n")
h8 = open(sys.argv[2], "rb").read().split(b"\n")
ndiff = sum(a != b for a, b in zip(host, h8)) + abs(len(host) - len(h8))
for i, (a, b) in enumerate(zip(host + [b""] * len(h8), h8 + [b""] * len(host))):
    if a != b:
        tag = (a or b).split(b" ")[0].decode(errors="replace")
        print(f"first differing vector (-{sys.argv[3]}): {tag}, line {i + 1}")
        print(f"  host: {a.decode(errors='replace')}")
        print(f"  h8:   {b.decode(errors='replace')}")
        break
print(f"{ndiff} differing line(s)")
PY
        fail "-$opt: H8 output differs from the host's (full outputs: $OUT/vectors_host.txt $D/vectors_h8.txt)"
    fi
    insts=$(grep -a -m 1 '#instructions executed' "$D/h8_stdout.txt" | awk '{print $NF}')
    lines=$(($(wc -l < "$D/vectors_h8.txt") - 2))
    echo "== identical (-$opt): $lines vector lines ($(tail -n 1 "$D/vectors_h8.txt")), ${insts:-?} instructions, ${secs} s"
    grep -a '^H8 stack' "$D/h8_stdout.txt" || true
done
echo "run_h8_tests: OK"
