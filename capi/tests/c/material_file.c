/*
 * Material files (TOML, docs/fitting.md) read by ts_material_desc_from_toml
 * and ts_material_desc_from_toml_file: the fields they give, the material
 * they make, and each fault as its status code and message. Run under
 * valgrind memcheck in CI.
 *
 *   material_file check DIR   self-test (DIR: a writable scratch directory)
 *   material_file eval FILE   directions "ix iy iz ox oy oz" per line on
 *                             stdin, rho per channel as C99 hex floats on
 *                             stdout; a refused file prints
 *                             "error CODE: MESSAGE" and exits with 3
 *                             (python/tests/test_material_file.py compares
 *                             both with Python and the generator)
 */
#include "twoscale.h"

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

/* `code` was returned and the last error has that code and message `text`. */
#define EXPECT_MESSAGE(code, expected, text)                                          \
    do {                                                                              \
        int got_ = (code);                                                            \
        if (got_ != (expected) || ts_last_status() != (expected) ||                   \
            strcmp(ts_last_error(), (text)) != 0) {                                   \
            fprintf(stderr, "%s:%d: %s returned %d (want %d): '%s' (want '%s')\n",    \
                    __FILE__, __LINE__, #code, got_, (expected), ts_last_error(),     \
                    (text));                                                          \
            failures++;                                                               \
        }                                                                             \
    } while (0)

/* As EXPECT_MESSAGE, the message containing `part`. */
#define EXPECT_PART(code, expected, part)                                             \
    do {                                                                              \
        int got_ = (code);                                                            \
        if (got_ != (expected) || ts_last_status() != (expected) ||                   \
            !strstr(ts_last_error(), (part))) {                                       \
            fprintf(stderr, "%s:%d: %s returned %d (want %d): '%s' (want '%s')\n",    \
                    __FILE__, __LINE__, #code, got_, (expected), ts_last_error(),     \
                    (part));                                                          \
            failures++;                                                               \
        }                                                                             \
    } while (0)

/* What `python -m twoscale.fit` writes: [material] and [metrics]. */
static const char FIT[] =
    "[material]\n"
    "beta = 0.0598\n"
    "p = 1.25\n"
    "sigma_s = 0.0273\n"
    "b = 4.8418\n"
    "c = 2.0\n"
    "eta = [[0.163, 3.56], [0.584, 2.15], [1.403, 1.925]]\n"
    "base = \"conductor\"\n"
    "lambertian = 0.02\n"
    "\n"
    "[metrics]\n"
    "rmse = [0.01, 0.02, 0.03]\n"
    "smape = 0.1\n";

static int write_text(const char *path, const char *text) {
    FILE *f = fopen(path, "wb");
    if (!f) return 0;
    int ok = fputs(text, f) >= 0;
    return fclose(f) == 0 && ok;
}

