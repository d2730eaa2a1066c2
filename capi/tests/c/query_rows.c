/*
 * The C API against `generator query brdf` (the runtime's f32 model, one
 * wavelength per row): both evaluate the same f32 path, so they must agree
 * within 1e-6 relative.
 *
 *   query_rows rows M P SEED > in.csv    M random materials, P random
 *                                        direction pairs each, one CSV row
 *                                        per channel (3 M P rows)
 *   generator query brdf < in.csv > out.csv
 *   query_rows compare out.csv M P       rebuilds each material through
 *                                        ts_material_new and compares
 *                                        ts_eval_rgb with the `table` column
 *
 * Materials are few and pairs many because building a material is what
 * valgrind makes slow (≈0.3 s each).
 */
#include "twoscale.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static uint64_t state;

/* splitmix64 */
static double uniform(void) {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (double)(z >> 11) * 0x1.0p-53;
}

static float in(double lo, double hi) { return (float)(lo + (hi - lo) * uniform()); }

static float log_in(double lo, double hi) { return (float)(lo * pow(hi / lo, uniform())); }

static void direction(float w[3]) {
    double z = 2.0 * uniform() - 1.0, phi = 6.283185307179586 * uniform();
    double r = sqrt(1.0 - z * z);
    w[0] = (float)(r * cos(phi));
    w[1] = (float)(r * sin(phi));
    w[2] = (float)z;
}

static int rows(long n, long pairs) {
    float lambda[3];
    if (ts_rgb_wavelengths(lambda) != TS_OK) {
        fprintf(stderr, "ts_rgb_wavelengths: %s\n", ts_last_error());
        return 1;
    }
    /* %.9g prints an f32 exactly enough to read back the same f32. */
    printf("sample,pair,channel,beta,p,sigma_s,b,c,n,k,lambda,ix,iy,iz,ox,oy,oz\n");
    for (long s = 0; s < n; s++) {
        float beta = log_in(0.01, 0.6), p = in(0.4, 3.0);
        float sigma_s = uniform() < 0.2 ? 0.0f : log_in(0.003, 0.1);
        float b = log_in(0.5, 15.0), c = in(1.3, 4.0);
        float n_re[3], k_im[3];
        for (int ch = 0; ch < 3; ch++) {
            n_re[ch] = in(0.1, 2.5);
            k_im[ch] = uniform() < 0.2 ? 0.0f : in(0.0, 5.0);
        }
        for (long pair = 0; pair < pairs; pair++) {
            float wi[3], wo[3];
            direction(wi);
            if (wi[2] < 0.0f && uniform() < 0.8) wi[2] = -wi[2];
            if (uniform() < 0.5) {
                /* near the mirror direction, where the lobes peak */
                wo[0] = -wi[0] + in(-0.1, 0.1);
                wo[1] = -wi[1] + in(-0.1, 0.1);
                wo[2] = wi[2];
            } else {
                direction(wo);
                if (wo[2] < 0.0f && uniform() < 0.8) wo[2] = -wo[2];
            }
            for (int ch = 0; ch < 3; ch++)
                printf("%ld,%ld,%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,"
                       "%.9g\n",
                       s, pair, ch, beta, p, sigma_s, b, c, n_re[ch], k_im[ch], lambda[ch], wi[0],
                       wi[1], wi[2], wo[0], wo[1], wo[2]);
        }
    }
    return 0;
}

enum { SAMPLE, PAIR, CHANNEL, BETA, P, SIGMA_S, B, C, N, K, LAMBDA, IX, IY, IZ, OX, OY, OZ, TABLE, COLUMNS };

