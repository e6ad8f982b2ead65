#!/usr/bin/env bash
# accelcal -- H8/300H build of the C core (the seed's MCU, H8/3664 in normal mode).
#
#  1. compiles every csrc/*.c with h8300-hms-gcc -mh -mn -O2 -fomit-frame-pointer -std=c99 -Wall -Wextra -Werror;
#     then steps 1-4 again at -Os (outputs in build/h8/Os/): the core must need
#     nothing from outside at either level (h8300-hms-gcc 3.4.6 at -Os turns some
#     zeroings into memset calls);
#  2. checks that the objects together need NO external symbol at all: the
#     H8/300H has no usable libgcc, so any ___mulsi3 / ___divsi3 / ___udivsi3 /
#     ___modsi3 / ___muldi3 / soft-float (___adddf3 ...) / memcpy / memset
#     reference is a failure (printed with the module that needs it);
#  3. links tools/h8/fw_main.c against the core as an archive with
#     -nostdlib -nostartfiles -Wl,-e,_main: "fw_full" (per-sample path plus
#     the on-device table build) and "fw_sample" (per-sample path only);
#  4. prints h8300-hms-size per module and per firmware, and writes per-function
#     sizes (from symbol addresses; COFF records no sizes) to
#     build/h8/function_sizes.txt and a summary table to build/h8/sizes.md.
#
# Usage:  tools/build_h8.sh            (from anywhere; outputs in build/h8/, -Os in build/h8/Os/)
# Env:    H8_OPT (O2 or Os; set, it builds that level only, into H8_OUT)
# Exit:   0 on success, 1 on any compiler warning/error, external symbol or link error.
set -euo pipefail
export LC_ALL=C

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
OUT=${H8_OUT:-$ROOT/build/h8}
OPT=${H8_OPT:-O2}
CROSS=${H8_CROSS:-h8300-hms-}
CC="${CROSS}gcc"
CFLAGS=(-mh -mn -"$OPT" -fomit-frame-pointer -std=c99 -Wall -Wextra -Werror -I"$ROOT/include")
LDFLAGS=(-mh -mn -nostdlib -nostartfiles -Wl,-e,_main)

fail() {
    echo "build_h8: FAIL: $*" >&2
    exit 1
}

for tool in "$CC" "${CROSS}nm" "${CROSS}size" "${CROSS}ar"; do
    command -v "$tool" > /dev/null || fail "'$tool' not found (apt-get install gcc-h8300-hms binutils-h8300-hms)"
