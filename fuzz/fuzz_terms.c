/*
 * accelcal -- target 14 of fuzz/fuzz_core.c (included by it): the correctable terms
 * (ac_temp.h, ac_skew.h, ac_nonlin.h).
 *
 * Mode byte: bits 0-1 the function (0 lag, 1 temperature, 2 skew, 3 nonlinearity); bit 2 an
 * arbitrary table (else one inside the documented ranges); bit 3 in place (y = x).
 * Properties:
 *   - every status is an ac_status value; a negative status writes nothing;
 *   - each function equals its header's integer recurrence written out here in 64-bit
 *     arithmetic (every rounding, clip and the AC_SATURATED flag), bit for bit;
 *   - in place gives the same as separate arrays;
 *   - on a checked table, without a clip: the temperature correction within the bound of
 *     ac_temp.h against the float formula, the nonlinearity within D_K of ac_nonlin.h against
 *     the float iteration.
 */

#define FT_SENT ((int16_t)0x5A5A)

/* floor(v / 2^s), s in 0..62, without relying on >> of a negative value */
static int64_t ft_floor(int64_t v, int s)
{
    int64_t d = (int64_t)1 << s;
    int64_t q = v / d;
    return (v % d != 0 && v < 0) ? q - 1 : q;
}

/* round(v 2^-s) half up; s = 0: v */
static int64_t ft_round(int64_t v, int s) { return s == 0 ? v : ft_floor(v + ((int64_t)1 << (s - 1)), s); }

static int64_t ft_clip(int64_t v, int64_t lo, int64_t hi, int *sat)
{
    if (v > hi) {
        *sat = 1;
        return hi;
    }
    if (v < lo) {
        *sat = 1;
        return lo;
    }
    return v;
}

#define FT_C32(v, s) ft_clip((v), INT32_MIN, INT32_MAX, (s))
#define FT_C16(v, s) ft_clip((v), INT16_MIN, INT16_MAX, (s))

static void ft_status(ac_status st, int sat, const char *what)
{
    CHECK_STATUS(st);
    CHECK((int)st == (sat ? (int)AC_SATURATED : (int)AC_OK), "%s: status %d, the recurrence's flag %d", what,
          (int)st, sat);
}

static void ft_lag(rd *r, int raw)
{
    ac_temp_lag f;
    uint8_t shift = raw ? rd_u8(r) : (uint8_t)(rd_u8(r) % 48u);
    uint16_t k = rd_u16(r);
    int64_t y = 0;
    int started = 0;
    uint8_t steps = (uint8_t)(1u + rd_u8(r) % 24u), s;
    ac_status st;
    if (!raw && shift < 16u) {
        k = (uint16_t)(k % ((1u << shift) + 1u));
    }
    memset(&f, 0x5A, sizeof f);
    st = ac_temp_lag_init(&f, k, shift);
    CHECK_STATUS(st);
    if (shift > 47u || (shift < 16u && (uint32_t)k > (1u << shift))) {
        CHECK(st == AC_ERR_RANGE, "lag init: shift %u k %u gave %d", shift, k, (int)st);
        return;
    }
    CHECK(st == AC_OK, "lag init: %d", (int)st);
    for (s = 0u; s < steps; s++) {
        int16_t temp = rd_i16_edge(r), out = FT_SENT, want;
        int sat = 0;
        int64_t x = (int64_t)temp * 65536;
        if (!started) {
            y = x;
            started = 1;
        } else {
            int64_t d = FT_C32(x - y, &sat);
            y = FT_C32(y + FT_C32(ft_round(d * (int64_t)k, shift), &sat), &sat);
        }
        want = (y >= 0x7FFF8000LL) ? INT16_MAX : (int16_t)ft_floor(y + 32768, 16);
        st = ac_temp_lag_step(&f, temp, &out);
        ft_status(st, sat, "ac_temp_lag_step");
        CHECK(out == want && (int64_t)f.y == y, "ac_temp_lag_step shift %u k %u step %u temp %d: out %d y %ld, "
              "recurrence %d %ld", shift, k, s, temp, out, (long)f.y, want, (long)y);
    }
}

