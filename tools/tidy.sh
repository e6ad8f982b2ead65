#!/usr/bin/env bash
# accelcal -- clang-tidy over the C core (csrc/*.c and the headers they include),
# with the checks of .clang-tidy at the repository root.  Zero findings is the bar.
#
# Each source is analysed in the configurations the core is built in:
#   default            (helpers inlined, <stdint.h>)
#   -DAC_INLINE_HELPERS=0  (helpers out of line in ac_ops.c: old cross compilers)
#   -DAC_NO_STDINT=1   (types from <limits.h>: the H8/300H path)
#
# Usage:  tools/tidy.sh [file.c ...]          (default: csrc/*.c)
# Env:    CLANG_TIDY (default: clang-tidy, else clang-tidy-14..19), JOBS (default 2)
# Exit:   0 with no finding, 1 with any (each printed once, with its check name), 2 if
#         clang-tidy is missing (apt-get install -y clang-tidy).
set -uo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT" || exit 2
JOBS=${JOBS:-2}

TIDY=${CLANG_TIDY:-}
if [ -z "$TIDY" ]; then
    for t in clang-tidy clang-tidy-19 clang-tidy-18 clang-tidy-17 clang-tidy-16 clang-tidy-15 clang-tidy-14; do
        if command -v "$t" > /dev/null; then
            TIDY=$t
            break
        fi
    done
fi
if [ -z "$TIDY" ]; then
    echo "tidy.sh: clang-tidy not found (apt-get install -y clang-tidy)" >&2
    exit 2
fi

if [ $# -gt 0 ]; then
    FILES=("$@")
else
    FILES=(csrc/*.c)
fi
CONFIGS=("" "-DAC_INLINE_HELPERS=0" "-DAC_NO_STDINT=1")

OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
echo "== $("$TIDY" --version | grep -m1 -i version | sed 's/^ *//') over ${#FILES[@]} files x ${#CONFIGS[@]} configurations"
n=0
for cfg in "${CONFIGS[@]}"; do
    for f in "${FILES[@]}"; do
        n=$((n + 1))
        # -p /dev/null: no compilation database; the flags after -- are the build's
        printf '%s\0%s\0%s\0' "$f" "$cfg" "$OUT/$n.log"
    done
done | xargs -0 -n 3 -P "$JOBS" sh -c '
    "$0" --quiet "$1" -- -std=c99 -Iinclude -Icsrc $2 > "$3" 2>&1
    echo $? >> "$3.rc"' "$TIDY"

# one line per distinct finding (file:line:col: severity: message [check])
cat "$OUT"/*.log | grep -E '^[^ ]+:[0-9]+:[0-9]+: (warning|error): ' | sed "s#^$ROOT/##" | sort -u > "$OUT/findings"
crashed=$(cat "$OUT"/*.rc | grep -cvE '^(0|1)$')
count=$(wc -l < "$OUT/findings")
if [ "$count" -gt 0 ]; then
    cat "$OUT/findings"
    echo
    echo "tidy.sh: $count finding(s):"
    sed -E 's/.*\[([^],]+).*\]$/\1/' "$OUT/findings" | sort | uniq -c | sort -rn
    exit 1
fi
if [ "$crashed" -gt 0 ]; then
    echo "tidy.sh: clang-tidy failed on some inputs:" >&2
    grep -l . "$OUT"/*.log | head -n 3 | xargs cat >&2
    exit 1
fi
echo "tidy.sh: no findings"
exit 0