static int check(const char *dir) {
    ts_material_desc desc;
    memset(&desc, 0, sizeof desc);
    CHECK(ts_material_desc_from_toml(FIT, &desc) == TS_OK);
    CHECK(desc.size == sizeof(ts_material_desc));
    CHECK(desc.beta == 0.0598f && desc.p == 1.25f && desc.sigma_s == 0.0273f);
    CHECK(desc.b == 4.8418f && desc.c == 2.0f && desc.lambertian == 0.02f);
    CHECK(desc.base == TS_BASE_CONDUCTOR && desc.base_albedo == 0.0f);
    CHECK(desc.eta_re[0] == 0.163f && desc.eta_im[0] == 3.56f);
    CHECK(desc.eta_re[2] == 1.403f && desc.eta_im[2] == 1.925f);
    CHECK(desc.masking == TS_MASKING_SEPARABLE && desc.colour == TS_COLOUR_PHYSICAL);

    /* The same text from a file gives the same description. */
    char path[4096];
    snprintf(path, sizeof path, "%s/fit.toml", dir);
    CHECK(write_text(path, FIT));
    ts_material_desc from_file;
    memset(&from_file, 0, sizeof from_file);
    CHECK(ts_material_desc_from_toml_file(path, &from_file) == TS_OK);
    CHECK(memcmp(&desc, &from_file, sizeof desc) == 0);

    /* It makes a material. */
    ts_tables *tables = ts_tables_embedded();
    CHECK(tables != NULL);
    ts_material *m = tables ? ts_material_new(tables, &desc) : NULL;
    CHECK(m != NULL);
    const float wi[3] = {0.5f, 0.0f, 0.866f}, wo[3] = {-0.45f, 0.05f, 0.89f};
    float rgb[3] = {0};
    if (m) {
        CHECK(ts_eval_rgb(m, wi, wo, rgb) == TS_OK);
        CHECK(rgb[0] > rgb[1] && rgb[1] > rgb[2] && rgb[2] > 0.0f);
    }
    ts_material_free(m);
    ts_tables_free(tables);

    /* Options and a base layer by name. */
    const char *plastic =
        "[material]\nbeta = 0.1\np = 1\neta = [[1.5, 0], [1.5, 0], [1.5, 0]]\n"
        "base = \"plastic\"\nalbedo = 0.8\nmasking = \"height-correlated\"\n"
        "halo_weight = \"incident\"\n";
    CHECK(ts_material_desc_from_toml(plastic, &desc) == TS_OK);
    CHECK(desc.base == TS_BASE_PLASTIC && desc.base_albedo == 0.8f);
    CHECK(desc.masking == TS_MASKING_HEIGHT_CORRELATED && desc.halo_weight == TS_HALO_INCIDENT);
    CHECK(desc.sigma_s == 0.0f && desc.b == 1.0f && desc.c == 2.0f); /* the defaults */
    CHECK(desc.multiple_scattering == TS_MULTIPLE_NONE); /* the default */

    /* The energy compensation by name: a rough gold gains at every channel. */
    const char *rough =
        "[material]\nbeta = 0.8\np = 1\neta = [[0.163, 3.56], [0.584, 2.15], [1.403, 1.925]]\n"
        "multiple_scattering = \"kulla-conty\"\n";
    CHECK(ts_material_desc_from_toml(rough, &desc) == TS_OK);
    CHECK(desc.multiple_scattering == TS_MULTIPLE_KULLA_CONTY);
    {
        ts_tables *t = ts_tables_embedded();
        ts_material_desc off = desc;
        off.multiple_scattering = TS_MULTIPLE_NONE;
        ts_material *on_m = t ? ts_material_new(t, &desc) : NULL;
        ts_material *off_m = t ? ts_material_new(t, &off) : NULL;
        CHECK(on_m != NULL && off_m != NULL);
        float on_rgb[3] = {0}, off_rgb[3] = {0};
        if (on_m && off_m) {
            CHECK(ts_eval_rgb(on_m, wi, wo, on_rgb) == TS_OK);
            CHECK(ts_eval_rgb(off_m, wi, wo, off_rgb) == TS_OK);
            for (int c = 0; c < 3; c++) CHECK(on_rgb[c] > off_rgb[c] && off_rgb[c] > 0.0f);
        }
        ts_material_free(on_m);
        ts_material_free(off_m);
        ts_tables_free(t);
    }

    /* Faults: each a status code and the message Rust and Python give. */
    ts_material_desc before = desc;
    EXPECT_MESSAGE(
        ts_material_desc_from_toml("[material]\nbeta = 20\np = 1\n"
                                   "eta = [[1.5, 0], [1.5, 0], [1.5, 0]]\n",
                                   &desc),
        TS_ERR_INVALID, "[material] beta = 20: must be in [0.0001, 10]");
    EXPECT_MESSAGE(
        ts_material_desc_from_toml("[material]\nbeta = 0.1\np = 1\n"
                                   "eta = [[1.5, 0], [1.5, 0], [1.5, 0]]\nalbedo = 0.5\n",
                                   &desc),
        TS_ERR_INVALID,
        "[material] albedo is for the base layers with a diffuse albedo, not 'conductor'");
    EXPECT_MESSAGE(
        ts_material_desc_from_toml("[material]\nbeta = 0.1\np = 1\neta = [[1.5, 0]]\n", &desc),
        TS_ERR_INVALID, "[material] eta must be three (n, k) pairs (red, green, blue), got 1");
    EXPECT_MESSAGE(
        ts_material_desc_from_toml("[material]\nbeta = 0.1\np = 1\n"
                                   "eta = [[1.5, 0], [1.5, 0], [1.5, 0]]\ncolour = \"grey\"\n",
                                   &desc),
        TS_ERR_INVALID, "[material] colour must be one of 'physical' or 'white', got 'grey'");
    EXPECT_PART(
        ts_material_desc_from_toml("[material]\nbeta = 0.1\np = 1\n"
                                   "eta = [[1.5, 0], [1.5, 0], [1.5, 0]]\ncolor = \"white\"\n",
                                   &desc),
        TS_ERR_PARSE, "unknown field `color`");
    EXPECT_PART(ts_material_desc_from_toml("[material]\np = 1\neta = []\n", &desc), TS_ERR_PARSE,
                "missing field `beta`");
    EXPECT_PART(ts_material_desc_from_toml("[material\n", &desc), TS_ERR_PARSE, "line 1");
    EXPECT_PART(ts_material_desc_from_toml(NULL, &desc), TS_ERR_NULL, "toml is NULL");
    EXPECT_PART(ts_material_desc_from_toml(FIT, NULL), TS_ERR_NULL, "out is NULL");
    EXPECT_PART(ts_material_desc_from_toml("\xff", &desc), TS_ERR_INVALID, "not UTF-8");
    CHECK(memcmp(&before, &desc, sizeof desc) == 0); /* unchanged by the failures */

    snprintf(path, sizeof path, "%s/absent.toml", dir);
    EXPECT_PART(ts_material_desc_from_toml_file(path, &desc), TS_ERR_IO, "cannot read");
    EXPECT_PART(ts_material_desc_from_toml_file(NULL, &desc), TS_ERR_NULL, "path is NULL");
    snprintf(path, sizeof path, "%s/bad.toml", dir);
    CHECK(write_text(path, "[material]\nbeta = 0.1\np = 9\neta = [[1, 0], [1, 0], [1, 0]]\n"));
    char want[4200];
    snprintf(want, sizeof want, "%s: [material] p = 9: must be in [0.2, 5]", path);
    EXPECT_MESSAGE(ts_material_desc_from_toml_file(path, &desc), TS_ERR_INVALID, want);
    remove(path);
    snprintf(path, sizeof path, "%s/fit.toml", dir);
    remove(path);

    if (failures) fprintf(stderr, "%d check(s) failed\n", failures);
    else printf("material files: all checks passed\n");
    return failures ? 1 : 0;
}