static void ft_temp(rd *r, int raw, int inplace)
{
    ac_temp_table t;
    int16_t x[AC_MAX_CHANNELS], y[AC_MAX_CHANNELS], want[AC_MAX_CHANNELS];
    int16_t t_off, t_gain;
    uint16_t i, n;
    int sat = 0, checked;
    int64_t dto, dtg;
    ac_status st;
    memset(&t, 0, sizeof t);
    n = raw ? (uint16_t)(rd_u8(r) % (AC_MAX_CHANNELS + 2u)) : (uint16_t)(1u + rd_u8(r) % AC_MAX_CHANNELS);
    t.n = n;
    /* the output in 2^-frac counts (frac 0..AC_TEMP_MAX_OUT_FRAC; a raw input also past it); the
     * readings of a table with frac k mostly within int16 / 2^k (the output's range), edges kept */
    t.frac = (uint8_t)(rd_u8(r) % (raw ? AC_TEMP_MAX_OUT_FRAC + 3u : AC_TEMP_MAX_OUT_FRAC + 1u));
    t.t_ref = rd_i16_edge(r);
    for (i = 0u; i < AC_MAX_CHANNELS; i++) {
        t.oc[i] = raw ? rd_i16_edge(r) : (int16_t)(rd_i16(r) % 32768);
        t.gc[i] = raw ? rd_i16_edge(r) : (int16_t)(rd_i16(r) % 32768);
        t.o[i] = raw ? rd_i16(r) : (int16_t)(rd_i16(r) % 129);
        x[i] = rd_i16_edge(r);
        if (!raw && t.frac <= AC_TEMP_MAX_OUT_FRAC) {
            x[i] = (int16_t)(x[i] / (1 << t.frac));
        }
        y[i] = FT_SENT;
    }
    t_off = rd_i16_edge(r);
    t_gain = rd_i16_edge(r);
    {
        /* an eighth of the time channel 0's gain term at E32 = 22657 * 10367 or E32 + 1 = 30720 * 7646
         * (the clip's edge), either sign */
        uint8_t pick = rd_u8(r);
        if ((pick & 7u) == 0u) {
            int16_t gc = (pick & 8u) ? 30720 : 22657, dt = (pick & 8u) ? 7646 : 10367;
            t.gc[0] = (pick & 16u) ? (int16_t)-gc : gc;
            t.t_ref = (int16_t)(rd_i16(r) % 8192);
            t_gain = (int16_t)(t.t_ref + ((pick & 32u) ? -dt : dt));
        }
    }
    checked = ac_temp_check(&t) == AC_OK;
    st = inplace ? ac_temp_correct(&t, t_off, t_gain, memcpy(y, x, sizeof x), y)
                 : ac_temp_correct(&t, t_off, t_gain, x, y);
    CHECK_STATUS(st);
    if (n < 1u || n > AC_MAX_CHANNELS || t.frac > AC_TEMP_MAX_OUT_FRAC) {
        CHECK(st == ((n < 1u || n > AC_MAX_CHANNELS) ? AC_ERR_SIZE : AC_ERR_FORMAT), "ac_temp_correct n %u frac %u: %d",
              n, t.frac, (int)st);
        if (!inplace) {
            for (i = 0u; i < AC_MAX_CHANNELS; i++) {
                CHECK(y[i] == FT_SENT, "ac_temp_correct wrote y[%u] on an error", i);
            }
        }
        return;
    }
    dto = FT_C16((int64_t)t_off - t.t_ref, &sat);
    dtg = FT_C16((int64_t)t_gain - t.t_ref, &sat);
    for (i = 0u; i < n; i++) {
        const int64_t E32 = (int64_t)AC_TEMP_E_MAX * 8192 + 4095, o8 = (int64_t)t.o[i] * 256;
        int64_t e32 = (int64_t)t.gc[i] * dtg, w, e, e2, e3, rr, w16, g;
        w = FT_C32((int64_t)x[i] * 65536 - (o8 + (int64_t)t.oc[i] * dto), &sat);
        if (e32 > E32 || e32 < -E32) {
            e = e32 > 0 ? AC_TEMP_E_MAX : -AC_TEMP_E_MAX;
            sat = 1;
        } else {
            e = ft_floor(e32 + 4096, 13);
        }
        e2 = ft_round(e * e, 19);
        e3 = ft_round(e2 * e, 19);
        rr = (int16_t)(e2 - e - e3);
        if (w >= 0x7FFF8000LL) {
            w16 = INT16_MAX;
            sat = 1;
        } else {
            w16 = ft_floor(w + 32768, 16);
        }
        g = ft_round(w16 * rr, 3);
        w = FT_C32(w + g, &sat);
        w = FT_C32(w + o8, &sat);
        if (t.frac != 0u) {
            want[i] = (int16_t)FT_C16(ft_round(w, 16 - t.frac), &sat);
        } else if (w >= 0x7FFF8000LL) {
            want[i] = INT16_MAX;
            sat = 1;
        } else {
            want[i] = (int16_t)ft_floor(w + 32768, 16);
        }
    }
    ft_status(st, sat, "ac_temp_correct");
    for (i = 0u; i < n; i++) {
        CHECK(y[i] == want[i], "ac_temp_correct channel %u: %d, recurrence %d", i, y[i], want[i]);
    }
    if (checked && !sat) {
        for (i = 0u; i < n; i++) {
            double o = t.o[i] / 256.0, oc = t.oc[i] / 256.0, gc = t.gc[i] / 16777216.0;
            double e = gc * ((double)dtg / 256.0);
            double yref = o + ((double)x[i] - o - oc * ((double)dto / 256.0)) / (1.0 + e);
            double big = fabs((double)x[i]) > fabs(yref) ? fabs((double)x[i]) : fabs(yref);
            double q = ldexp(1.0, -(int)t.frac);     /* one output step, counts */
            double bound = 0.5 * q + 1.0 / 256 + 0.54 * fabs(e)
                           + (big + 1.0) * (1.0 / 262144 + e * e * e * e / (1.0 - fabs(e)));
            CHECK(fabs(y[i] * q - yref) <= bound, "ac_temp_correct channel %u frac %u: %d against %.6f, bound %.6f", i,
                  t.frac, y[i], yref, bound);
        }
    }
}

