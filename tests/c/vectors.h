/*
 * accelcal -- platform layer of the test-vector program (tests/c/vectors.c).
 *
 * vectors.c uses nothing but the library and these four functions, so the
 * same source runs on the host (vectors_host.c) and on an AVR under simavr
 * (vectors_avr.c); tools/run_avr_tests.sh compares the two outputs byte for
 * byte.
 */
#ifndef AC_VECTORS_H
#define AC_VECTORS_H

#include <accelcal/ac_config.h>

/* Read-only data and strings.  On the AVR (2 KB RAM, Harvard) they stay in
 * flash; elsewhere these are plain const objects. */
#if defined(__AVR__)
#include <avr/pgmspace.h>
#define AC_ROM PROGMEM
#define AC_STR(s) PSTR(s)
#define AC_ROM_U8(p) ((uint8_t)pgm_read_byte(p))
#define AC_ROM_U16(p) ((uint16_t)pgm_read_word(p))
#define AC_ROM_U32(p) ((uint32_t)pgm_read_dword(p))
#else
#define AC_ROM
#define AC_STR(s) (s)
#define AC_ROM_U8(p) (*(const uint8_t *)(const void *)(p))
#define AC_ROM_U16(p) (*(const uint16_t *)(const void *)(p))
#define AC_ROM_U32(p) (*(const uint32_t *)(const void *)(p))
#endif

/* Called once before any output / after the last output (may not return). */
void ac_test_platform_init(void);
void ac_test_platform_exit(void);
/* Write one character of output. */
void ac_test_putc(char c);
/* A free-running cycle counter, or 0 always where there is none
 * (ac_test_have_cycles() says which). */
uint8_t ac_test_have_cycles(void);
uint32_t ac_test_cycles(void);

#endif /* AC_VECTORS_H */
