/* accelcal -- time skew (see ac_skew.h for the arithmetic and its bound). */
#include "accelcal/ac_skew.h"
#include "ac_internal.h"
#include "ac_terms_impl.h"

ac_status ac_skew_check(const ac_skew_table *t)
{
    uint8_t i;
    if (t == 0) {
        return AC_ERR_NULL;
    }
    if (t->n < 1u || t->n > (uint16_t)AC_MAX_CHANNELS || t->len < 2u || t->len > (uint16_t)AC_SKEW_MAX_LEN) {
        return AC_ERR_SIZE;
    }
    for (i = 0u; i < (uint8_t)t->n; i++) {
        if ((uint16_t)t->whole[i] + 2u > t->len || t->frac[i] > 32767u) {
            return AC_ERR_FORMAT;
        }
    }
    return AC_OK;
}

ac_status ac_skew_init(ac_skew_line *line, const ac_skew_table *t, int16_t *buf, uint16_t buf_values)
{
    ac_status st;
    if (line == 0 || buf == 0) {
        return AC_ERR_NULL;
    }
    st = ac_skew_check(t);
    if (st != AC_OK) {
        return st;
    }
    /* len <= 64, n <= 64: the product fits 16 bits */
    if (buf_values < (uint16_t)(t->len * t->n)) {
        return AC_ERR_SIZE;
    }
    line->buf = buf;
    line->n = t->n;
    line->len = t->len;
    line->pos = 0u;
    line->started = 0u;
    return AC_OK;
}

ac_status ac_skew_step(const ac_skew_table *t, ac_skew_line *line, const int16_t *x, int16_t *y)
{
    uint16_t n, len, pos;
    uint8_t i;
    if (t == 0 || line == 0 || x == 0 || y == 0 || line->buf == 0) {
        return AC_ERR_NULL;
    }
    n = t->n;
    len = t->len;
    if (line->n != n || line->len != len) {
        return AC_ERR_SIZE;
    }
    {
        ac_status st = ac_skew_check(t); /* before the line changes: an error writes nothing */
        if (st != AC_OK) {
            return st;
        }
    }
    if (line->started == 0u) {
        uint16_t s;
        for (s = 0u; s < len; s++) {
            for (i = 0u; i < (uint8_t)n; i++) {
                line->buf[(uint16_t)(s * n) + i] = x[i];
            }
        }
        line->started = 1u;
        pos = 0u;
    } else {
        int16_t *slot;
        pos = (uint16_t)(line->pos + 1u);
        if (pos >= len) {
            pos = 0u;
        }
        slot = line->buf + (uint16_t)(pos * n);
        for (i = 0u; i < (uint8_t)n; i++) {
            slot[i] = x[i];
        }
    }
    line->pos = pos;
    for (i = 0u; i < (uint8_t)n; i++) {
        uint16_t k = t->whole[i];
        uint16_t s0, s1;
        int16_t v0, v1, h, f;
        int32_t d, p;
        s0 = (pos >= k) ? (uint16_t)(pos - k) : (uint16_t)(pos + len - k);
        s1 = (s0 != 0u) ? (uint16_t)(s0 - 1u) : (uint16_t)(len - 1u);
        v0 = line->buf[(uint16_t)(s0 * n) + i];
        v1 = line->buf[(uint16_t)(s1 * n) + i];
        f = (int16_t)t->frac[i];
        /* d = v1 - v0 (17 bits) = 2 h + (d & 1): one 16 x 16 product f h */
        d = (int32_t)v1 - (int32_t)v0;
        h = (int16_t)((int32_t)((uint32_t)(d + (int32_t)65536L) >> 1) - (int32_t)32768L);
        p = AC_MUL16(f, h);
        p += p;
        if (((uint32_t)d & 1u) != 0u) {
            p += f;
        }
        /* |p| <= 2 * 32767 * 32768 + 32767 < 2^31 - 2^14 */
        y[i] = (int16_t)((int32_t)v0 + AC_R15W(p));
    }
    return AC_OK;
}
