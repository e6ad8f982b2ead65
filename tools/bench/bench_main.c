/* Firmware-cost benchmark: one 6-channel sample through pre-trim, apply and
 * centripetal correction (ac_process), plus ac_resolver_build and ac_rate_step.
 * Host: run under callgrind (instruction counts).  AVR: Timer1 at prescaler 1
 * counts cycles exactly under simavr; results go out on UART0. */
#define AC_CAL_IMPLEMENTATION
#include "cal.h"

#include "bench_io.h"

static ac_build_work work;
static ac_resolver built;

int main(void)
{
    uint16_t raw[AC_CAL_N_CHANNELS];
    int16_t w[3] = {300, -1200, 2500};
    int32_t out[6];
    int32_t alpha[3] = {1000, -2000, 3000};
    int16_t omega[3];
    ac_rate rate;
    uint32_t c_process, c_process_now, c_build, c_rate;
    uint16_t i;
#ifdef BENCH_REPEAT
    uint16_t k;
#endif
    uint32_t check = 0;
    for (i = 0; i < AC_CAL_N_CHANNELS; i++) raw[i] = (uint16_t)(AC_CAL_TRIM[i] + 37u * i);
    (void)ac_rate_init(&rate, 34953u, 21u, 109u);
#ifdef BENCH_REPEAT
    for (k = 0; k < BENCH_REPEAT; k++) {
        raw[0] = (uint16_t)(raw[0] + 1u);
        (void)ac_process(&AC_CAL_RESOLVER, AC_CAL_TRIM, raw, w, out);
        check += (uint32_t)out[0];
    }

#endif
    timer_start();
    (void)ac_process(&AC_CAL_RESOLVER, AC_CAL_TRIM, raw, w, out);
    c_process = timer_stop();
    timer_start();
    (void)ac_process(&AC_CAL_RESOLVER, AC_CAL_TRIM, raw, 0, out);
    c_process_now = timer_stop();
    timer_start();
    (void)ac_rate_step(&rate, alpha, omega);
    c_rate = timer_stop();
    timer_start();
    (void)ac_resolver_build(AC_CAL_CHANNELS, AC_CAL_N_CHANNELS, &work, &built, 0);
    c_build = timer_stop();
    out_str("BENCH process_omega="); out_u32(c_process);
    out_str(" process_no_omega="); out_u32(c_process_now);
    out_str(" rate_step="); out_u32(c_rate);
    out_str(" resolver_build="); out_u32(c_build);
    out_str(" check="); out_u32(check + (uint32_t)out[0]);
    out_str("\n");
    bench_end();
    return 0;
}
