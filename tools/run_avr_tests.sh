#!/usr/bin/env bash
# accelcal -- bit-for-bit cross-check of the C core on a 16-bit-int target.
#
# Builds tests/c/vectors.c + csrc/*.c for the ATmega1284P (avr-gcc, int is 16
# bits as on the H8/300H), runs it under simavr, builds the same program for
# the host, and compares the two outputs byte for byte.  Any difference is a
# portability bug (integer promotion, implementation-defined behaviour) in the
# core or in the vector program.  Also checks that the C unit tests that do
# not need host-only features (long double maths) compile for the AVR.
#
# Usage:  tools/run_avr_tests.sh            (from anywhere; outputs in build/avr/)
# Env:    SIMAVR_TIMEOUT (seconds, default 600), AVR_MCU (default atmega1284p: the vector program outgrew the 328P's 32 KB flash),
#         AVR_RAM (bytes, default 2048)
# Exit:   0 = outputs identical; 1 = mismatch or any build/run failure.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
OUT="$ROOT/build/avr"
MCU=${AVR_MCU:-atmega1284p}
RAM=${AVR_RAM:-2048}
FREQ=16000000
TIMEOUT=${SIMAVR_TIMEOUT:-600}
# gc-sections: firmware links only what it calls (the flash is 32 KB)
AVR_CFLAGS=(-mmcu="$MCU" -Os -std=c99 -Wall -Wextra -Werror -ffunction-sections -fdata-sections -Wl,--gc-sections -I"$ROOT/include")
# AVR_EXTRA_CFLAGS=-DAC_NO_ASM runs the plain C of the AVR assembly kernels (the C that the
# H8 and every other target compile) with 16-bit int
read -r -a extra <<< "${AVR_EXTRA_CFLAGS:-}"
AVR_CFLAGS+=("${extra[@]}")
HOST_CC=${CC:-cc}
HOST_CFLAGS=(-std=c99 -O2 -Wall -Wextra -Werror -I"$ROOT/include")

fail() {
    echo "run_avr_tests: FAIL: $*" >&2
    exit 1
}

for tool in avr-gcc avr-size simavr "$HOST_CC" perl diff; do
    command -v "$tool" > /dev/null || fail "'$tool' not found"
