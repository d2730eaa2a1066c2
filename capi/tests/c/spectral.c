/*
 * ts_eval_spectral: a preset at four wavelengths against its RGB channels at
 * the paper's wavelengths (TS_RGB_MODE_PAPER_WAVELENGTHS; within 0.5%,
 * docs/model.md §2.12), a material
 * with one index, a material given its index over the spectrum (eta_rows,
 * from a heap copy freed before use: the handle owns its copy) against the
 * preset with the same rows, TS_RGB_MODE_INTEGRATED, and each refusal as
 * its status code; a material file with a spectrum through its owned handle
 * (ts_material_file_*). Run under valgrind memcheck in CI.
 */
#include "twoscale.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
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
    /* A preset's default RGB is the integral over the spectrum. */
    ts_material_desc preset;
    CHECK(ts_material_desc_preset("gold-hp17-geometry", &preset) == TS_OK);
    CHECK(preset.rgb_mode == TS_RGB_MODE_INTEGRATED);
    preset.rgb_mode = TS_RGB_MODE_PAPER_WAVELENGTHS;
    ts_material *paper = ts_material_new(tables, &preset);
    CHECK(paper != NULL);
    const float wi[3] = {0.5f, 0.0f, 0.866f};
    const float wo[3] = {-0.48f, 0.02f, 0.877f};
    float rgb[3], four[4];
    const float lambda[4] = {0.645f, 0.526f, 0.444f, 0.8f};
    CHECK(ts_eval_rgb(paper, wi, wo, rgb) == TS_OK);
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
    /* σs = 0 and one index: ρ does not depend on λ, and it is the RGB
     * model's up to F: the spectral model reads F from its table over λ and
     * √cos θd, coarser than the one-wavelength bakes' (within 4.5e-4 of the
     * closed form, the runtime's test fresnel_bake_is_within_its_stated_error). */
    for (int k = 0; k < 4; k++) {
        CHECK(fabsf(four[k] - four[0]) <= 1e-6f * four[0]);
        CHECK(fabsf(four[k] - rgb[1]) <= 4.5e-4f * rgb[1]);
    }
    /* An index per channel is no spectrum. */
    CHECK(ts_material_desc_from_toml("[material]\nbeta = 0.2\np = 1\n"
                                     "eta = [[0.2, 3.5], [0.5, 2.2], [1.4, 1.9]]\n",
                                     &desc) == TS_OK);
    ts_material *coloured = ts_material_new(tables, &desc);
    CHECK(coloured != NULL);
    CHECK(ts_eval_spectral(coloured, wi, wo, lambda, four) == TS_ERR_INVALID);
    CHECK(strstr(ts_last_error(), "index over the spectrum") != NULL);

    /* Integrated RGB needs a spectrum. */
    desc.rgb_mode = TS_RGB_MODE_INTEGRATED;
    CHECK(ts_material_new(tables, &desc) == NULL);
    CHECK(ts_last_status() == TS_ERR_INVALID);
    CHECK(strstr(ts_last_error(), "rgb_mode 'integrated'") != NULL);

    /* The preset's description points to its measured rows; a copy of the
     * rows on the heap, freed once the handle is built, gives the same model. */
    CHECK(preset.eta_rows != NULL && preset.eta_row_count > 2);
    float *rows = malloc(3 * preset.eta_row_count * sizeof(float));
    CHECK(rows != NULL);
    memcpy(rows, preset.eta_rows, 3 * preset.eta_row_count * sizeof(float));
    ts_material_desc given = preset;
    given.eta_rows = rows;
    memset(given.eta_re, 0, sizeof given.eta_re); /* not read with rows */
    ts_material *copied = ts_material_new(tables, &given);
    free(rows);
    CHECK(copied != NULL);
    float mine[4];
    CHECK(ts_eval_spectral(gold, wi, wo, lambda, four) == TS_OK);
    CHECK(ts_eval_spectral(copied, wi, wo, lambda, mine) == TS_OK);
    CHECK(memcmp(four, mine, sizeof four) == 0);
    CHECK(ts_eval_rgb(copied, wi, wo, mine) == TS_OK);
    CHECK(ts_eval_rgb(paper, wi, wo, rgb) == TS_OK);
    CHECK(memcmp(rgb, mine, sizeof rgb) == 0);

    /* Integrated RGB of gold (the preset's default): blue below the paper's
     * 0.444 µm value relative to red (docs/design/rgb-integration.md). */
    preset.rgb_mode = TS_RGB_MODE_INTEGRATED;
    ts_material *integrated = ts_material_new(tables, &preset);
    CHECK(integrated != NULL);
    float sum[3], by_name[3];
    CHECK(ts_eval_rgb(gold, wi, wo, by_name) == TS_OK);
    CHECK(ts_eval_rgb(integrated, wi, wo, sum) == TS_OK);
    CHECK(sum[0] > 0.0f && sum[2] > 0.0f);
    CHECK(memcmp(sum, by_name, sizeof sum) == 0);
    CHECK(rgb[2] / rgb[0] > 1.1f * (sum[2] / sum[0]));
    float pdf = 0.0f;
    CHECK(ts_pdf(integrated, wi, wo, &pdf) == TS_OK);
    CHECK(pdf > 0.0f);

    /* Rows out of order, a count without rows. */
    const float decreasing[6] = {0.5f, 1.0f, 2.0f, 0.4f, 1.0f, 2.0f};
    given.eta_rows = decreasing;
    given.eta_row_count = 2;
    CHECK(ts_material_new(tables, &given) == NULL);
    CHECK(strstr(ts_last_error(), "eta_rows[].lambda = 0.4") != NULL);
    given.eta_rows = NULL;
    CHECK(ts_material_new(tables, &given) == NULL);
    CHECK(strstr(ts_last_error(), "eta_row_count = 2") != NULL);
    /* A material file's spectrum cannot be returned in a description... */
    const char *spectrum = "[material]\nbeta = 0.2\np = 1\n"
                           "eta = { lambda = [0.4, 0.5, 0.6], n = [0.5, 1, 1.2], k = [2, 3, 3.5] }\n";
    CHECK(ts_material_desc_from_toml(spectrum, &desc) == TS_ERR_INVALID);
    CHECK(strstr(ts_last_error(), "ts_material_file_from_toml") != NULL);
    /* ...but a material file handle owns its rows. */
    ts_material_file *file = NULL;
    CHECK(ts_material_file_from_toml(spectrum, &file) == TS_OK);
    CHECK(file != NULL);
    ts_material_desc from_file;
    CHECK(ts_material_file_desc(file, &from_file) == TS_OK);
    CHECK(from_file.size == sizeof from_file);
    CHECK(from_file.eta_row_count == 3 && from_file.eta_rows != NULL);
    CHECK(from_file.eta_rows[3] == 0.5f && from_file.eta_rows[8] == 3.5f);
    CHECK(from_file.rgb_mode == TS_RGB_MODE_INTEGRATED); /* a spectrum's default */
    ts_material *filed = ts_material_new(tables, &from_file);
    CHECK(filed != NULL);
    /* The same rows given by hand: the same model. */
    const float by_hand[9] = {0.4f, 0.5f, 2.0f, 0.5f, 1.0f, 3.0f, 0.6f, 1.2f, 3.5f};
    ts_material_desc hand;
    memset(&hand, 0, sizeof hand);
    hand.size = sizeof hand;
    hand.beta = 0.2f;
    hand.p = 1.0f;
    hand.b = 1.0f;
    hand.c = 2.0f;
    hand.eta_rows = by_hand;
    hand.eta_row_count = 3;
    ts_material *manual = ts_material_new(tables, &hand);
    CHECK(manual != NULL);
    float a[3] = {0}, b[3] = {1};
    CHECK(ts_eval_rgb(filed, wi, wo, a) == TS_OK);
    CHECK(ts_eval_rgb(manual, wi, wo, b) == TS_OK);
    CHECK(memcmp(a, b, sizeof a) == 0 && a[0] > 0.0f);
    ts_material_free(manual);
    ts_material_free(filed);
    ts_material_file_free(file);
    ts_material_file_free(NULL);
    /* Refusals leave *out unchanged. */
    ts_material_file *untouched = (ts_material_file *)&from_file;
    CHECK(ts_material_file_from_toml("[material\n", &untouched) == TS_ERR_PARSE);
    CHECK(ts_material_file_from_toml("[material]\nbeta = 20\np = 1\neta = [[1, 2], [1, 2], [1, 2]]\n",
                                     &untouched) == TS_ERR_INVALID);
    CHECK(strstr(ts_last_error(), "beta = 20") != NULL);
    CHECK(untouched == (ts_material_file *)&from_file);
    CHECK(ts_material_file_from_toml(NULL, &untouched) == TS_ERR_NULL);
    CHECK(ts_material_file_from_toml(spectrum, NULL) == TS_ERR_NULL);
    CHECK(ts_material_file_desc(NULL, &from_file) == TS_ERR_NULL);

    ts_material_free(integrated);
    ts_material_free(paper);
    ts_material_free(copied);
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
