/*
 * accelcal -- a minimal H8/300H "firmware" for tools/build_h8.sh: links the
 * core with no libc and no libgcc and keeps every entry point firmware uses
 * alive, so the link proves nothing is missing and the size is realistic.
 *
 * Not meant to run (no start-up code: the link uses -nostartfiles and enters
 * at _main).  With -DFW_SAMPLE_ONLY it keeps only the per-sample path (a
 * table made on the host: ac_process + ac_rate_step, and the path with the correctable
 * terms: ac_trim_rails, ac_temp_*, ac_skew_step, ac_nonlin_invert, ac_resolve), the smallest useful
 * firmware; otherwise it also rebuilds the table on the device
 * (ac_resolver_build), as after a field recalibration.
 */
#include <accelcal/accelcal.h>

/* Inputs the compiler cannot see through (a timer capture, a flag set by an
 * interrupt), outputs it cannot drop. */
volatile uint16_t fw_capture[6];
volatile uint8_t fw_recal_request;
volatile int32_t fw_out[6];
volatile int16_t fw_omega[3];
volatile int16_t fw_status;

volatile int16_t fw_temp; /* the sensor's temperature, degC Q.8 */

static ac_resolver fw_table;
/* the correctable terms (a generated header's tables; the values of tools/h8sim/bench_h8.c) */
static const ac_temp_table fw_temp_table = {6u, 6400, {640, 640, 640, 640, 640, 640},
                                            {5033, 5033, 5033, 5033, 5033, 5033}, {0, 0, 0, 0, 0, 0}, 0u};
static const ac_skew_table fw_skew = {6u, 3u, {1, 0, 1, 1, 1, 0}, {7864u, 26870u, 3932u, 0u, 11796u, 22938u}};
static const ac_nonlin_table fw_nl = {6u, 15, {4295, 4295, 4295, 4295, 4295, 4295},
                                      {22518, 22518, 22518, 22518, 22518, 22518}, 0u};
static ac_temp_lag fw_lag_off, fw_lag_gain;
static int16_t fw_line_buf[3u * 6u];
static ac_skew_line fw_line;
static ac_rate fw_rate;
static uint16_t fw_trim[6] = {5000u, 5000u, 5000u, 5000u, 5000u, 5000u};
#ifndef FW_SAMPLE_ONLY
static ac_channel_cal fw_cal[6];
static ac_build_work fw_work;
#endif

int main(void)
{
    uint16_t raw[6];
    int16_t x[6];
    int32_t out[6];
    int16_t omega[3];
    uint8_t i;
    ac_status st;

    st = ac_rate_init(&fw_rate, 34953u, 21u, 655u); /* 60 Hz, tau ~ 1.7 s */
    st = ac_temp_lag_init(&fw_lag_off, 55901u, 26u);
    st = ac_temp_lag_init(&fw_lag_gain, 55831u, 24u);
    st = ac_skew_init(&fw_line, &fw_skew, fw_line_buf, 18u);
    for (;;) {
#ifndef FW_SAMPLE_ONLY
        if (fw_recal_request) {
            fw_recal_request = 0u;
            st = ac_resolver_build(fw_cal, 6u, &fw_work, &fw_table, 0);
        }
#endif
        for (i = 0u; i < 6u; i++) {
            raw[i] = fw_capture[i];
        }
        /* pre-trim on its own (diagnostics) and the full per-sample path */
        st = ac_trim(raw, fw_trim, 6u, x);
        omega[0] = fw_omega[0];
        omega[1] = fw_omega[1];
        omega[2] = fw_omega[2];
        st = ac_process(&fw_table, fw_trim, raw, omega, out);
        {
            /* the path with the correctable terms: pre-trim, terms, resolve */
            int16_t t = fw_temp, t_off, t_gain;
            st = ac_trim_rails(raw, fw_trim, 6u, 0u, 10000u, x);
            st = ac_temp_lag_step(&fw_lag_off, t, &t_off);
            st = ac_temp_lag_step(&fw_lag_gain, t, &t_gain);
            st = ac_temp_correct(&fw_temp_table, t_off, t_gain, x, x);
            st = ac_skew_step(&fw_skew, &fw_line, x, x);
            st = ac_nonlin_invert(&fw_nl, x, x);
            st = ac_resolve(&fw_table, x, omega, out);
        }
        st = ac_rate_step(&fw_rate, &out[3], omega);
        for (i = 0u; i < 6u; i++) {
            fw_out[i] = out[i];
        }
        fw_omega[0] = omega[0];
        fw_omega[1] = omega[1];
        fw_omega[2] = omega[2];
        fw_status = (int16_t)st;
        (void)x;
    }
    return 0;
}
