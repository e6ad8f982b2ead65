#!/usr/bin/env bash
# accelcal -- host checks of the C core (what CI runs for C besides the
# cross builds tools/build_h8.sh and tools/run_avr_tests.sh).
#
#  a. CMake build with the strict warning set and -Werror, then ctest;
#  b. the same with ACCELCAL_SANITIZE=ON (ASan + UBSan, no recovery), then ctest;
#  c. cppcheck over csrc/ and include/ (warning, style, performance, portability):
#     zero findings;
#  d. textual checks on csrc/ and include/ (comments stripped): no float, no
#     double, no malloc/calloc/realloc/free, no <math.h>;
#  e. packaging: install, then a consumer using find_package(accelcal), and a
#     consumer using add_subdirectory(); both build and run;
#  f. valgrind (memcheck) over the vector program and the small unit tests, if
#     valgrind is installed.
#
# Usage:  tools/check_c.sh [step ...]     steps: build sanitize cppcheck grep package valgrind
#         (default: all, in that order; build dirs under build/)
# Env:    JOBS (parallel build jobs, default 2), CC (host compiler)
# Exit:   0 if every step passed, 1 otherwise (all requested steps still run).
set -uo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
B="$ROOT/build"
JOBS=${JOBS:-2}
STEPS=("$@")
[ ${#STEPS[@]} -gt 0 ] || STEPS=(build sanitize cppcheck grep package valgrind)
declare -a RESULTS=()
failed=0

pass() { RESULTS+=("PASS  $1"); echo "-- $1: PASS"; }
flop() { RESULTS+=("FAIL  $1"); echo "-- $1: FAIL" >&2; failed=1; }
hdr() { echo; echo "======== $* ========"; }

cmake_build_test() { # dir, extra cmake args...
    local dir=$1
    shift
    cmake -S "$ROOT" -B "$dir" "$@" > "$dir.configure.log" 2>&1 \
        || { cat "$dir.configure.log"; return 1; }
    cmake --build "$dir" -j "$JOBS" || return 1
    (cd "$dir" && ctest --output-on-failure -j "$JOBS" --timeout 900) || return 1
    return 0
}

step_build() {
    hdr "a. build (-Werror) + ctest: build/host"
    mkdir -p "$B"
    if cmake_build_test "$B/host" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DACCELCAL_TESTS=ON \
        -DACCELCAL_WERROR=ON; then
        summaries "$B/host"
        pass "build + ctest"
    else
        summaries "$B/host"
        flop "build + ctest"
    fi
}

step_sanitize() {
    hdr "b. ASan + UBSan build + ctest: build/sanitize"
    mkdir -p "$B"
    if ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:strict_string_checks=1 \
        UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
        cmake_build_test "$B/sanitize" -DCMAKE_BUILD_TYPE=Debug -DACCELCAL_TESTS=ON \
        -DACCELCAL_WERROR=ON -DACCELCAL_SANITIZE=ON; then
        summaries "$B/sanitize"
        pass "sanitize build + ctest"
    else
        summaries "$B/sanitize"
        flop "sanitize build + ctest"
    fi
}

# print each test program's "N passed, N failed" line from the ctest log
summaries() {
    local log="$1/Testing/Temporary/LastTest.log"
    [ -f "$log" ] || return 0
    awk '/^[0-9]+\/[0-9]+ Test: / { name = $3 }
         /^[0-9]+ passed, [0-9]+ failed$/ { printf "   %-10s %s\n", name, $0 }
         /^END accelcal-vectors/ { printf "   %-10s %s\n", name, $0 }' "$log"
}

step_cppcheck() {
    hdr "c. cppcheck"
    if ! command -v cppcheck > /dev/null; then
        flop "cppcheck (not installed)"
        return
    fi
    # AC_CONFIG_USER names a header of the firmware's own: not part of the core
    if cppcheck --enable=warning,style,performance,portability --error-exitcode=1 \
        --inline-suppr --std=c99 --quiet -UAC_CONFIG_USER -I "$ROOT/include" \
        "$ROOT/csrc" "$ROOT/include"; then
        pass "cppcheck ($(cppcheck --version))"
    else
        flop "cppcheck"
    fi
}

step_grep() {
    hdr "d. textual checks (no float, double, malloc & co, <math.h>) on csrc/ include/"
    local bad=0 f
    shopt -s nullglob
    for f in "$ROOT"/csrc/*.[ch] "$ROOT"/include/accelcal/*.h; do
        # strip comments, keeping line numbers
        perl -0777 -pe 's{/\*.*?\*/}{ (my $c = $&) =~ s/[^\n]//g; $c }gse; s{//[^\n]*}{}g' "$f" \
            | grep -nE '\b(float|double)\b|\b(malloc|calloc|realloc|free)[[:space:]]*\(|#[[:space:]]*include[[:space:]]*[<"]math\.h[>"]' \
            | sed "s#^#  ${f#"$ROOT"/}:#" && bad=1
    done
    shopt -u nullglob
    if [ $bad -eq 0 ]; then pass "textual checks"; else flop "textual checks"; fi
}

step_package() {
    hdr "e. install + find_package / add_subdirectory consumers"
    local inst="$B/install" ok=1
    rm -rf "$inst" "$B/consumer_pkg" "$B/consumer_sub"
    mkdir -p "$B/consumer_pkg/src" "$B/consumer_sub/src"
    cmake -S "$ROOT" -B "$B/pkg" -DCMAKE_BUILD_TYPE=Release -DACCELCAL_TESTS=OFF \
        > "$B/pkg.configure.log" 2>&1 || { cat "$B/pkg.configure.log"; ok=0; }
    [ $ok -eq 1 ] && { cmake --build "$B/pkg" -j "$JOBS" > /dev/null || ok=0; }
    [ $ok -eq 1 ] && { cmake --install "$B/pkg" --prefix "$inst" > "$B/pkg.install.log" || ok=0; }
    if [ $ok -eq 1 ]; then
        for f in include/accelcal/accelcal.h include/accelcal/ac_config.h \
            lib/cmake/accelcal/accelcalConfig.cmake lib/cmake/accelcal/accelcalConfigVersion.cmake; do
            [ -f "$inst/$f" ] || { echo "  missing after install: $f" >&2; ok=0; }
        done
        ls "$inst"/lib*/libaccelcal.a > /dev/null 2>&1 || { echo "  missing: libaccelcal.a" >&2; ok=0; }
    fi
    # a tiny program: trim + a resolver identity-ish table + rate step
    cat > "$B/consumer_pkg/src/main.c" << 'EOF'
#include <accelcal/accelcal.h>
#include <stdio.h>
int main(void)
{
    static ac_resolver r;
    uint16_t raw[6] = {5100, 4900, 5000, 5000, 5000, 5000}, trim[6] = {5000, 5000, 5000, 5000, 5000, 5000};
    int32_t out[6];
    int j;
    r.n = 6;
    for (j = 0; j < 6; j++) {
        r.m[j][j] = 1;
    }
    if (ac_process(&r, trim, raw, NULL, out) != AC_OK || out[0] != 100 || out[1] != -100) {
        printf("consumer: unexpected result\n");
        return 1;
    }
    printf("consumer OK (accelcal %s)\n", ACCELCAL_VERSION);
    return 0;
}
EOF
    cp "$B/consumer_pkg/src/main.c" "$B/consumer_sub/src/main.c"
    cat > "$B/consumer_pkg/CMakeLists.txt" << 'EOF'
cmake_minimum_required(VERSION 3.16)
project(consumer_pkg C)
find_package(accelcal 0.1 REQUIRED)
add_executable(consumer src/main.c)
target_link_libraries(consumer PRIVATE accelcal::accelcal)
EOF
    cat > "$B/consumer_sub/CMakeLists.txt" << EOF
cmake_minimum_required(VERSION 3.16)
project(consumer_sub C)
add_subdirectory("$ROOT" accelcal)
add_executable(fw src/main.c)
target_link_libraries(fw PRIVATE accelcal)
EOF
    if [ $ok -eq 1 ]; then
        cmake -S "$B/consumer_pkg" -B "$B/consumer_pkg/build" -DCMAKE_PREFIX_PATH="$inst" \
            > "$B/consumer_pkg.configure.log" 2>&1 || { cat "$B/consumer_pkg.configure.log"; ok=0; }
        [ $ok -eq 1 ] && { cmake --build "$B/consumer_pkg/build" > /dev/null || ok=0; }
        [ $ok -eq 1 ] && { "$B/consumer_pkg/build/consumer" || ok=0; }
    fi
    if [ $ok -eq 1 ]; then pass "install + find_package consumer"; else flop "install + find_package consumer"; fi
    ok=1
    cmake -S "$B/consumer_sub" -B "$B/consumer_sub/build" > "$B/consumer_sub.configure.log" 2>&1 \
        || { cat "$B/consumer_sub.configure.log"; ok=0; }
    [ $ok -eq 1 ] && { cmake --build "$B/consumer_sub/build" > /dev/null || ok=0; }
    [ $ok -eq 1 ] && { "$B/consumer_sub/build/fw" || ok=0; }
    # as a subproject the tests and the install rules stay off
    if [ -e "$B/consumer_sub/build/accelcal/test_fixed" ] || [ -e "$B/consumer_sub/build/accelcal/CTestTestfile.cmake" ]; then
        echo "  add_subdirectory built the tests (ACCELCAL_TESTS should default OFF)" >&2
        ok=0
    fi
    if [ $ok -eq 1 ]; then pass "add_subdirectory consumer"; else flop "add_subdirectory consumer"; fi
}

step_valgrind() {
    hdr "f. valgrind memcheck (build/host binaries)"
    if ! command -v valgrind > /dev/null; then
        RESULTS+=("SKIP  valgrind (not installed)")
        return
    fi
    local ok=1 t
    for t in vectors test_trim test_resolve test_rate test_invert test_terms; do
        if [ ! -x "$B/host/$t" ]; then
            echo "  $t: not built (run the build step first)" >&2
            ok=0
            continue
        fi
        # exit 99 = memcheck found errors; a test's own failures (exit 1) are
        # ctest's business (step a) and do not count here
        valgrind -q --error-exitcode=99 --leak-check=full "$B/host/$t" > "$B/host/$t.valgrind.out" 2>&1
        case $? in
        0) echo "  $t: clean" ;;
        99)
            echo "  $t: memcheck errors:" >&2
            grep -E '==[0-9]+==' "$B/host/$t.valgrind.out" | head -n 30 >&2
            ok=0
            ;;
        *)
            if grep -q '==[0-9]*==' "$B/host/$t.valgrind.out"; then
                echo "  $t: memcheck output:" >&2
                grep -E '==[0-9]+==' "$B/host/$t.valgrind.out" | head -n 30 >&2
                ok=0
            else
                echo "  $t: clean (the program reports test failures: see step a)"
            fi
            ;;
        esac
    done
    if [ $ok -eq 1 ]; then pass "valgrind"; else flop "valgrind"; fi
}

for s in "${STEPS[@]}"; do
    case $s in
    build | sanitize | cppcheck | grep | package | valgrind) "step_$s" ;;
    *)
        echo "check_c: unknown step '$s' (build sanitize cppcheck grep package valgrind)" >&2
        exit 2
        ;;
    esac
done

echo
echo "======== summary ========"
printf '%s\n' "${RESULTS[@]}"
exit $failed