done
shopt -s nullglob
SRC=("$ROOT"/csrc/*.c)
shopt -u nullglob
[ ${#SRC[@]} -gt 0 ] || fail "no sources in csrc/"

rm -rf "$OUT"
mkdir -p "$OUT/obj"
echo "== compile ($CC $($CC -dumpversion), ${CFLAGS[*]:0:6})"
errors=0
OBJ=()
for src in "${SRC[@]}"; do
    obj="$OUT/obj/$(basename "$src" .c).o"
    if ! "$CC" "${CFLAGS[@]}" -c -o "$obj" "$src"; then
        echo "  $(basename "$src"): FAILED" >&2
        errors=$((errors + 1))
        continue
    fi
    OBJ+=("$obj")
done
[ $errors -eq 0 ] || fail "$errors module(s) did not compile"

# ---- 2. external symbols ------------------------------------------------------------
# (coff-h8300 ld cannot do 'ld -r', so combine the per-object lists: needed minus defined)
echo "== external symbols needed by the core (must be none)"
"${CROSS}nm" -g --defined-only "${OBJ[@]}" 2> /dev/null | awk 'NF == 3 { print $3 }' | sort -u > "$OUT/defined.txt"
: > "$OUT/undefined_by_module.txt"
for obj in "${OBJ[@]}"; do
    "${CROSS}nm" -u "$obj" | awk -v m="$(basename "$obj")" 'NF >= 2 { print $NF, m }' \
        >> "$OUT/undefined_by_module.txt"
done
sort -u "$OUT/undefined_by_module.txt" | sort -k1,1 > "$OUT/undefined_sorted.txt"
join -v 1 -1 1 "$OUT/undefined_sorted.txt" "$OUT/defined.txt" > "$OUT/external.txt" || true
if [ -s "$OUT/external.txt" ]; then
    echo "  the core needs symbols that no module defines (libgcc/libc/soft-float):" >&2
    awk '{ printf "    %-24s needed by %s\n", $1, $2 }' "$OUT/external.txt" >&2
    if grep -qE '^___(mul|div|udiv|mod|umod)[sd]i3|^___.*(df|sf)[0-9]' "$OUT/external.txt"; then
        echo "  (___mulsi3/___divsi3/... are libgcc helpers: no 32x32 '*' or 32-bit '/' '%'" >&2
        echo "   on the H8/300H -- use the 16x16 partial products of ac_fixed)" >&2
    fi
    fail "$(awk '{print $1}' "$OUT/external.txt" | sort -u | wc -l) external symbol(s)"
fi
echo "  none"

# ---- 3. firmware links --------------------------------------------------------------------
echo "== link firmware (${LDFLAGS[*]})"
"${CROSS}ar" rcs "$OUT/libaccelcal.a" "${OBJ[@]}"
for fw in full sample; do
    defs=()
    [ $fw = sample ] && defs=(-DFW_SAMPLE_ONLY)
    "$CC" "${CFLAGS[@]}" "${defs[@]}" -c -o "$OUT/fw_main_$fw.o" "$ROOT/tools/h8/fw_main.c" \
        || fail "fw_main.c ($fw) did not compile"
    "$CC" "${LDFLAGS[@]}" -Wl,-Map="$OUT/fw_$fw.map" -o "$OUT/fw_$fw.out" \
        "$OUT/fw_main_$fw.o" "$OUT/libaccelcal.a" || fail "firmware link ($fw)"
    echo "  fw_$fw.out: linked"
done

# ---- 4. sizes -------------------------------------------------------------------------------
echo "== sizes (bytes)"
"${CROSS}size" "${OBJ[@]}" | sed "s#$OUT/obj/##" | tee "$OUT/module_sizes.txt"
"${CROSS}size" "$OUT/fw_full.out" "$OUT/fw_sample.out" "$OUT/fw_main_full.o" "$OUT/fw_main_sample.o" \
    | sed "s#$OUT/##" | tee "$OUT/firmware_sizes.txt"

# per-function sizes: distance to the next symbol in the same section (local
# labels .L* and section symbols skipped), last one to the end of the section
{
    echo "# H8/300H (h8300-hms-gcc ${CFLAGS[*]:0:4}): per-function sizes in bytes, largest first"
    echo "# size  nm-type (T global, t static function; D/d data)  symbol  module"
    for obj in "${OBJ[@]}"; do
        m=$(basename "$obj")
        text_end=$("${CROSS}size" -A "$obj" | awk '$1 == ".text" { print $2 }')
        data_end=$("${CROSS}size" -A "$obj" | awk '$1 == ".data" { print $2 + $3 }')
        "${CROSS}nm" -n --defined-only "$obj" | awk -v m="$m" -v te="$text_end" -v de="$data_end" '
            function hex(s,    i, v) {
                v = 0
                for (i = 1; i <= length(s); i++) v = v * 16 + index("0123456789abcdef", tolower(substr(s, i, 1))) - 1
                return v
            }
            function flush(end) { if (name != "") printf "%6d  %s  %s  %s\n", end - addr, letter, name, m }
            $3 ~ /^\.L/ || $3 ~ /^\./ { next }
            {
                a = hex($1); t = toupper($2)
                if (name != "" && t == type) { flush(a) }
                else if (name != "") { flush(type == "T" ? te : de) }
                name = $3; addr = a; type = t; letter = $2
            }
            END { flush(type == "T" ? te : de) }'
    done | sort -k1,1nr
} > "$OUT/function_sizes.txt"
echo "  per-function sizes: build/h8/function_sizes.txt"

# summary table for the README
{
    echo "| module | text | data | bss |"
    echo "| --- | ---: | ---: | ---: |"
    awk 'NR > 1 { printf "| %s | %d | %d | %d |\n", $6, $1, $2, $3; t += $1; d += $2; b += $3 }
         END { printf "| **core total** | **%d** | **%d** | **%d** |\n", t, d, b }' "$OUT/module_sizes.txt"
    awk 'NR > 1 && $6 ~ /^fw_(full|sample)\.out$/ {
             label = ($6 == "fw_full.out") ? "firmware: per-sample path + on-device build (fw_full)" \
                                           : "firmware: per-sample path only (fw_sample)"
             printf "| %s | %d | %d | %d |\n", label, $1, $2, $3 }' "$OUT/firmware_sizes.txt"
} > "$OUT/sizes.md"
echo "  summary table: build/h8/sizes.md"
cat "$OUT/sizes.md"
echo "build_h8: OK (-$OPT)"
if [ -z "${H8_OPT:-}" ]; then
    echo "== the same at -Os (build/h8/Os)"
    H8_OPT=Os H8_OUT="$OUT/Os" bash "${BASH_SOURCE[0]}"
fi
