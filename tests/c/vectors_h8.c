/*
 * accelcal -- H8/300H platform layer of the test-vector program, for GNU's
 * H8 simulator (tools/run_h8_tests.sh): output through the simulator's
 * write trap (`jsr @@0xc7': r0 = fd, r1 = buffer, r2 = length), a line at a
 * time; no cycle counter; the stack painted at start-up and scanned at the
 * end; the end through the simulator's exit sequence (tools/h8sim/crt0.s).
 *
 * It also gives the vector program (not the library) the two helpers its
 * own code needs on a target without libc or libgcc: tools/run_h8_tests.sh
 * renames vectors.o's references to memcpy and __umodsi3 to the names
 * below, so a reference from the library still fails the link.
 */
#include "vectors.h"

void h8sim_exit(int status); /* tools/h8sim/crt0.s */

extern uint8_t end;   /* end of .bss (linker script symbol _end) */
extern uint8_t stack; /* initial stack pointer (linker script symbol _stack) */

#define PAINT 0xC5u
#define LINE 128u

static char line[LINE];
static uint16_t line_n;

static uint16_t sim_write(const char *buf, uint16_t n)
{
    register uint16_t r0 __asm__("r0") = 1u; /* stdout */
    register const char *r1 __asm__("r1") = buf;
    register uint16_t r2 __asm__("r2") = n;
    __asm__ volatile("jsr @@0xc7" : "+r"(r0) : "r"(r1), "r"(r2) : "memory");
    return r0;
}

static void flush(void)
{
    if (line_n > 0u && sim_write(line, line_n) != line_n) {
        h8sim_exit(3); /* output lost: fail */
    }
    line_n = 0u;
}

static uint16_t stack_pointer(void)
{
    uint16_t sp;
    __asm__ volatile("mov.w r7,%0" : "=r"(sp));
    return sp;
}

void ac_test_platform_init(void)
{
    uint8_t *p = &end;
    uint8_t *top = (uint8_t *)stack_pointer() - 32; /* leave this frame alone */
    while (p < top) {
        *p++ = PAINT;
    }
}

void ac_test_putc(char c)
{
    line[line_n++] = c;
    if (c == '\n' || line_n == LINE) {
        flush();
    }
}

uint8_t ac_test_have_cycles(void)
{
    return 0u;
}

uint32_t ac_test_cycles(void)
{
    return 0u;
}

static void put_str(const char *s)
{
    while (*s != '\0') {
        ac_test_putc(*s++);
    }
}

static void put_u16_dec(uint16_t v)
{
    char d[6];
    uint8_t i = 0u;
    do {
        d[i++] = (char)('0' + v % 10u);
        v = (uint16_t)(v / 10u);
    } while (v != 0u);
    while (i > 0u) {
        ac_test_putc(d[--i]);
    }
}

void ac_test_platform_exit(void)
{
    const uint8_t *p = &end;
    uint16_t never = 0u, sp = stack_pointer();
    while (*p == PAINT && (uint16_t)p < sp) {
        p++;
        never++;
    }
    put_str("H8 stack: deepest use ");
    put_u16_dec((uint16_t)((uint16_t)&stack - (uint16_t)&end - never));
    put_str(" bytes below the initial stack pointer, never used ");
    put_u16_dec(never);
    put_str(" bytes\n");
    flush();
    h8sim_exit(0);
}

/* ---- helpers for vectors.o only (see the comment at the top) ---- */

void *h8vec_memcpy(void *dst, const void *src, uint16_t n)
{
    uint8_t *d = (uint8_t *)dst;
    const uint8_t *s = (const uint8_t *)src;
    while (n-- > 0u) {
        *d++ = *s++;
    }
    return dst;
}

uint32_t h8vec_umodsi3(uint32_t a, uint32_t b)
{
    uint32_t r = 0UL;
    uint8_t i;
    if (b == 0UL) {
        h8sim_exit(4);
    }
    for (i = 0u; i < 32u; i++) {
        uint8_t carry = (uint8_t)(r >> 31);
        r = (r << 1) | (a >> 31);
        a <<= 1;
        if (carry != 0u || r >= b) {
            r -= b;
        }
    }
    return r;
}
