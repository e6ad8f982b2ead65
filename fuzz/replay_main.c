/*
 * accelcal -- replay driver for fuzz/fuzz_core.c without libFuzzer: feeds each
 * file named on the command line (directories: each regular file in them, in
 * name order) to LLVMFuzzerTestOneInput once.  Lets any C99 compiler with
 * sanitizers (gcc -fsanitize=address,undefined) run the seed corpus and
 * reproduce a finding where clang's libFuzzer is absent:
 *
 *   cc -g -fsanitize=address,undefined -fno-sanitize-recover=all -std=c99 \
 *      -Iinclude -Icsrc fuzz/fuzz_core.c fuzz/replay_main.c csrc/\*.c -lm -o replay
 *   ./replay fuzz/corpus            # or ./replay build/fuzz/artifacts/crash-...
 *
 * Exit 0 after all inputs ran (a failed property aborts), 2 on a read error.
 * Host test code (POSIX dirent for directories).
 */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int run_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    uint8_t *buf;
    long len;
    size_t got;
    if (f == NULL) {
        fprintf(stderr, "replay: cannot open %s\n", path);
        return 2;
    }
    if (fseek(f, 0, SEEK_END) != 0 || (len = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) {
        fprintf(stderr, "replay: cannot size %s\n", path);
        fclose(f);
        return 2;
    }
    buf = malloc((size_t)len + 1u);
    if (buf == NULL) {
        fclose(f);
        return 2;
    }
    got = fread(buf, 1, (size_t)len, f);
    fclose(f);
    if (got != (size_t)len) {
        fprintf(stderr, "replay: short read on %s\n", path);
        free(buf);
        return 2;
    }
    (void)LLVMFuzzerTestOneInput(buf, got);
    free(buf);
    return 0;
}

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static int run_path(const char *path, unsigned long *count)
{
    struct stat sb;
    DIR *d;
    struct dirent *e;
    char **names = NULL;
    size_t n = 0, cap = 0, i;
    int rc = 0;
    if (stat(path, &sb) != 0) {
        fprintf(stderr, "replay: no such file %s\n", path);
        return 2;
    }
    if (!S_ISDIR(sb.st_mode)) {
        (*count)++;
        return run_file(path);
    }
    d = opendir(path);
    if (d == NULL) {
        fprintf(stderr, "replay: cannot read directory %s\n", path);
        return 2;
    }
    while ((e = readdir(d)) != NULL) {
        size_t len;
        char *full;
        if (e->d_name[0] == '.') {
            continue;
        }
        len = strlen(path) + strlen(e->d_name) + 2u;
        full = malloc(len);
        if (full == NULL) {
            rc = 2;
            break;
        }
        snprintf(full, len, "%s/%s", path, e->d_name);
        if (stat(full, &sb) != 0 || !S_ISREG(sb.st_mode)) {
            free(full);
            continue;
        }
        if (n == cap) {
            char **nn;
            cap = cap ? 2u * cap : 64u;
            nn = realloc(names, cap * sizeof *names);
            if (nn == NULL) {
                free(full);
                rc = 2;
                break;
            }
            names = nn;
        }
        names[n++] = full;
    }
    closedir(d);
    if (n > 0u) {
        qsort(names, n, sizeof *names, cmp_str);
    }
    for (i = 0; i < n; i++) {
        if (rc == 0) {
            (*count)++;
            rc = run_file(names[i]);
        }
        free(names[i]);
    }
    free(names);
    return rc;
}

int main(int argc, char **argv)
{
    unsigned long count = 0;
    int i;
    if (argc < 2) {
        fprintf(stderr, "usage: %s FILE|DIR ...\n", argv[0]);
        return 2;
    }
    for (i = 1; i < argc; i++) {
        int rc = run_path(argv[i], &count);
        if (rc != 0) {
            return rc;
        }
    }
    printf("replay: %lu inputs ran\n", count);
    return 0;
}