static int eval(const char *path) {
    ts_material_desc desc;
    int status = ts_material_desc_from_toml_file(path, &desc);
    if (status != TS_OK) {
        printf("error %d: %s\n", status, ts_last_error());
        return 3;
    }
    ts_tables *tables = ts_tables_embedded();
    ts_material *m = tables ? ts_material_new(tables, &desc) : NULL;
    if (!m) {
        printf("error %d: %s\n", ts_last_status(), ts_last_error());
        ts_tables_free(tables);
        return 3;
    }
    float wi[3], wo[3], rgb[3];
    while (scanf("%f %f %f %f %f %f", &wi[0], &wi[1], &wi[2], &wo[0], &wo[1], &wo[2]) == 6) {
        if (ts_eval_rgb(m, wi, wo, rgb) != TS_OK) {
            fprintf(stderr, "ts_eval_rgb: %s\n", ts_last_error());
            status = 1;
            break;
        }
        printf("%a %a %a\n", rgb[0], rgb[1], rgb[2]);
    }
    ts_material_free(m);
    ts_tables_free(tables);
    return status;
}

int main(int argc, char **argv) {
    if (argc == 3 && strcmp(argv[1], "check") == 0) return check(argv[2]);
    if (argc == 3 && strcmp(argv[1], "eval") == 0) return eval(argv[2]);
    fprintf(stderr, "usage: material_file check DIR | material_file eval FILE\n");
    return 2;
}