static int compare(const char *path, long expected) {
    ts_material *m = NULL;
    double current = -1.0;
    static const char *names[COLUMNS] = {"sample", "pair", "channel", "beta", "p", "sigma_s", "b",
                                         "c", "n", "k", "lambda", "ix", "iy", "iz", "ox",
                                         "oy", "oz", "table"};
    FILE *f = fopen(path, "r");
    if (!f) {
        perror(path);
        return 1;
    }
    ts_tables *tables = ts_tables_embedded();
    if (!tables) {
        fprintf(stderr, "ts_tables_embedded: %s\n", ts_last_error());
        return 1;
    }
    char line[4096];
    int position[COLUMNS];
    if (!fgets(line, sizeof line, f)) {
        fprintf(stderr, "%s: empty\n", path);
        return 1;
    }
    line[strcspn(line, "\r\n")] = 0;
    for (int c = 0; c < COLUMNS; c++) position[c] = -1;
    {
        int col = 0;
        for (char *tok = strtok(line, ","); tok; tok = strtok(NULL, ","), col++)
            for (int c = 0; c < COLUMNS; c++)
                if (strcmp(tok, names[c]) == 0) position[c] = col;
    }
    for (int c = 0; c < COLUMNS; c++)
        if (position[c] < 0) {
            fprintf(stderr, "%s: no column %s\n", path, names[c]);
            return 1;
        }
    long rows = 0, failures = 0, nonzero = 0;
    double worst = 0.0;
    double group[3][COLUMNS];
    int filled = 0;
    while (fgets(line, sizeof line, f)) {
        double field[64];
        int count = 0;
        for (char *tok = strtok(line, ",\r\n"); tok && count < 64; tok = strtok(NULL, ",\r\n"))
            field[count++] = strtod(tok, NULL);
        double row[COLUMNS];
        for (int c = 0; c < COLUMNS; c++) row[c] = position[c] < count ? field[position[c]] : NAN;
        if ((int)row[CHANNEL] != filled) {
            fprintf(stderr, "row %ld: channel %g out of order (rows dropped by the query?)\n",
                    rows, row[CHANNEL]);
            return 1;
        }
        memcpy(group[filled++], row, sizeof row);
        rows++;
        if (filled < 3) continue;
        filled = 0;
        const double *g = group[0];
        if (g[SAMPLE] != current) {
            /* a new material: its parameters are on each of its rows */
            ts_material_free(m);
            ts_material_desc desc;
            memset(&desc, 0, sizeof desc); /* conductor, the paper's options */
            desc.size = sizeof desc;
            desc.beta = (float)g[BETA];
            desc.p = (float)g[P];
            desc.sigma_s = (float)g[SIGMA_S];
            desc.b = (float)g[B];
            desc.c = (float)g[C];
            for (int ch = 0; ch < 3; ch++) {
                desc.eta_re[ch] = (float)group[ch][N];
                desc.eta_im[ch] = (float)group[ch][K];
            }
            m = ts_material_new(tables, &desc);
            current = g[SAMPLE];
            if (!m) {
                fprintf(stderr, "sample %g: ts_material_new: %s\n", g[SAMPLE], ts_last_error());
                return 1;
            }
        }
        float wi[3] = {(float)g[IX], (float)g[IY], (float)g[IZ]};
        float wo[3] = {(float)g[OX], (float)g[OY], (float)g[OZ]};
        float out[3];
        if (ts_eval_rgb(m, wi, wo, out) != TS_OK) {
            fprintf(stderr, "sample %g: ts_eval_rgb: %s\n", g[SAMPLE], ts_last_error());
            return 1;
        }
        for (int ch = 0; ch < 3; ch++) {
            double expected_value = (float)group[ch][TABLE], got = out[ch];
            double scale = fmax(fabs(expected_value), fabs(got));
            double rel = scale > 0.0 ? fabs(got - expected_value) / scale : 0.0;
            if (!(rel <= 1e-6) || !isfinite(got)) {
                failures++;
                fprintf(stderr, "sample %g pair %g channel %d: C API %.9g, query %.9g (rel %.3g)\n",
                        g[SAMPLE], g[PAIR], ch, got, expected_value, rel);
            }
            if (got > 0.0) nonzero++;
            if (rel > worst) worst = rel;
        }
    }
    ts_material_free(m);
    fclose(f);
    ts_tables_free(tables);
    printf("%ld rows, %ld nonzero, max relative difference %.3g, %ld over 1e-6\n", rows,
           nonzero, worst, failures);
    if (rows != 3 * expected) {
        fprintf(stderr, "expected %ld rows, read %ld\n", 3 * expected, rows);
        return 1;
    }
    /* Most pairs are above the horizon: a run of zeros would test nothing. */
    if (nonzero < rows / 2) {
        fprintf(stderr, "only %ld of %ld values are positive\n", nonzero, rows);
        return 1;
    }
    return failures ? 1 : 0;
}

int main(int argc, char **argv) {
    if (argc == 5 && strcmp(argv[1], "rows") == 0) {
        state = strtoull(argv[4], NULL, 10);
        return rows(strtol(argv[2], NULL, 10), strtol(argv[3], NULL, 10));
    }
    if (argc == 5 && strcmp(argv[1], "compare") == 0)
        return compare(argv[2], strtol(argv[3], NULL, 10) * strtol(argv[4], NULL, 10));
    fprintf(stderr, "usage: %s rows M P SEED | compare FILE M P\n", argv[0]);
    return 2;
}
