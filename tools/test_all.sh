#!/usr/bin/env bash
# Installs everything the test suite needs and runs every test: the C core on the
# host (warnings as errors, ctest, ASan/UBSan, cppcheck, valgrind), the H8/300H
# build and link without libgcc at -O2 and -Os, the test vectors on GNU's H8/300H
# simulator (built from Debian's gdb-source, cached) at -Os and -O2 bit for bit
# against the host, the AVR (16-bit int) run under simavr bit for bit against the
# host, clang-tidy, a bounded libFuzzer run, and the Python suite (the
# core's properties at 10,000 examples each, the estimators' at 2,000), then the
# documentation site (tools/build_docs.sh: warnings are errors, the examples run).
set -euo pipefail
cd "$(dirname "$0")/.."

need_apt=0
for tool in h8300-hms-gcc patch xz avr-gcc simavr cppcheck cmake valgrind clang clang-tidy; do
    command -v "$tool" >/dev/null 2>&1 || need_apt=1
done
[ -f /usr/lib/avr/include/avr/io.h ] || need_apt=1
dpkg -L gdb-source 2>/dev/null | grep -q '/gdb\.tar\.xz$' || need_apt=1  # the H8 simulator's source
[ -f /usr/share/i18n/locales/de_DE ] || need_apt=1  # a comma-decimal locale for the CSV locale test
ls /usr/lib/llvm-*/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a >/dev/null 2>&1 || need_apt=1
if [ "$need_apt" = 1 ]; then
    echo "== installing Debian packages"
    SUDO=""; [ "$(id -u)" = 0 ] || SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq \
        gcc-h8300-hms binutils-h8300-hms gdb-source patch xz-utils gcc-avr avr-libc simavr cppcheck cmake valgrind \
        clang clang-tidy libclang-rt-14-dev locales >/dev/null
fi

echo "== installing the Python package (with the test and docs extras)"
python3 -m pip install -q -e ".[test,docs]"

echo "== C core: host builds, ctest, sanitizers, cppcheck"
bash tools/check_c.sh
echo "== C core: H8/300H (h8300-hms-gcc -mh -mn) build and link without libgcc"
bash tools/build_h8.sh
echo "== C core: H8/300H simulator (GNU sim/h8300 from gdb-source + decode cache; built once, then cached)"
bash tools/build_h8sim.sh
echo "== C core: the test vectors on the simulated H8/300H at -Os and -O2, bit for bit against the host"
bash tools/run_h8_tests.sh
echo "== C core: AVR (16-bit int) under simavr, bit for bit against the host"
bash tools/run_avr_tests.sh
echo "== C core: the same on AVR with the plain C instead of the AVR assembly kernels (-DAC_NO_ASM)"
AVR_EXTRA_CFLAGS=-DAC_NO_ASM bash tools/run_avr_tests.sh

echo "== C core: clang-tidy (zero findings)"
bash tools/tidy.sh
echo "== C core: libFuzzer over the whole API, bounded run"
bash tools/fuzz.sh "${ACCELCAL_FUZZ_SECONDS:-45}"

echo "== Python suite"
ACCELCAL_HYPOTHESIS="${ACCELCAL_HYPOTHESIS:-ci}" python3 -m pytest -q -p no:cacheprovider --durations=25 -n "${ACCELCAL_TEST_JOBS:-2}" --dist worksteal

echo "== documentation site: sphinx -W (warnings are errors), the worked examples run, into build/docs/html"
ACCELCAL_DOCS_INSTALL=0 bash tools/build_docs.sh