static void ft_skew(rd *r, int raw, int inplace)
{
    ac_skew_table t;
    ac_skew_line line;
    int16_t buf[AC_SKEW_MAX_LEN * AC_MAX_CHANNELS];
    int16_t hist[AC_SKEW_MAX_LEN + 40][AC_MAX_CHANNELS];
    uint16_t i, n;
    uint8_t steps = (uint8_t)(1u + rd_u8(r) % 40u), s;
    ac_status st;
    memset(&t, 0, sizeof t);
    n = raw ? (uint16_t)(rd_u8(r) % (AC_MAX_CHANNELS + 2u)) : (uint16_t)(1u + rd_u8(r) % AC_MAX_CHANNELS);
    t.n = n;
    t.len = raw ? (uint16_t)(rd_u8(r) % (AC_SKEW_MAX_LEN + 2u)) : (uint16_t)(2u + rd_u8(r) % 7u);
    for (i = 0u; i < AC_MAX_CHANNELS; i++) {
        t.whole[i] = raw ? rd_u8(r) : (uint8_t)(t.len >= 2u ? rd_u8(r) % (t.len - 1u) : 0u);
        t.frac[i] = raw ? rd_u16(r) : (uint16_t)(rd_u16(r) & 0x7FFFu);
    }
    st = ac_skew_init(&line, &t, buf, (uint16_t)(sizeof buf / sizeof buf[0]));
    CHECK_STATUS(st);
    if (st != AC_OK) {
        CHECK(ac_skew_check(&t) != AC_OK, "ac_skew_init refused a table ac_skew_check accepts: %d", (int)st);
        return;
    }
    for (s = 0u; s < steps; s++) {
        int16_t x[AC_MAX_CHANNELS], y[AC_MAX_CHANNELS];
        for (i = 0u; i < AC_MAX_CHANNELS; i++) {
            x[i] = rd_i16_edge(r);
            y[i] = FT_SENT;
            hist[s][i] = x[i];
        }
        st = inplace ? ac_skew_step(&t, &line, memcpy(y, x, sizeof x), y) : ac_skew_step(&t, &line, x, y);
        ft_status(st, 0, "ac_skew_step");
        for (i = 0u; i < n; i++) {
            /* the first step fills the line: samples before it are the first sample */
            int k0 = (int)s - t.whole[i], k1 = k0 - 1;
            int64_t v0 = hist[k0 < 0 ? 0 : k0][i], v1 = hist[k1 < 0 ? 0 : k1][i];
            int64_t want = v0 + ft_round((int64_t)t.frac[i] * (v1 - v0), 15);
            CHECK(y[i] == want, "ac_skew_step step %u channel %u (whole %u frac %u): %d, formula %ld", s, i,
                  t.whole[i], t.frac[i], y[i], (long)want);
        }
    }
}

