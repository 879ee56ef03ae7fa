/* gen_proto_corpus.c — writes the seed corpus of fuzz_proto: one valid frame (header + payload)
 * per sample message of tests/unit/proto/proto_samples.h, named after the message.
 * Not a test or fuzz target (the Makefile globs fuzz_X.c only). Build and run from the repo root:
 *   cc -std=c11 -D_GNU_SOURCE -I. tests/fuzz/gen_proto_corpus.c proto/[a-z]*.c
 *      core/common/df_error.c -lm -o /tmp/gen_proto_corpus
 *   /tmp/gen_proto_corpus tests/fuzz/corpus/proto */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "proto/messages.h"
#include "tests/unit/proto/proto_samples.h"

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s OUTPUT_DIR\n", argv[0]);
        return 2;
    }
    sample s[N_SAMPLES];
    build_samples(s);
    int written = 0;
    for (int i = 0; i < N_SAMPLES; i++) {
        df_buf frame;
        df_buf_init(&frame);
        df_error e;
        size_t start;
        if (df_frame_begin(&frame, s[i].type, s[i].flags, (uint64_t)i + 1, &start, &e) ||
            df_buf_append(&frame, s[i].payload.data, s[i].payload.len, &e) ||
            df_frame_end(&frame, start, &e)) {
            fprintf(stderr, "%s: %s\n", s[i].name, e.msg);
            return 1;
        }
        char path[4096];
        snprintf(path, sizeof path, "%s/%s.bin", argv[1], s[i].name);
        FILE *f = fopen(path, "wb");
        if (!f || fwrite(frame.data, 1, frame.len, f) != frame.len || fclose(f)) {
            perror(path);
            return 1;
        }
        written++;
        df_buf_free(&frame);
    }
    free_samples(s);
    printf("wrote %d seeds to %s\n", written, argv[1]);
    return 0;
}
