/*
 * The C API's contract: the happy paths agree with each other, and misuse
 * (NULL pointers, misaligned or truncated buffers, unknown names, NaN
 * parameters) is a status code with a message, never a crash. Run under
 * valgrind memcheck in CI.
 *
 *   misuse TABLES_DIR
 */
#include "twoscale.h"

#include <math.h>
#include <pthread.h>
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

/* `code` was returned and the last error has that code and names `part`. */
#define EXPECT_ERROR(code, expected, part)                                            \
    do {                                                                              \
        int got_ = (code);                                                            \
        if (got_ != (expected) || ts_last_status() != (expected) ||                   \
            !strstr(ts_last_error(), (part))) {                                       \
            fprintf(stderr, "%s:%d: %s returned %d (want %d), last %d: '%s' (want '%s')\n", \
                    __FILE__, __LINE__, #code, got_, (expected), ts_last_status(),    \
                    ts_last_error(), (part));                                         \
            failures++;                                                               \
        }                                                                             \
    } while (0)

/* A NULL handle, with the last error's code and message part. */
#define EXPECT_NULL(call, expected, part)                                             \
    do {                                                                              \
        void *h_ = (void *)(call);                                                    \
        if (h_ != NULL || ts_last_status() != (expected) ||                           \
            !strstr(ts_last_error(), (part))) {                                       \
            fprintf(stderr, "%s:%d: %s gave %p, last %d: '%s' (want NULL, %d, '%s')\n", \
                    __FILE__, __LINE__, #call, h_, ts_last_status(), ts_last_error(), \
                    (expected), (part));                                              \
            failures++;                                                               \
        }                                                                             \
    } while (0)

static unsigned char *read_file(const char *dir, const char *name, size_t *len) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "rb");
    if (!f) {
        perror(path);
        exit(2);
    }
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    /* one spare byte in front, to hand the library a misaligned copy */
    unsigned char *buf = malloc((size_t)size + 1);
    if (!buf || fread(buf + 1, 1, (size_t)size, f) != (size_t)size) {
        fprintf(stderr, "%s: read failed\n", path);
        exit(2);
    }
    fclose(f);
    *len = (size_t)size;
    return buf;
}

static const float WI[3] = {0.6f, 0.1f, 0.8f};
static const float WO[3] = {-0.55f, -0.05f, 0.83f};