done
shopt -s nullglob
CORE_SRC=("$ROOT"/csrc/*.c)
shopt -u nullglob
[ ${#CORE_SRC[@]} -gt 0 ] || fail "no sources in csrc/"

rm -rf "$OUT"
mkdir -p "$OUT"

# ---- 1. AVR build -------------------------------------------------------------------
echo "== AVR build ($MCU, avr-gcc $(avr-gcc -dumpversion))"
avr-gcc "${AVR_CFLAGS[@]}" -Wl,-Map="$OUT/vectors_avr.map" -o "$OUT/vectors_avr.elf" \
    "${CORE_SRC[@]}" "$ROOT/tests/c/vectors.c" "$ROOT/tests/c/vectors_avr.c" \
    || fail "AVR build of the vector program"
avr-size "$OUT/vectors_avr.elf" | tee "$OUT/size.txt"
read -r _text data bss _rest < <(avr-size "$OUT/vectors_avr.elf" | tail -n 1)
static_ram=$((data + bss))
echo "static RAM (data + bss): $static_ram of $RAM bytes; $((RAM - static_ram)) left for the stack"
[ "$static_ram" -lt $((RAM - 256)) ] || fail "static RAM $static_ram leaves under 256 bytes of stack"

# Unit tests: those without long double maths must at least compile for the AVR.
echo "== AVR compile check of the C unit tests"
for t in "$ROOT"/tests/c/test_*.c; do
    name=$(basename "$t" .c)
    if grep -qE '\b(ldexpl|fabsl|lroundl|log2l|ceill|roundl|frexpl|sinl|cosl)\b' "$t"; then
        echo "  $name: host-only (long double maths), not built for the AVR"
        continue
    fi
    avr-gcc "${AVR_CFLAGS[@]}" -c -o "$OUT/$name.o" "$t" || fail "AVR compile of $name"
    echo "  $name: compiles"
done

# ---- 2. run under simavr -------------------------------------------------------------
echo "== simavr -m $MCU -f $FREQ (timeout ${TIMEOUT}s)"
# -v makes simavr report a crashed core ("avr_sadly_crashed"); it then waits for a
# debugger instead of exiting, so watch for that rather than sit out the timeout.
simavr -v -m "$MCU" -f "$FREQ" "$OUT/vectors_avr.elf" \
    > "$OUT/simavr_stdout.log" 2> "$OUT/simavr_stderr.log" &
sim=$!
waited=0
while kill -0 "$sim" 2> /dev/null; do
    if grep -q "sadly_crashed" "$OUT/simavr_stderr.log"; then
        kill "$sim" 2> /dev/null || true
        why=$(grep -a -m 1 "CORE:" "$OUT/simavr_stderr.log" | sed 's/\x1b\[[0-9;]*m//g')
        fail "the AVR program crashed: ${why:-see $OUT/simavr_stderr.log}"
    fi
    if [ "$waited" -ge "$TIMEOUT" ]; then
        kill "$sim" 2> /dev/null || true
        fail "simavr timed out after ${TIMEOUT}s (see $OUT/simavr_stderr.log)"
    fi
    sleep 1
    waited=$((waited + 1))
done
set +e
wait "$sim"
rc=$?
set -e
[ $rc -eq 0 ] || echo "warning: simavr exited with status $rc"

# simavr prints UART0 output line by line as ESC[32m<text><newline shown as '.'>ESC[0m;
# everything else it says is chatter.  Keep only the coloured chunks, turn the
# '.' that stands for each newline back into one (the vector lines contain no
# '.'), and fall back to stripping the colour codes if a simavr version prints
# them differently.
extract_uart() {
    perl -0777 -ne '
        my $found = 0;
        while (/\e\[32m(.*?)\e\[0m/sg) {
            my $c = $1;
            $c =~ s/\r?\n\z//;
            $c =~ s/\.\z/\n/;
            print $c;
            $found = 1;
        }
        if (!$found) {
            s/\e\[[0-9;]*m//g;
            for my $l (split /\n/) { $l =~ s/\.\z//; print "$l\n"; }
        }'

}
cat "$OUT/simavr_stderr.log" "$OUT/simavr_stdout.log" | extract_uart > "$OUT/avr_uart.txt"

frame() { # the compared part: BEGIN line .. END line
    sed -n '/^BEGIN accelcal-vectors/,/^END accelcal-vectors/p' "$1"
}
frame "$OUT/avr_uart.txt" > "$OUT/vectors_avr.txt"
grep -q '^BEGIN accelcal-vectors' "$OUT/vectors_avr.txt" \
    || fail "no BEGIN line in the AVR output (crash before output?); see $OUT/simavr_stderr.log"
grep -q '^END accelcal-vectors' "$OUT/vectors_avr.txt" || {
    echo "last AVR lines:" >&2
    tail -n 5 "$OUT/avr_uart.txt" >&2
    fail "the AVR run stopped before the END line (crash, stack overflow or timeout)"
}

# ---- 3. host build and run -------------------------------------------------------------
echo "== host build ($HOST_CC) and run"
"$HOST_CC" "${HOST_CFLAGS[@]}" -o "$OUT/vectors_host" \
    "${CORE_SRC[@]}" "$ROOT/tests/c/vectors.c" "$ROOT/tests/c/vectors_host.c" \
    || fail "host build of the vector program"
"$OUT/vectors_host" > "$OUT/host_stdout.txt" || fail "host vector program exited with an error"
frame "$OUT/host_stdout.txt" > "$OUT/vectors_host.txt"
grep -q '^END accelcal-vectors' "$OUT/vectors_host.txt" || fail "host output has no END line"

# the END line carries the line count: check each output against its own count
for f in "$OUT/vectors_host.txt" "$OUT/vectors_avr.txt"; do
    declared=$((16#$(tail -n 1 "$f" | awk '{print $3}')))
    actual=$(($(wc -l < "$f") - 2))
    [ "$declared" -eq "$actual" ] || fail "$(basename "$f"): END says $declared lines, found $actual"
done

# ---- 4. compare -------------------------------------------------------------------------
lines=$(($(wc -l < "$OUT/vectors_host.txt") - 2))
if cmp -s "$OUT/vectors_host.txt" "$OUT/vectors_avr.txt"; then
    echo "== identical: $lines vector lines, $(wc -c < "$OUT/vectors_host.txt") bytes" \
        "($(tail -n 1 "$OUT/vectors_host.txt"))"
else
    ndiff=$(diff "$OUT/vectors_host.txt" "$OUT/vectors_avr.txt" | grep -c '^[<>]' || true)
    echo "== MISMATCH between host and AVR ($ndiff differing lines); first differences" \
        "(--- host, +++ avr):" >&2
    diff -u --label host --label avr "$OUT/vectors_host.txt" "$OUT/vectors_avr.txt" \
        | head -n 60 >&2 || true
    echo "full outputs: $OUT/vectors_host.txt $OUT/vectors_avr.txt" >&2
    exit 1
fi

# platform-specific lines after END (cycle counts, stack use): informational
sed -n '/^END accelcal-vectors/,$p' "$OUT/avr_uart.txt" | tail -n +2 | tee "$OUT/avr_cycles.txt"
echo "run_avr_tests: OK"
