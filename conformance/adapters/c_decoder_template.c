/*
 * A template for putting a C FBA decoder behind the conformance protocol (conformance/README.md).
 *
 *     cc -O2 -o mydecoder-conform c_decoder_template.c mydecoder_hooks.c
 *     mpeg4fa conform --decoder ./mydecoder-conform
 *
 * The runner calls   mydecoder-conform STREAM OUT.json [--fdp FDP]   once per vector. This file does
 * the protocol's part: arguments, the JSON answer (written to OUT.json.tmp and renamed, so a killed
 * run leaves no half file), exit statuses (0 decoded, 1 refused with "bit N" on stderr, 3 anything
 * else) and the frames decoded before a fault. You write the three hooks below around your decoder's
 * own loop, in a file of your own: open the stream, hand over one frame at a time (its time in
 * seconds and the 68 values it shows, FAP 1 and 2 as 0: their effect is in the low-level FAPs),
 * close. A decoder whose clock counts whole milliseconds sets TIMESTAMP_RESOLUTION to 0.001 (the
 * answer then declares it and the suite compares time stamps within 1 ms instead of 0.5 ms).
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef TIMESTAMP_RESOLUTION
#define TIMESTAMP_RESOLUTION 0.0 /* seconds per tick of your decoder's clock; 0: not declared */
#endif
#define N_FAPS 68

typedef struct fba_decoder fba_decoder;

/* Open STREAM; NULL when it cannot be decoded at all (then fill err and *bit, -1 if unknown). */
fba_decoder *hook_open(const char *stream, const char *fdp, char *err, size_t errlen, long *bit);
/* The next frame: 1 and fill *time_s and faps[68]; 0 at the end of the stream; -1 on a fault
   (fill err and *bit: the bit offset from the stream's first bit where it was found, -1 if unknown). */
int hook_next(fba_decoder *d, double *time_s, double faps[N_FAPS], char *err, size_t errlen, long *bit);
void hook_close(fba_decoder *d);

typedef struct {
    double *rows; /* (1 + N_FAPS) doubles a frame: time, then the values */
    size_t n, cap;
} frames;

static int push(frames *f, double t, const double *faps) {
    if (f->n == f->cap) {
        size_t cap = f->cap ? 2 * f->cap : 256;
        double *rows = realloc(f->rows, cap * (1 + N_FAPS) * sizeof(double));
        if (!rows) return -1;
        f->rows = rows;
        f->cap = cap;
    }
    double *row = f->rows + f->n * (1 + N_FAPS);
    row[0] = t;
    memcpy(row + 1, faps, N_FAPS * sizeof(double));
    f->n++;
    return 0;
}

static int write_answer(const char *out, const frames *f) {
    size_t len = strlen(out);
    char *tmp = malloc(len + 5);
    if (!tmp) return -1;
    memcpy(tmp, out, len);
    memcpy(tmp + len, ".tmp", 5);
    FILE *fh = fopen(tmp, "w");
    if (!fh) { free(tmp); return -1; }
    fputs("{\"timestamps\": [", fh);
    for (size_t k = 0; k < f->n; k++) fprintf(fh, "%s%.17g", k ? ", " : "", f->rows[k * (1 + N_FAPS)]);
    fputs("], \"shown\": [", fh);
    for (size_t k = 0; k < f->n; k++) {
        const double *row = f->rows + k * (1 + N_FAPS) + 1;
        fputs(k ? ", [" : "[", fh);
        for (int i = 0; i < N_FAPS; i++) fprintf(fh, "%s%.17g", i ? ", " : "", row[i]);
        fputc(']', fh);
    }
    fputc(']', fh);
    if (TIMESTAMP_RESOLUTION > 0) fprintf(fh, ", \"timestamp_resolution\": %.17g", (double)TIMESTAMP_RESOLUTION);
    fputs("}\n", fh);
    int bad = ferror(fh) | fclose(fh);
    if (bad || rename(tmp, out) != 0) { remove(tmp); free(tmp); return -1; }
    free(tmp);
    return 0;
}

int main(int argc, char **argv) {
    if (!(argc == 3 || (argc == 5 && strcmp(argv[3], "--fdp") == 0))) {
        fprintf(stderr, "usage: %s STREAM OUT.json [--fdp FDP]\n", argv[0]);
        return 3;
    }
    const char *stream = argv[1], *out = argv[2], *fdp = argc == 5 ? argv[4] : NULL;
    char err[512] = "";
    long bit = -1;
    frames f = {0};
    fba_decoder *d = hook_open(stream, fdp, err, sizeof err, &bit);
    int status = 0;
    if (!d) {
        status = -1;
    } else {
        double t, faps[N_FAPS];
        for (;;) {
            memset(faps, 0, sizeof faps);
            status = hook_next(d, &t, faps, err, sizeof err, &bit);
            if (status <= 0) break;
            if (push(&f, t, faps) != 0) {
                fprintf(stderr, "crash: out of memory after %zu frames\n", f.n);
                return 3;
            }
        }
        hook_close(d);
    }
    if ((status == 0 || f.n) && write_answer(out, &f) != 0) { /* refused: the frames before the fault */
        fprintf(stderr, "crash: cannot write %s: %s\n", out, strerror(errno));
        return 3;
    }
    free(f.rows);
    if (status < 0) {
        if (bit >= 0) fprintf(stderr, "refused: %s (bit %ld)\n", err, bit);
        else fprintf(stderr, "refused: %s\n", err);
        return 1;
    }
    return 0;
}
