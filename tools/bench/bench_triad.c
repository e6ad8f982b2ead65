/* Firmware-cost benchmark of the 3-axis path: one sample through ac_triad_apply
 * (pre-trim + 3x3 apply) and the triad's on-device table build ac_triad_build,
 * from triad.h (made by tools/bench_core.py, prefix AC_TRI).  A program of its
 * own, beside bench_main.c: both builds' work areas and tables together do not
 * fit the ATmega328P's 2 KB of RAM.  Host: run under callgrind (instruction
 * counts).  AVR: Timer1 at prescaler 1 counts cycles exactly under simavr;
 * results go out on UART0. */
#define AC_TRI_IMPLEMENTATION
#include "triad.h"

#include "bench_io.h"

static ac_build_work work;
static ac_triad built;

int main(void)
{
    uint16_t raw[3];
    int32_t f[3];
    uint32_t c_apply, c_build;
#ifdef BENCH_REPEAT
    uint16_t k;
#endif
    uint32_t check = 0;
    /* about 1.6 m/s^2 on x, -1 m/s^2 on y and g on z (16-bit, +-2 g) */
    raw[0] = (uint16_t)(AC_TRI_TRIAD.trim[0] + 2700u);
    raw[1] = (uint16_t)(AC_TRI_TRIAD.trim[1] - 1650u);
    raw[2] = (uint16_t)(AC_TRI_TRIAD.trim[2] + 16400u);
#ifdef BENCH_REPEAT
    for (k = 0; k < BENCH_REPEAT; k++) {
        raw[0] = (uint16_t)(raw[0] + 1u);
        (void)ac_triad_apply(&AC_TRI_TRIAD, raw, f);
        check += (uint32_t)f[0];
    }
#endif
    timer_start();
    (void)ac_triad_apply(&AC_TRI_TRIAD, raw, f);
    c_apply = timer_stop();
    timer_start();
    (void)ac_triad_build(AC_TRI_CHANNELS, AC_TRI_TRIAD.trim, &work, &built);
    c_build = timer_stop();
    out_str("BENCH triad_apply="); out_u32(c_apply);
    out_str(" triad_build="); out_u32(c_build);
    out_str(" check="); out_u32(check + (uint32_t)f[0] + (uint32_t)built.k[0]);
    out_str("\n");
    bench_end();
    return 0;
}
