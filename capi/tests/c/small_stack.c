/*
 * Building materials needs no large stack: every preset, through
 * ts_material_preset and through ts_material_desc_preset + ts_material_new,
 * is built and evaluated on a thread whose stack is 64 KiB (the model's
 * bakes are allocated zeroed on the heap and filled in place).
 *
 *   small_stack
 */
#include "twoscale.h"

#include <pthread.h>
#include <stdio.h>
#include <string.h>

/* The stack of the construction thread. */
#define STACK_BYTES (64 * 1024)

static void *build_every_preset(void *arg) {
    ts_tables *tables = arg;
    const float wi[3] = {0.6f, 0.1f, 0.8f}, wo[3] = {-0.55f, -0.05f, 0.83f};
    size_t built = 0;
    for (size_t p = 0; p < ts_preset_count(); p++) {
        const char *name = ts_preset_name(p);
        ts_material_desc desc;
        ts_material *m[2] = {ts_material_preset(tables, name), NULL};
        if (ts_material_desc_preset(name, &desc) == TS_OK) m[1] = ts_material_new(tables, &desc);
        for (int k = 0; k < 2; k++) {
            float rgb[3];
            if (m[k] && ts_eval_rgb(m[k], wi, wo, rgb) == TS_OK && rgb[0] > 0.0f) built++;
            else fprintf(stderr, "%s (%s): %s\n", name, k ? "desc" : "preset", ts_last_error());
            ts_material_free(m[k]);
        }
    }
    return (void *)built;
}

int main(void) {
    ts_tables *tables = ts_tables_embedded();
    if (!tables) {
        fprintf(stderr, "twoscale: %s\n", ts_last_error());
        return 1;
    }
    pthread_attr_t attr;
    pthread_t thread;
    void *built = NULL;
    if (pthread_attr_init(&attr) != 0 ||
        pthread_attr_setstacksize(&attr, STACK_BYTES) != 0 ||
        pthread_create(&thread, &attr, build_every_preset, tables) != 0 ||
        pthread_join(thread, &built) != 0) {
        fprintf(stderr, "could not run a thread with a %d-byte stack\n", STACK_BYTES);
        return 2;
    }
    pthread_attr_destroy(&attr);
    ts_tables_free(tables);
    size_t want = 2 * ts_preset_count();
    if ((size_t)built != want) {
        fprintf(stderr, "small_stack: %zu of %zu materials built\n", (size_t)built, want);
        return 1;
    }
    printf("small_stack: %zu materials built and evaluated on a %d KiB stack\n", want,
           STACK_BYTES / 1024);
    return 0;
}