static void *other_thread(void *arg) {
    (void)arg;
    /* A fresh thread has no failure of its own... */
    int fresh = ts_last_status() == TS_OK && strcmp(ts_last_error(), "") == 0;
    /* ...and its failures stay its own. */
    ts_material_free(ts_material_preset(NULL, "gold-rough"));
    return (void *)(size_t)(fresh && ts_last_status() == TS_ERR_NULL);
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: %s TABLES_DIR\n", argv[0]);
        return 2;
    }
    const char *dir = argv[1];

    /* Happy paths: the three ways to get tables give the same values. */
    ts_tables *embedded = ts_tables_embedded();
    CHECK(embedded != NULL);
    ts_tables *opened = ts_tables_open(dir);
    CHECK(opened != NULL);
    const char *files[5] = {"t1-smith-g1.tbl", "t2-sigma-ratio.tbl", "t3-convolution.tbl",
                            "t5-diffuse-fresnel.tbl", "t6-albedo.tbl"};
    unsigned char *buf[5];
    size_t len[5];
    for (int k = 0; k < 5; k++) buf[k] = read_file(dir, files[k], &len[k]);
    /* buf[k] + 1 is deliberately not 64-byte aligned: the library copies. */
    ts_table_bytes bytes = {buf[0] + 1, len[0], buf[1] + 1, len[1], buf[2] + 1,
                            len[2],     buf[3] + 1, len[3], buf[4] + 1, len[4]};
    ts_tables *copied = ts_tables_from_bytes(&bytes);
    CHECK(copied != NULL);

    CHECK(ts_preset_count() > 0);
    CHECK(ts_preset_name(ts_preset_count()) == NULL);
    for (size_t p = 0; p < ts_preset_count(); p++) {
        const char *name = ts_preset_name(p);
        ts_material *m[3] = {ts_material_preset(embedded, name),
                             ts_material_preset(opened, name),
                             ts_material_preset(copied, name)};
        ts_material_desc desc;
        CHECK(ts_material_desc_preset(name, &desc) == TS_OK);
        ts_material *from_desc = ts_material_new(copied, &desc);
        CHECK(m[0] && m[1] && m[2] && from_desc);
        if (!(m[0] && m[1] && m[2] && from_desc)) continue;
        float ref[3], out[3];
        CHECK(ts_eval_rgb(m[0], WI, WO, ref) == TS_OK);
        CHECK(ref[0] > 0.0f && ref[1] > 0.0f && ref[2] > 0.0f && isfinite(ref[0]));
        for (int k = 1; k < 3; k++) {
            CHECK(ts_eval_rgb(m[k], WI, WO, out) == TS_OK);
            CHECK(memcmp(ref, out, sizeof out) == 0);
        }
        CHECK(ts_eval_rgb(from_desc, WI, WO, out) == TS_OK);
        CHECK(memcmp(ref, out, sizeof out) == 0);

        /* A sample's pdf and value are ts_pdf's and ts_eval_rgb's. */
        const float u[3] = {0.3f, 0.6f, 0.2f};
        ts_sample s;
        CHECK(ts_sample_rgb(m[0], WI, u, &s) == TS_OK);
        CHECK(s.pdf > 0.0f && s.wo[2] > 0.0f);
        float pdf, value[3];
        CHECK(ts_pdf(m[0], WI, s.wo, &pdf) == TS_OK);
        CHECK(pdf == s.pdf);
        CHECK(ts_eval_rgb(m[0], WI, s.wo, value) == TS_OK);
        CHECK(memcmp(value, s.value, sizeof value) == 0);
        /* Below the horizon: no sample, not an error. */
        const float below[3] = {0.3f, 0.0f, -0.5f};
        CHECK(ts_sample_rgb(m[0], below, u, &s) == TS_OK && s.pdf == 0.0f);

        /* Batches equal single calls, also in place (out aliasing wi). */
        enum { N = 5 };
        float wi[3 * N], wo[3 * N], us[3 * N], batch[3 * N], pdfs[N];
        ts_sample samples[N];
        for (int j = 0; j < 3 * N; j++) {
            wi[j] = WI[j % 3] + 0.05f * (float)(j / 3);
            wo[j] = WO[j % 3] - 0.04f * (float)(j / 3);
            us[j] = (float)((j * 7) % 10) / 10.0f;
        }
        CHECK(ts_eval_rgb_batch(m[0], N, wi, wo, batch) == TS_OK);
        CHECK(ts_pdf_batch(m[0], N, wi, wo, pdfs) == TS_OK);
        CHECK(ts_sample_rgb_batch(m[0], N, wi, us, samples) == TS_OK);
        for (int j = 0; j < N; j++) {
            CHECK(ts_eval_rgb(m[0], wi + 3 * j, wo + 3 * j, out) == TS_OK);
            CHECK(memcmp(out, batch + 3 * j, sizeof out) == 0);
            CHECK(ts_pdf(m[0], wi + 3 * j, wo + 3 * j, &pdf) == TS_OK && pdf == pdfs[j]);
            CHECK(ts_sample_rgb(m[0], wi + 3 * j, us + 3 * j, &s) == TS_OK);
            CHECK(memcmp(&s, &samples[j], sizeof s) == 0);
        }
        float in_place[3 * N];
        memcpy(in_place, wi, sizeof wi);
        CHECK(ts_eval_rgb_batch(m[0], N, in_place, wo, in_place) == TS_OK);
        CHECK(memcmp(in_place, batch, sizeof batch) == 0);
        CHECK(ts_eval_rgb_batch(m[0], 0, NULL, NULL, NULL) == TS_ERR_NULL);

        for (int k = 0; k < 3; k++) ts_material_free(m[k]);
        ts_material_free(from_desc);
    }

    /* Materials outlive their tables handle (reference-counted). */
    ts_material *survivor = ts_material_preset(copied, ts_preset_name(0));
    ts_tables_free(copied);
    float out[3];
    CHECK(survivor && ts_eval_rgb(survivor, WI, WO, out) == TS_OK && out[0] > 0.0f);
    ts_material_free(survivor);

    /* NULL pointers. */
    ts_material *m = ts_material_preset(embedded, "gold-rough");
    CHECK(m != NULL);
    EXPECT_NULL(ts_tables_open(NULL), TS_ERR_NULL, "dir");
    EXPECT_NULL(ts_tables_from_bytes(NULL), TS_ERR_NULL, "bytes");
    EXPECT_NULL(ts_material_preset(NULL, "gold-rough"), TS_ERR_NULL, "tables");
    EXPECT_NULL(ts_material_preset(embedded, NULL), TS_ERR_NULL, "name");
    EXPECT_NULL(ts_material_new(embedded, NULL), TS_ERR_NULL, "desc");
    EXPECT_NULL(ts_material_new(NULL, NULL), TS_ERR_NULL, "tables");
    EXPECT_ERROR(ts_eval_rgb(NULL, WI, WO, out), TS_ERR_NULL, "material");
    EXPECT_ERROR(ts_eval_rgb(m, NULL, WO, out), TS_ERR_NULL, "wi");
    EXPECT_ERROR(ts_eval_rgb(m, WI, NULL, out), TS_ERR_NULL, "wo");
    EXPECT_ERROR(ts_eval_rgb(m, WI, WO, NULL), TS_ERR_NULL, "out");
    EXPECT_ERROR(ts_pdf(m, WI, WO, NULL), TS_ERR_NULL, "pdf");
    EXPECT_ERROR(ts_sample_rgb(m, WI, WI, NULL), TS_ERR_NULL, "out");
    EXPECT_ERROR(ts_rgb_wavelengths(NULL), TS_ERR_NULL, "out");
    EXPECT_ERROR(ts_material_desc_preset("gold-rough", NULL), TS_ERR_NULL, "out");
    ts_tables_free(NULL);
    ts_material_free(NULL);

    /* Misaligned float arrays. */
    float storage[8] = {0};
    float *misaligned = (float *)((char *)storage + 1);
    EXPECT_ERROR(ts_eval_rgb(m, misaligned, WO, out), TS_ERR_MISALIGNED, "wi");
    EXPECT_ERROR(ts_eval_rgb(m, WI, WO, misaligned), TS_ERR_MISALIGNED, "out");
    EXPECT_ERROR(ts_pdf(m, WI, WO, misaligned), TS_ERR_MISALIGNED, "pdf");

    /* Non-finite inputs, named; a failing batch says which entry. */
    const float nan_dir[3] = {NAN, 0.0f, 1.0f}, inf_dir[3] = {0.0f, 0.0f, INFINITY};
    EXPECT_ERROR(ts_eval_rgb(m, nan_dir, WO, out), TS_ERR_INVALID, "wi");
    EXPECT_ERROR(ts_pdf(m, WI, inf_dir, out), TS_ERR_INVALID, "wo");
    EXPECT_ERROR(ts_sample_rgb(m, WI, nan_dir, (ts_sample *)storage), TS_ERR_INVALID, "u");
    /* Uniforms outside [0, 1), 1 included, are refused; its edges are not. */
    {
        const float ones[3] = {0.5f, 1.0f, 0.5f}, negative[3] = {-0.25f, 0.5f, 0.5f};
        const float edge[3] = {0.0f, 0.99999994f, 0.0f};
        ts_sample s;
        EXPECT_ERROR(ts_sample_rgb(m, WI, ones, &s), TS_ERR_INVALID, "outside [0, 1)");
        EXPECT_ERROR(ts_sample_rgb(m, WI, negative, &s), TS_ERR_INVALID, "u (entry 0)");
        CHECK(ts_sample_rgb(m, WI, edge, &s) == TS_OK);
        float wi2[6] = {WI[0], WI[1], WI[2], WI[0], WI[1], WI[2]};
        float u2[6] = {0.3f, 0.6f, 0.2f, 0.3f, 1.5f, 0.2f};
        ts_sample s2[2];
        EXPECT_ERROR(ts_sample_rgb_batch(m, 2, wi2, u2, s2), TS_ERR_INVALID, "u (entry 1)");
    }
    {
        float wi2[6] = {WI[0], WI[1], WI[2], NAN, 0.0f, 1.0f}, wo2[6], out2[6];
        memcpy(wo2, WO, sizeof WO);
        memcpy(wo2 + 3, WO, sizeof WO);
        EXPECT_ERROR(ts_eval_rgb_batch(m, 2, wi2, wo2, out2), TS_ERR_INVALID, "entry 1");
    }
    EXPECT_ERROR(ts_eval_rgb_batch(m, (size_t)-1, WI, WO, out), TS_ERR_INVALID, "too large");

    /* Unknown names list the presets. */
    EXPECT_NULL(ts_material_preset(embedded, "gold"), TS_ERR_UNKNOWN_MATERIAL, "gold-rough");
    ts_material_desc desc;
    EXPECT_ERROR(ts_material_desc_preset("unobtainium", &desc), TS_ERR_UNKNOWN_MATERIAL,
                 "unobtainium");
    EXPECT_NULL(ts_material_preset(embedded, "\xff\xfe"), TS_ERR_INVALID, "UTF-8");

    /* NaN and infinite parameters, unknown enumeration values. */
    CHECK(ts_material_desc_preset("gold-rough", &desc) == TS_OK);
    ts_material_desc bad = desc;
    bad.beta = NAN;
    EXPECT_NULL(ts_material_new(embedded, &bad), TS_ERR_INVALID, "beta");
    bad = desc;
    bad.eta_rows = NULL; /* the channels' index is read only without rows */
    bad.eta_row_count = 0;
    bad.eta_im[2] = INFINITY;
    EXPECT_NULL(ts_material_new(embedded, &bad), TS_ERR_INVALID, "eta_im[2]");
    bad = desc;
    bad.base = 3;
    EXPECT_NULL(ts_material_new(embedded, &bad), TS_ERR_INVALID, "base = 3");
    bad = desc;
    bad.halo_weight = -1;
    EXPECT_NULL(ts_material_new(embedded, &bad), TS_ERR_INVALID,
                "halo_weight = -1 is not one of TS_HALO_PRINTED (0), TS_HALO_INCIDENT (1)");
    bad = desc;
    bad.multiple_scattering = 2;
    EXPECT_NULL(ts_material_new(embedded, &bad), TS_ERR_INVALID,
                "multiple_scattering = 2 is not one of TS_MULTIPLE_NONE (0), "
                "TS_MULTIPLE_KULLA_CONTY (1)");
    bad = desc;
    bad.masking = 1; /* by name: TS_MASKING_HEIGHT_CORRELATED */
    CHECK(TS_MASKING_HEIGHT_CORRELATED == 1);
    {
        ts_material *hc = ts_material_new(embedded, &bad);
        CHECK(hc != NULL);
        ts_material_free(hc);
    }

    /* Values outside the runtime's domain (Material::validate), with its message. */
    CHECK(desc.base == TS_BASE_CONDUCTOR);
    bad = desc;
    bad.beta = -0.1f;
    EXPECT_NULL(ts_material_new(embedded, &bad), TS_ERR_INVALID,
                "ts_material_desc.beta = -0.1: must be in [0.0001, 10]");
    bad = desc;
    bad.p = 100.0f;
    EXPECT_NULL(ts_material_new(embedded, &bad), TS_ERR_INVALID,
                "ts_material_desc.p = 100: must be in [0.2, 5]");
    bad = desc;
    bad.c = 0.5f;
    EXPECT_NULL(ts_material_new(embedded, &bad), TS_ERR_INVALID,
                "ts_material_desc.c = 0.5: must be finite and > 1");
    bad = desc;
    bad.sigma_s = -1.0f;
    EXPECT_NULL(ts_material_new(embedded, &bad), TS_ERR_INVALID,
                "ts_material_desc.sigma_s = -1: must be finite and");
    bad = desc;
    bad.b = -5.0f;
    EXPECT_NULL(ts_material_new(embedded, &bad), TS_ERR_INVALID,
                "ts_material_desc.b = -5: must be finite and");
    bad = desc;
    bad.base_albedo = 0.5f;
    EXPECT_NULL(ts_material_new(embedded, &bad), TS_ERR_INVALID,
                "ts_material_desc.base_albedo = 0.5");
    bad = desc;
    bad.eta_rows = NULL;
    bad.eta_row_count = 0;
    bad.eta_im[1] = -1.0f;
    EXPECT_NULL(ts_material_new(embedded, &bad), TS_ERR_INVALID, "ts_material_desc.eta_im[1] = -1");

    /* The caller's layout: size must be sizeof(ts_material_desc). */
    CHECK(desc.size == sizeof desc);
    bad = desc;
    bad.size = 0;
    EXPECT_NULL(ts_material_new(embedded, &bad), TS_ERR_INVALID, "ts_material_desc.size = 0");
    bad = desc;
    bad.size = (uint32_t)sizeof desc + 4;
    EXPECT_NULL(ts_material_new(embedded, &bad), TS_ERR_INVALID, "sizeof(ts_material_desc)");

    /* The version is MAJOR.MINOR.PATCH. */
    {
        unsigned major, minor, patch;
        char end;
        CHECK(ts_version() != NULL &&
              sscanf(ts_version(), "%u.%u.%u%c", &major, &minor, &patch, &end) == 3);
    }

    /* Truncated, corrupted, swapped and empty table bytes, and a missing directory. */
    ts_table_bytes t = bytes;
    t.sigma_ratio_len = len[1] - 1;
    EXPECT_NULL(ts_tables_from_bytes(&t), TS_ERR_TABLES, "t2-sigma-ratio.tbl");
    t = bytes;
    t.convolution_len = 100;
    EXPECT_NULL(ts_tables_from_bytes(&t), TS_ERR_TABLES, "t3-convolution.tbl");
    t = bytes;
    t.smith_len = 0;
    EXPECT_NULL(ts_tables_from_bytes(&t), TS_ERR_TABLES, "t1-smith-g1.tbl");
    t = bytes;
    t.diffuse_fresnel = NULL;
    EXPECT_NULL(ts_tables_from_bytes(&t), TS_ERR_NULL, "t5-diffuse-fresnel.tbl");
    t = bytes;
    t.albedo_len = len[4] - 8;
    EXPECT_NULL(ts_tables_from_bytes(&t), TS_ERR_TABLES, "t6-albedo.tbl");
    t = bytes;
    t.smith = bytes.diffuse_fresnel;
    t.smith_len = bytes.diffuse_fresnel_len;
    EXPECT_NULL(ts_tables_from_bytes(&t), TS_ERR_TABLES, "t1-smith-g1.tbl");
    buf[3][1 + len[3] / 2] ^= 0x40; /* one flipped bit in T5's data */
    EXPECT_NULL(ts_tables_from_bytes(&bytes), TS_ERR_TABLES, "t5-diffuse-fresnel.tbl");
    EXPECT_NULL(ts_tables_open("/nonexistent/twoscale"), TS_ERR_IO, "/nonexistent/twoscale");

    /* The last error is per thread. */
    EXPECT_NULL(ts_material_preset(embedded, "gold"), TS_ERR_UNKNOWN_MATERIAL, "gold");
    pthread_t thread;
    void *ok = NULL;
    CHECK(pthread_create(&thread, NULL, other_thread, NULL) == 0);
    CHECK(pthread_join(thread, &ok) == 0);
    CHECK(ok == (void *)1);
    CHECK(ts_last_status() == TS_ERR_UNKNOWN_MATERIAL);

    ts_material_free(m);
    ts_tables_free(embedded);
    ts_tables_free(opened);
    for (int k = 0; k < 5; k++) free(buf[k]);
    if (failures) {
        fprintf(stderr, "%d checks failed\n", failures);
        return 1;
    }
    printf("misuse: all checks passed\n");
    return 0;
}