static void ft_nonlin(rd *r, int raw, int inplace)
{
    ac_nonlin_table t;
    int16_t x[AC_MAX_CHANNELS], y[AC_MAX_CHANNELS], want[AC_MAX_CHANNELS];
    uint16_t i, n;
    int sat = 0, sh, checked, it;
    ac_status st;
    memset(&t, 0, sizeof t);
    n = raw ? (uint16_t)(rd_u8(r) % (AC_MAX_CHANNELS + 2u)) : (uint16_t)(1u + rd_u8(r) % AC_MAX_CHANNELS);
    t.n = n;
    t.shift = raw ? rd_i8(r) : (int8_t)(rd_u8(r) % 31u);
    for (i = 0u; i < AC_MAX_CHANNELS; i++) {
        int16_t a2 = rd_i16_edge(r), a3 = rd_i16_edge(r);
        if (!raw) {
            int32_t room;
            a2 = (int16_t)(a2 == INT16_MIN ? -32767 : a2);
            room = 32767 - (a2 < 0 ? -a2 : a2);
            a3 = (int16_t)((int32_t)a3 % (room + 1));
        }
        t.a2[i] = a2;
        t.a3[i] = a3;
        x[i] = rd_i16_edge(r);
        y[i] = FT_SENT;
    }
    checked = ac_nonlin_check(&t) == AC_OK;
    st = inplace ? ac_nonlin_invert(&t, memcpy(y, x, sizeof x), y) : ac_nonlin_invert(&t, x, y);
    CHECK_STATUS(st);
    if (n < 1u || n > AC_MAX_CHANNELS || t.shift < 0 || t.shift > 30) {
        CHECK(st == (n < 1u || n > AC_MAX_CHANNELS ? AC_ERR_SIZE : AC_ERR_FORMAT), "ac_nonlin_invert: %d", (int)st);
        if (!inplace) {
            for (i = 0u; i < AC_MAX_CHANNELS; i++) {
                CHECK(y[i] == FT_SENT, "ac_nonlin_invert wrote y[%u] on an error", i);
            }
        }
        return;
    }
    sh = t.shift;
    for (i = 0u; i < n; i++) {
        int64_t z = x[i];
        for (it = 0; it < AC_NONLIN_ITERATIONS; it++) {
            int64_t h = (int16_t)(t.a2[i] + (int16_t)ft_round((int64_t)t.a3[i] * z, 15));
            int64_t g = (int16_t)ft_round(h * z, 15);
            z = FT_C16((int64_t)x[i] - ft_round(g * z, sh), &sat);
        }
        want[i] = (int16_t)z;
    }
    ft_status(st, sat, "ac_nonlin_invert");
    for (i = 0u; i < n; i++) {
        CHECK(y[i] == want[i], "ac_nonlin_invert shift %d channel %u: %d, recurrence %d", sh, i, y[i], want[i]);
    }
    if (checked && !sat) {
        for (i = 0u; i < n; i++) {
            double c2 = t.a2[i] / ldexp(1.0, 15 + sh), c3 = t.a3[i] / ldexp(1.0, 30 + sh);
            double zf = x[i], big = fabs((double)x[i]), L, E, D = 0.5;
            for (it = 0; it < AC_NONLIN_ITERATIONS; it++) {
                zf = x[i] - c2 * zf * zf - c3 * zf * zf * zf;
                big = fabs(zf) > big ? fabs(zf) : big;
            }
            big = fabs((double)y[i]) > big ? fabs((double)y[i]) : big;
            L = 2.0 * fabs(c2) * big + 3.0 * fabs(c3) * big * big;
            E = 0.5 + (big * big / 65536.0 + big / 2.0) / ldexp(1.0, sh);
            for (it = 0; it < AC_NONLIN_ITERATIONS; it++) {
                D = E + L * D;
            }
            CHECK(fabs(y[i] - zf) <= D, "ac_nonlin_invert shift %d channel %u: %d against the float %.4f, D %.4f",
                  sh, i, y[i], zf, D);
        }
    }
}

static void target_terms(rd *r)
{
    uint8_t mode = rd_u8(r);
    int raw = (mode & 4u) != 0u, inplace = (mode & 8u) != 0u;
    switch (mode & 3u) {
    case 0:
        ft_lag(r, raw);
        break;
    case 1:
        ft_temp(r, raw, inplace);
        break;
    case 2:
        ft_skew(r, raw, inplace);
        break;
    default:
        ft_nonlin(r, raw, inplace);
        break;
    }
}
