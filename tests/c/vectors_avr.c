/*
 * accelcal -- AVR (ATmega328P under simavr) platform layer of the test-vector
 * program: output on UART0 (simavr prints what is sent there), Timer1 at the
 * CPU clock extended to 32 bits by its overflow interrupt as a cycle counter,
 * stack painting to report the deepest stack use, and cli + sleep at the end
 * (which makes simavr exit).
 */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>

#include "vectors.h"

static volatile uint16_t timer_ovf;

ISR(TIMER1_OVF_vect)
{
    timer_ovf++;
}

/* RAM between the end of .bss and the stack, painted at start-up. */
extern uint8_t _end;
#define PAINT 0xC5u

static void paint_stack(void)
{
    uint8_t *p = &_end;
    uint8_t *top = (uint8_t *)SP - 32; /* leave this function's frame alone */
    while (p < top) {
        *p++ = PAINT;
    }
}

static uint16_t stack_never_used(void)
{
    const uint8_t *p = &_end;
    uint16_t n = 0u;
    while (*p == PAINT && p < (const uint8_t *)SP) {
        p++;
        n++;
    }
    return n;
}

static void put_str(const char *s) /* s in flash */
{
    char c;
    while ((c = (char)pgm_read_byte(s)) != '\0') {
        ac_test_putc(c);
        s++;
    }
}

static void put_u16_dec(uint16_t v)
{
    static const uint16_t p10[5] PROGMEM = {10000u, 1000u, 100u, 10u, 1u};
    uint8_t i, started = 0u;
    for (i = 0u; i < 5u; i++) {
        char d = '0';
        uint16_t p = pgm_read_word(&p10[i]);
        while (v >= p) {
            v = (uint16_t)(v - p);
            d++;
        }
        if (d != '0' || started || i == 4u) {
            ac_test_putc(d);
            started = 1u;
        }
    }
}

void ac_test_platform_init(void)
{
    paint_stack();
    /* UART0: 2 Mbaud at 16 MHz (U2X, UBRR 0); simavr does not care, a real
     * board would need a matching terminal. */
    UCSR0A = (uint8_t)(1u << U2X0);
    UBRR0H = 0u;
    UBRR0L = 0u;
    UCSR0C = (uint8_t)((1u << UCSZ01) | (1u << UCSZ00));
    UCSR0B = (uint8_t)(1u << TXEN0);
    /* Timer1: normal mode, clk/1, overflow interrupt */
    TCCR1A = 0u;
    TCCR1B = (uint8_t)(1u << CS10);
    TIMSK1 = (uint8_t)(1u << TOIE1);
    sei();
}

void ac_test_putc(char c)
{
    while ((UCSR0A & (1u << UDRE0)) == 0u) {
    }
    UDR0 = (uint8_t)c;
}

uint8_t ac_test_have_cycles(void)
{
    return 1u;
}

uint32_t ac_test_cycles(void)
{
    uint8_t sreg = SREG;
    uint16_t lo, hi;
    cli();
    lo = TCNT1;
    hi = timer_ovf;
    if ((TIFR1 & (1u << TOV1)) != 0u && lo < 0x8000u) {
        hi++; /* overflow pending, not yet counted */
    }
    SREG = sreg;
    return ((uint32_t)hi << 16) | lo;
}

void ac_test_platform_exit(void)
{
    put_str(PSTR("AVR stack never used: "));
    put_u16_dec(stack_never_used());
    put_str(PSTR(" bytes\n"));
    /* let the last byte leave the shift register, then stop the simulation */
    while ((UCSR0A & (1u << TXC0)) == 0u) {
    }
    cli();
    sleep_enable();
    sleep_cpu();
    for (;;) {
    }
}
