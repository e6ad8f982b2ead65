/* accelcal -- host platform layer of the test-vector program: stdout. */
#include <stdio.h>

#include "vectors.h"

void ac_test_platform_init(void)
{
}

void ac_test_platform_exit(void)
{
    fflush(stdout);
}

void ac_test_putc(char c)
{
    putchar((unsigned char)c);
}

uint8_t ac_test_have_cycles(void)
{
    return 0u;
}

uint32_t ac_test_cycles(void)
{
    return 0u;
}
