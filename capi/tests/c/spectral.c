/*
 * ts_eval_spectral: a preset at four wavelengths against its RGB channels at
 * the paper's wavelengths (within 0.5%, docs/model.md §2.12), a material
 * with one index, and each refusal as its status code. Run under valgrind
 * memcheck in CI.
 */
#include "twoscale.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static int failures = 0;

#define CHECK(cond)                                                                   \
    do {                                                                              \
        if (!(cond)) {                                                                \
            fprintf(stderr, "%s:%d: CHECK failed: %s (last error: %s)\n", __FILE__,   \
                    __LINE__, #cond, ts_last_error());                                \
            failures++;                                                               \
        }                                                                             \
    } while (0)

int main(void) {
    ts_tables *tables = ts_tables_embedded();
    CHECK(tables != NULL);
    ts_material *gold = ts_material_preset(tables, "gold-hp17-geometry");
    CHECK(gold != NULL);
    const float wi[3] = {0.5f, 0.0f, 0.866f};
    const float wo[3] = {-0.48f, 0.02f, 0.877f};
    float rgb[3], four[4];
    const float lambda[4] = {0.645f, 0.526f, 0.444f, 0.8f};
    CHECK(ts_eval_rgb(gold, wi, wo, rgb) == TS_OK);
    CHECK(ts_eval_spectral(gold, wi, wo, lambda, four) == TS_OK);
    for (int c = 0; c < 3; c++) {
        CHECK(fabsf(four[c] - rgb[c]) <= 5e-3f * rgb[c]);
    }
    CHECK(four[3] > 0.0f);

    /* A wavelength outside [0.36, 0.83] µm, NULL, a non-finite direction. */
    const float outside[4] = {0.5f, 0.5f, 0.9f, 0.5f};
    CHECK(ts_eval_spectral(gold, wi, wo, outside, four) == TS_ERR_INVALID);
    CHECK(strstr(ts_last_error(), "lambda[2]") != NULL);
    CHECK(ts_eval_spectral(gold, wi, wo, NULL, four) == TS_ERR_NULL);
    CHECK(ts_eval_spectral(NULL, wi, wo, lambda, four) == TS_ERR_NULL);
    const float bad[3] = {NAN, 0.0f, 1.0f};
    CHECK(ts_eval_spectral(gold, bad, wo, lambda, four) == TS_ERR_INVALID);

    /* One index for every channel: a constant index over the spectrum. */
    ts_material_desc desc;
    CHECK(ts_material_desc_from_toml("[material]\nbeta = 0.2\np = 1\n"
                                     "eta = [[1.5, 3.0], [1.5, 3.0], [1.5, 3.0]]\n",
                                     &desc) == TS_OK);
    ts_material *grey = ts_material_new(tables, &desc);
    CHECK(grey != NULL);
    CHECK(ts_eval_spectral(grey, wi, wo, lambda, four) == TS_OK);
    CHECK(ts_eval_rgb(grey, wi, wo, rgb) == TS_OK);
    /* σs = 0 and one index: ρ does not depend on λ. */
    for (int k = 0; k < 4; k++) {
        CHECK(fabsf(four[k] - rgb[1]) <= 1e-5f * rgb[1]);
    }
    /* An index per channel is no spectrum. */
    CHECK(ts_material_desc_from_toml("[material]\nbeta = 0.2\np = 1\n"
                                     "eta = [[0.2, 3.5], [0.5, 2.2], [1.4, 1.9]]\n",
                                     &desc) == TS_OK);
    ts_material *coloured = ts_material_new(tables, &desc);
    CHECK(coloured != NULL);
    CHECK(ts_eval_spectral(coloured, wi, wo, lambda, four) == TS_ERR_INVALID);
    CHECK(strstr(ts_last_error(), "index over the spectrum") != NULL);

    ts_material_free(coloured);
    ts_material_free(grey);
    ts_material_free(gold);
    ts_tables_free(tables);
    if (failures) {
        fprintf(stderr, "%d failures\n", failures);
        return 1;
    }
    printf("spectral: ok\n");
    return 0;
}
