#!/usr/bin/env bash
# accelcal -- build the libFuzzer harness (fuzz/fuzz_core.c) over the whole C
# core and run it for a bounded time.
#
# Usage:  tools/fuzz.sh [seconds] [extra libFuzzer flags...]    (default 60 s)
# Env:    CLANG (default: clang, else clang-14..19), FUZZ_JOBS (parallel fuzzing
#         processes, default 1), FUZZ_MAX_LEN (default 1024 bytes)
# Files:  seed corpus fuzz/corpus/ (committed; regenerate with
#         python3 fuzz/make_corpus.py) -- read only;
#         build/fuzz/corpus/ working corpus (grows across runs, not committed);
#         build/fuzz/artifacts/ crash/leak/timeout reproducers;
#         build/fuzz/fuzz_core the fuzzer, build/fuzz/fuzz.log its output.
# Reproduce a finding:  build/fuzz/fuzz_core build/fuzz/artifacts/crash-...
#         (or without clang: cc -fsanitize=address,undefined -std=c99 -Iinclude
#          -Icsrc fuzz/fuzz_core.c fuzz/replay_main.c csrc/*.c -lm && ./a.out FILE)
# Exit:   0 if the run ended with no crash, non-zero otherwise (1 build or
#         setup failure, libFuzzer's code on a finding).
#
# Needs clang with its runtime: apt-get install -y clang libclang-rt-14-dev
set -uo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
OUT="$ROOT/build/fuzz"
SECS=${1:-60}
[ $# -gt 0 ] && shift
JOBS=${FUZZ_JOBS:-1}
MAXLEN=${FUZZ_MAX_LEN:-1024}

CC=${CLANG:-}
if [ -z "$CC" ]; then
    for c in clang clang-19 clang-18 clang-17 clang-16 clang-15 clang-14; do
        if command -v "$c" > /dev/null; then
            CC=$c
            break
        fi
    done
fi
if [ -z "$CC" ]; then
    echo "fuzz.sh: clang not found (apt-get install -y clang libclang-rt-14-dev)" >&2
    exit 1
fi

mkdir -p "$OUT/corpus" "$OUT/artifacts"
echo "== building $OUT/fuzz_core with $CC"
# shellcheck disable=SC2046
if ! "$CC" -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all \
    -fno-omit-frame-pointer -std=c99 -Wall -Wextra -Werror \
    -I"$ROOT/include" -I"$ROOT/csrc" \
    "$ROOT/fuzz/fuzz_core.c" $(ls "$ROOT"/csrc/*.c) -lm -o "$OUT/fuzz_core"; then
    echo "fuzz.sh: build failed" >&2
    exit 1
fi

echo "== fuzzing for ${SECS} s (jobs: $JOBS); log: $OUT/fuzz.log"
args=(-max_total_time="$SECS" -max_len="$MAXLEN" -timeout=20 -print_final_stats=1
      -artifact_prefix="$OUT/artifacts/" "$@" "$OUT/corpus" "$ROOT/fuzz/corpus")
if [ "$JOBS" -gt 1 ]; then
    args=(-jobs="$JOBS" -workers="$JOBS" "${args[@]}")
fi
rm -f "$OUT"/fuzz-*.log
# (run in $OUT: with -jobs libFuzzer writes fuzz-N.log into the working directory)
(cd "$OUT" && UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 ASAN_OPTIONS=detect_leaks=1 \
    ./fuzz_core "${args[@]}") > "$OUT/fuzz.log" 2>&1
rc=$?
if [ "$JOBS" -gt 1 ]; then
    cat "$OUT"/fuzz-*.log >> "$OUT/fuzz.log" 2> /dev/null
fi
# a run's verdict from its exit code and its log: exits with the finding, if any
check_run() { # rc log name
    local rc=$1 log=$2 name=$3
    grep -E '^stat::number_of_executed_units|^Done [0-9]+ runs|^#[0-9]+[[:space:]]+DONE' "$log" | tail -n 3
    if [ "$rc" -ne 0 ] || grep -qE 'ERROR: (libFuzzer|AddressSanitizer)|runtime error:|property failed' "$log"; then
        echo "fuzz.sh: FINDING in $name (exit $rc):" >&2
        grep -E 'property failed|runtime error:|ERROR:|SUMMARY:|Test unit written' -A1 "$log" | head -n 30 >&2
        [ "$rc" -ne 0 ] || rc=1
        exit "$rc"
    fi
}
check_run $rc "$OUT/fuzz.log" fuzz_core

echo "fuzz.sh: no crash in ${SECS} s"
exit 0
