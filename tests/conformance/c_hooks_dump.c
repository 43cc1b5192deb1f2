/* Hooks for conformance/adapters/c_decoder_template.c used by the tests: a "decoder" that replays what
   this project's decoder made of STREAM, from STREAM.dump written by the test. First line "ok" or
   "refuse BIT MESSAGE"; then one line a frame: time, then the 68 shown values. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct fba_decoder { FILE *fh; int refuse; long bit; } fba_decoder;

fba_decoder *hook_open(const char *stream, const char *fdp, char *err, size_t errlen, long *bit) {
    (void)fdp;
    char path[4096];
    snprintf(path, sizeof path, "%s.dump", stream);
    fba_decoder *d = calloc(1, sizeof *d);
    if (!d || !(d->fh = fopen(path, "r"))) { snprintf(err, errlen, "no dump %s", path); *bit = -1; free(d); return NULL; }
    char head[64] = "";
    if (!fgets(head, sizeof head, d->fh)) { fclose(d->fh); free(d); snprintf(err, errlen, "empty dump"); return NULL; }
    d->refuse = strncmp(head, "refuse", 6) == 0;
    d->bit = d->refuse ? strtol(head + 6, NULL, 10) : -1;
    return d;
}

int hook_next(fba_decoder *d, double *time_s, double faps[68], char *err, size_t errlen, long *bit) {
    if (fscanf(d->fh, "%lf", time_s) != 1) {
        if (!d->refuse) return 0;
        snprintf(err, errlen, "the replayed decoder refused the stream");
        *bit = d->bit;
        return -1;
    }
    for (int i = 0; i < 68; i++)
        if (fscanf(d->fh, "%lf", &faps[i]) != 1) { snprintf(err, errlen, "short dump line"); *bit = -1; return -1; }
    return 1;
}

void hook_close(fba_decoder *d) { fclose(d->fh); free(d); }
