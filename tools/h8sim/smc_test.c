/*
 * accelcal -- self-modifying-code check of the simulator's decode cache
 * (tools/h8sim/decode-cache.patch), run by tools/build_h8sim.sh.
 *
 * A routine in RAM, `mov.w #imm,r0 ; rts', is called, then rewritten with
 * each kind of store the simulator has (word, byte, long, eepmov.b block
 * copy) and called again; every call must return the value just written.
 * Exit status: a bit per wrong call (1 first call, 2 after the word store,
 * 4 byte, 8 long, 16 eepmov.b), so 0 when all are right.  With the cache's
 * invalidation switched off (H8SIM_DCACHE_NO_INVAL=1) the stale decoded
 * instruction runs and every store's call must be wrong (status 30): that
 * is how the build proves the check exercises the cache after each kind of
 * store.
 */
typedef unsigned char u8;
typedef unsigned short u16;
typedef unsigned long u32;
typedef u16 (*fn)(void);

void h8sim_exit(int status);

/* mov.w #0x1111,r0 (79 00 11 11) ; rts (54 70) */
static u8 code[8] __attribute__((aligned(4))) = {0x79, 0x00, 0x11, 0x11, 0x54, 0x70, 0x00, 0x00};
static u8 patch[8] __attribute__((aligned(4))) = {0x79, 0x00, 0x55, 0x66, 0x54, 0x70, 0x00, 0x00};

static u16 call(void)
{
    fn f = (fn)(void *)code;
    return f();
}

static void store_w(volatile u16 *p, u16 v)
{
    __asm__ volatile("mov.w %1,@%0" : : "r"(p), "r"(v) : "memory");
}

static void store_b(volatile u8 *p, u8 v)
{
    __asm__ volatile("mov.b %1l,@%0" : : "r"(p), "r"(v) : "memory");
}

static void store_l(volatile u32 *p, u32 v)
{
    __asm__ volatile("mov.l %1,@%0" : : "r"(p), "r"(v) : "memory");
}

/* eepmov.b: r4l bytes from @er5 to @er6 (er6 is the frame pointer gcc will
 * not give to an asm, so a routine of its own; args dst r0, src r1, n r2) */
void eepmov_b(void *dst, const void *src, u16 n);
__asm__(".global _eepmov_b\n"
        "_eepmov_b:\n"
        "\tmov.l er4,@-er7\n"
        "\tmov.l er5,@-er7\n"
        "\tmov.l er6,@-er7\n"
        "\tsub.l er5,er5\n"
        "\tmov.w r1,r5\n"
        "\tsub.l er6,er6\n"
        "\tmov.w r0,r6\n"
        "\tsub.w r4,r4\n"
        "\tmov.b r2l,r4l\n"
        "\teepmov.b\n"
        "\tmov.l @er7+,er6\n"
        "\tmov.l @er7+,er5\n"
        "\tmov.l @er7+,er4\n"
        "\trts\n");

int main(void)
{
    u16 i;
    int wrong = 0;
    /* warm the cache: the same address decoded several times */
    for (i = 0u; i < 3u; i++) {
        if (call() != 0x1111u) {
            wrong |= 1;
        }
    }
    store_w((volatile u16 *)(void *)&code[2], 0x2222u); /* word store into the immediate */
    if (call() != 0x2222u) {
        wrong |= 2;
    }
    store_b((volatile u8 *)&code[3], 0x33u); /* byte store, last byte of the instruction */
    if (call() != 0x2233u) {
        wrong |= 4;
    }
    store_l((volatile u32 *)(void *)&code[0], 0x79004444UL); /* long store over the whole insn */
    if (call() != 0x4444u) {
        wrong |= 8;
    }
    eepmov_b(code, patch, 4u); /* block copy */
    if (call() != 0x5566u) {
        wrong |= 16;
    }
    return wrong;
}
