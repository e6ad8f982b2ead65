/* Cycle counting and output for the firmware benchmarks (bench_main.c,
 * bench_estimators.c).  AVR: Timer1 at prescaler 1 counts cycles exactly under
 * simavr (overflows counted in an interrupt); text goes out on UART0.  Host: the
 * same calls print to stdout and count nothing (a smoke test). */
#ifndef BENCH_IO_H
#define BENCH_IO_H

#ifdef __AVR__
#include <avr/io.h>
#include <avr/interrupt.h>
#include <avr/sleep.h>
static volatile uint16_t overflows;
ISR(TIMER1_OVF_vect) { overflows++; }
static inline void out_char(char c) { while (!(UCSR0A & (1 << UDRE0))) {} UDR0 = (uint8_t)c; }
static inline void timer_start(void) { TCCR1A = 0; TCCR1B = 0; TCNT1 = 0; overflows = 0; TIFR1 = 0xFF; TIMSK1 = 1 << TOIE1; sei(); TCCR1B = 1 << CS10; }
static inline uint32_t timer_stop(void) { uint16_t t = TCNT1; TCCR1B = 0; cli(); return ((uint32_t)overflows << 16) + t; }
static inline void bench_end(void) { cli(); sleep_enable(); sleep_cpu(); }
#else
#include <stdio.h>
static inline void out_char(char c) { putchar(c); }
static inline void timer_start(void) {}
static inline uint32_t timer_stop(void) { return 0; }
static inline void bench_end(void) {}
#endif

static inline void out_str(const char *s) { while (*s) out_char(*s++); }
static inline void out_u32(uint32_t v)
{
    char buf[11];
    int i = 10;
    buf[i] = 0;
    do { buf[--i] = (char)('0' + (v % 10u)); v /= 10u; } while (v != 0u && i > 0);
    out_str(&buf[i]);
}
static inline void out_kv(const char *k, uint32_t v) { out_char(' '); out_str(k); out_char('='); out_u32(v); }

#endif /* BENCH_IO_H */
