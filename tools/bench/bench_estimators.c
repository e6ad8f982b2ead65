/* Firmware cost of the motion estimators, per sample (tools/bench_estimators.py).
 * AVR: Timer1 at prescaler 1 counts cycles exactly under simavr; each figure is the
 * mean over BENCH_N timed calls in a realistic state (the pendulum mid-swing, the
 * displacement in motion).  Results go out on UART0 as one "BENCH k=v ..." line.
 * Host: the same program prints the same line with zero cycles (a smoke test).
 * est_data.h (made by the tool) holds two triad tables, BENCH_N samples of raw
 * pendulum readings, r1, r2 (Q.20) and dt. */
#include <accelcal/accelcal.h>
#include "est_data.h"

#include "bench_io.h"

static ac_att att;
static ac_att_out aout;
static ac_disp disp;
static ac_disp_out dout;
static ac_rest rest;
static ac_rate rate;

int main(void)
{
    uint16_t i;
    uint32_t c_triad = 0, c_att = 0, c_atan = 0, c_sqrt = 0, c_disp3 = 0, c_disp1 = 0, c_rest = 0,
             c_rate = 0, c_frame = 0, c_end = 0;
    uint32_t check = 0;
    int32_t f1[3], f2[3], f[3], alpha[3] = {120, -340, 510};
    int16_t omega[3], ang = 0, rot[3][3];
    uint16_t root = 0;
    uint32_t mag = 0;
    uint8_t fl = 0;
    ac_rest_cfg rc;
    ac_disp_cfg dc;
    int32_t g[3] = {30000, -45000, 640000};

    /* ---- attitude: triad apply x 2 + ac_att_step, mid-swing ---- */
    (void)ac_att_init(&att, BENCH_R1, BENCH_R2, BENCH_DT_M, BENCH_DT_SHIFT, 512u, BENCH_W2_GATE, BENCH_LEAK);
    for (i = 0; i < BENCH_N; i++) {
        timer_start();
        (void)ac_triad_apply(&BENCH_TRIAD1, BENCH_RAW[i], f1);
        (void)ac_triad_apply(&BENCH_TRIAD2, BENCH_RAW[i] + 3, f2);
        c_triad += timer_stop();
        timer_start();
        (void)ac_att_step(&att, f1, f2, &aout);
        c_att += timer_stop();
        check += (uint32_t)aout.theta + (uint32_t)aout.w;
        timer_start();
        (void)ac_atan2(f1[0] * 300 - f2[0] * 100, f2[2] * 100 - f1[2] * 300, &ang, &mag);
        c_atan += timer_stop();
        timer_start();
        (void)ac_isqrt32((uint32_t)aout.gmag * 977u + i, &root);
        c_sqrt += timer_stop();
        check += (uint32_t)ang + root;
    }

    /* ---- displacement, 3-axis and 1-D: rest, then timed steps in motion ---- */
    rc.dev_max = 51;              /* 0.05 m/s^2 */
    rc.g2_lo = 96000000UL;        /* (9.34 m/s^2)^2 Q.20 */
    rc.g2_hi = 116000000UL;       /* (10.5 m/s^2)^2 */
    rc.alpha_max = 2000;
    rc.ref_max = 154;             /* 0.15 m/s^2 */
    rc.hold = 25u;
    rc.ema_shift = 3u;
    dc.rest = rc;
    dc.dt_m = BENCH_DT_M;
    dc.dt_shift = BENCH_DT_SHIFT;
    dc.axis = -1;
    (void)ac_disp_init(&disp, &dc);
    f[0] = 300;
    f[1] = -450;
    f[2] = 10030;
    for (i = 0; i < 40; i++) {
        (void)ac_disp_step(&disp, f, &dout);
    }
    for (i = 0; i < BENCH_N; i++) {
        f[0] = 300 + (int32_t)(i * 37u);
        timer_start();
        (void)ac_disp_step(&disp, f, &dout);
        c_disp3 += timer_stop();
        check += (uint32_t)dout.p[0];
    }
    /* back to rest: the step that ends the motion applies the correction */
    f[0] = 300;
    for (i = 0; i < 60; i++) {
        if (i == 0) {
            (void)ac_disp_step(&disp, f, &dout);
            continue;
        }
        timer_start();
        (void)ac_disp_step(&disp, f, &dout);
        if (dout.flags & AC_DISP_SEG_END) {
            c_end = timer_stop();
        } else {
            (void)timer_stop();
        }
    }
    check += (uint32_t)dout.p[0];
    dc.axis = 0;
    (void)ac_disp_init(&disp, &dc);
    for (i = 0; i < 40; i++) {
        (void)ac_disp_step(&disp, f, &dout);
    }
    for (i = 0; i < BENCH_N; i++) {
        f[0] = 300 + (int32_t)(i * 37u);
        timer_start();
        (void)ac_disp_step(&disp, f, &dout);
        c_disp1 += timer_stop();
        check += (uint32_t)dout.p[0];
    }

    /* ---- rest detector alone, and rate with reset on rest (3 axes) ---- */
    (void)ac_rest_init(&rest, &rc);
    (void)ac_rate_init(&rate, BENCH_DT_M, BENCH_DT_SHIFT, 200u);
    for (i = 0; i < BENCH_N; i++) {
        f[0] = 300 + (int32_t)((i & 3u) * 400u);
        timer_start();
        (void)ac_rest_step(&rest, f, alpha, &fl);
        c_rest += timer_stop();
        timer_start();
        (void)ac_rest_rate_step(&rest, &rate, f, alpha, omega, &fl);
        c_rate += timer_stop();
        check += (uint32_t)omega[0] + fl;
    }

    /* ---- the frame of the first rest (once per run) ---- */
    timer_start();
    (void)ac_tilt_frame(g, rot);
    c_frame = timer_stop();
    check += (uint32_t)rot[0][0];

    out_str("BENCH");
    out_kv("triad_apply_x2", c_triad / BENCH_N);
    out_kv("att_step", c_att / BENCH_N);
    out_kv("atan2", c_atan / BENCH_N);
    out_kv("isqrt32", c_sqrt / BENCH_N);
    out_kv("disp_step_3axis", c_disp3 / BENCH_N);
    out_kv("disp_step_1d", c_disp1 / BENCH_N);
    out_kv("disp_segment_end", c_end);
    out_kv("rest_step", c_rest / BENCH_N);
    out_kv("rest_rate_step", c_rate / BENCH_N);
    out_kv("tilt_frame", c_frame);
    out_kv("check", check);
    out_str("\n");
    bench_end();
    return 0;
}
