//! The C header of `generator export --format c`: per table `<stem>.h` with
//! the arrays as `static const`, the axis constants as macros, one inline
//! function per axis that maps a physical value to its fractional node
//! position, and the interpolation weights the tables use (in the style of
//! Cycles' precomputed tables and Filament's `dfg.inc`). docs/export.md
//! describes the arrays and the lookups.

use std::fmt::Write as _;

use twoscale::tables::format::Mapping;
use twoscale::tables::interp::coordinate_f64;

use super::{Encoded, NamedArray, Source, aux_array, npy};

/// `t1-smith-g1` → `ts_t1_smith_g1`.
pub fn prefix(stem: &str) -> String {
    format!("ts_{}", stem.replace('-', "_"))
}

/// An f32 as a C literal that reads back to the same value.
fn c_float(x: f32) -> String {
    let text = format!("{x:e}");
    format!("{text}f")
}

/// Helpers shared by every header (guarded, so that several headers can be
/// included together).
const COMMON: &str = r#"#ifndef TS_EXPORT_COMMON
#define TS_EXPORT_COMMON
/* Splits a fractional node position u in [0, nodes - 1] into a cell i in
 * [0, nodes - 2] and a fraction t in [0, 1] (the runtime's Axis::locate). */
static inline int ts_cell(float u, int nodes, float *t) {
    int i = (int)floorf(u);
    if (i > nodes - 2) i = nodes - 2;
    if (i < 0) i = 0;
    *t = u - (float)i;
    return i;
}
/* Uniform cubic B-spline weights of coefficients i, i+1, i+2, i+3 at fraction t
 * of cell i (coefficient j sits at node j - 1). */
static inline void ts_bspline_weights(float t, float w[4]) {
    float s = 1.0f - t, t2 = t * t, t3 = t2 * t;
    w[0] = s * s * s / 6.0f;
    w[1] = (3.0f * t3 - 6.0f * t2 + 4.0f) / 6.0f;
    w[2] = (-3.0f * t3 + 3.0f * t2 + 3.0f * t + 1.0f) / 6.0f;
    w[3] = t3 / 6.0f;
}
/* Catmull-Rom weights of nodes i-1, i, i+1, i+2 at fraction t of cell i
 * (T3's parameter axes; the first and last cell use the quadratic through
 * their three nodes instead: docs/export.md). */
static inline void ts_catmull_rom_weights(float t, float w[4]) {
    float t2 = t * t, t3 = t2 * t;
    w[0] = 0.5f * (-t3 + 2.0f * t2 - t);
    w[1] = 0.5f * (3.0f * t3 - 5.0f * t2 + 2.0f);
    w[2] = 0.5f * (-3.0f * t3 + 4.0f * t2 + t);
    w[3] = 0.5f * (t3 - t2);
}
#endif
"#;

/// Writes `values` as the body of a C array initialiser, eight per line.
fn initialiser<T>(out: &mut String, values: &[T], format: impl Fn(&T) -> String) {
    for chunk in values.chunks(8) {
        out.push_str("   ");
        for v in chunk {
            out.push(' ');
            out.push_str(&format(v));
            out.push(',');
        }
        out.push('\n');
    }
}

/// One array as a `static const` definition with a comment on its shape.
fn array(out: &mut String, name: &str, named: &NamedArray, comment: &str) {
    let shape = &named.array.shape;
    let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
    let _ = writeln!(
        out,
        "/* {comment}; shape [{}], C order (last index fastest). */",
        dims.join("][")
    );
    match &named.array.data {
        npy::Data::F32(v) => {
            let _ = writeln!(out, "static const float {name}[{}] = {{", v.len());
            initialiser(out, v, |x| c_float(*x));
        }
        npy::Data::U16(v) => {
            let _ = writeln!(out, "static const uint16_t {name}[{}] = {{", v.len());
            initialiser(out, v, u16::to_string);
        }
    }
    out.push_str("};\n\n");
}

/// The C expression of an axis's coordinate `c(x)`.
fn coordinate_expression(mapping: Mapping, param: f64, param2: f64) -> String {
    match mapping {
        Mapping::Uniform => "x".into(),
        Mapping::Log => "logf(x)".into(),
        Mapping::LogOffset if param2 != 0.0 => format!(
            "logf(x + {}) + {} * x",
            c_float(param as f32),
            c_float(param2 as f32)
        ),
        Mapping::LogOffset => format!("logf(x + {})", c_float(param as f32)),
        Mapping::Power => format!("powf(x, {})", c_float(param as f32)),
    }
}

/// T3's normalised angle in C (double, as the runtime's
/// `twoscale::tables::convolution::normalised_angle`; `P` is the macro prefix of the
/// header's parameters, `p` the function prefix).
pub fn normalised_angle(p: &str, u: &str) -> String {
    format!(
        r#"/* The normalised angle xi in [0, 1] of tau = tan(theta_h) for the (clamped) parameters
 * (u, beta, p): xi = F(min(tau, tau_max)) / F(tau_max), F as in docs/export.md (T3, step 3);
 * in double, as the runtime's twoscale::tables::convolution::normalised_angle. tau < 0 is 0. */
static inline double {p}_asinh_pos(double x) {{
    return log1p(x + x * x / (1.0 + sqrt(1.0 + x * x)));
}}
static inline double {p}_angle_f(double tau, double u, double beta, double p) {{
    double ue = sqrt(u * u + {u}_KERNEL_SCALE_FLOOR * {u}_KERNEL_SCALE_FLOOR);
    double p_eff = p / (1.0 + {u}_NDF_SOFTENING * p / (2.0 * ue * beta));
    double tau_edge = beta * exp(log({u}_NDF_EXPONENT_CAP) / (2.0 * p_eff));
    double fade = 1.0 / (1.0 + (tau_edge / {u}_EDGE_FADE_TAN) * (tau_edge / {u}_EDGE_FADE_TAN));
    if ({u}_EDGE_SOFTENING_FADE > 0.0) {{
        fade *= exp({u}_EDGE_SOFTENING_FADE * log(p_eff / p));
    }}
    double delta = {u}_EDGE_SMOOTHING / (2.0 * ue);
    double secant = sqrt(1.0 + tau * tau);
    double kernel = {p}_asinh_pos(2.0 * ue * tau / secant);
    double horizon = 0.5 * log1p(tau * tau);
    double y = tau > 0.0 ? exp(2.0 * p_eff * log(tau / beta)) : 0.0;
    double ndf = log1p({u}_NDF_EXPONENT_CAP * -expm1(-(y / {u}_NDF_EXPONENT_CAP)));
    double edge = 0.0;
    if (fade > 0.0) {{
        double offset = atan((tau - tau_edge) / (1.0 + tau * tau_edge));
        double beyond = fmin(0.5 * (offset + sqrt(offset * offset + delta * delta)),
                             1.5707963267948966);
        edge = fade * {p}_asinh_pos(2.0 * ue * sin(beyond));
    }}
    return kernel + {u}_HORIZON_WEIGHT * horizon + {u}_EDGE_WEIGHT * edge + {u}_NDF_WEIGHT * ndf;
}}
static inline double {p}_normalised_angle(double tau, double u, double beta, double p) {{
    double t = fmin(fmax(tau, 0.0), {u}_TAU_MAX);
    double xi = {p}_angle_f(t, u, beta, p) / {p}_angle_f({u}_TAU_MAX, u, beta, p);
    return fmin(fmax(xi, 0.0), 1.0);
}}

"#
    )
}

/// Stored value `k` as the C expression `value` (which reads `(k)`) at index `k`.
fn value_at(value: &str, k: &str) -> String {
    value.replace("(k)", &format!("({k})"))
}

/// T1's lookup in C: G1 bilinear in (p, a_scaled), and the asymptote beyond the last node. The C lookups read the header's first exported precision
/// (`value`, the C expression of stored value `k`) as the runtime does
/// (docs/export.md); `p` is the identifier prefix, `u` its upper case.
pub fn smith_g1(p: &str, u: &str, value: &str) -> String {
    let v = |k: &str| value_at(value, k);
    format!(
        r#"/* G1 bilinear in (p, a_scaled) inside the table (a_scaled <= {u}_A_SCALED_HI). */
static inline float {p}_bilinear(float p, float a_scaled) {{
float tp, ta;
int i = ts_cell({p}_p_position(p), {u}_P_NODES, &tp);
int j = ts_cell({p}_a_scaled_position(a_scaled), {u}_A_SCALED_NODES, &ta);
int n = {u}_A_SCALED_NODES;
float v00 = {}, v01 = {};
float v10 = {}, v11 = {};
float g0 = v00 + ta * (v01 - v00), g1 = v10 + ta * (v11 - v10);
return g0 + tp * (g1 - g0);
}}
/* Smith G1 of the EPD at shape p and a = beta * tan(theta) (HP17 38), given
 * k_p = Gamma(3/(2p)) / (pi Gamma(1/p)) (once per material): the table for
 * a_scaled = k_p * a up to its last node, the asymptote Lambda(last) + (a_scaled - last)
 * beyond. a <= 0 or NaN gives 1. */
static inline float {p}_g1(float p, float a, float k_p) {{
if (!(a > 0.0f)) return 1.0f;
float a_scaled = k_p * a;
if (a_scaled <= {u}_A_SCALED_HI) return {p}_bilinear(p, a_scaled);
float g_last = {p}_bilinear(p, {u}_A_SCALED_HI);
float lambda_last = g_last > 0.0f ? fmaxf(1.0f / g_last - 1.0f, 0.0f) : 3.4028235e38f;
return 1.0f / (1.0f + lambda_last + (a_scaled - {u}_A_SCALED_HI));
}}

"#,
        v("i * n + j"),
        v("i * n + j + 1"),
        v("(i + 1) * n + j"),
        v("(i + 1) * n + j + 1")
    )
}

/// T5's lookup in C: the cubic B-spline at η. The C lookups read the header's first exported precision
/// (`value`, the C expression of stored value `k`) as the runtime does
/// (docs/export.md); `p` is the identifier prefix, `u` its upper case.
pub fn diffuse_fresnel(p: &str, u: &str, value: &str) -> String {
    let v = |k: &str| value_at(value, k);
    format!(
        r#"/* F_dr,int(eta): the cubic B-spline at eta clamped to [1, 3], clamped to [0, 1]. */
static inline float {p}_f_dr(float eta) {{
float t, w[4];
int i = ts_cell({p}_eta_position(eta), {u}_ETA_NODES, &t);
ts_bspline_weights(t, w);
float f = w[0] * {} + w[1] * {} + w[2] * {} + w[3] * {};
return fminf(fmaxf(f, 0.0f), 1.0f);
}}

"#,
        v("i"),
        v("i + 1"),
        v("i + 2"),
        v("i + 3")
    )
}

/// T2's lookup in C: the tricubic B-spline times the closed form r0. The C lookups read the header's first exported precision
/// (`value`, the C expression of stored value `k`) as the runtime does
/// (docs/export.md); `p` is the identifier prefix, `u` its upper case.
pub fn sigma_ratio(p: &str, u: &str, value: &str) -> String {
    let v = |k: &str| value_at(value, k);
    format!(
        r#"/* sigma_rel / sigma_s inside the table's domain (B in [0.05, 3000], c in (1, 100]):
 * q = tricubic B-spline at (cos theta_i, B, c), times r0 = sqrt(1 - (1 + B^2)^(-(c-1)/2)).
 * Outside it the runtime applies the rules of runtime/src/tables/sigma_ratio.rs. */
static inline float {p}_sigma_ratio(float cos_theta_i, float big_b, float c) {{
float t0, t1, t2, w0[4], w1[4], w2[4];
int i0 = ts_cell({p}_cos_theta_i_position(cos_theta_i), {u}_COS_THETA_I_NODES, &t0);
int i1 = ts_cell({p}_B_position(big_b), {u}_B_NODES, &t1);
int i2 = ts_cell({p}_c_position(c), {u}_C_NODES, &t2);
int n1 = {u}_B_NODES + 2, n2 = {u}_C_NODES + 2;
ts_bspline_weights(t0, w0);
ts_bspline_weights(t1, w1);
ts_bspline_weights(t2, w2);
float q = 0.0f;
for (int a = 0; a < 4; a++)
    for (int b = 0; b < 4; b++)
        for (int d = 0; d < 4; d++) {{
            int k = ((i0 + a) * n1 + i1 + b) * n2 + i2 + d;
            q += w0[a] * w1[b] * w2[d] * {};
        }}
double bb = big_b, cc = c;
double r0 = sqrt(fmax(-expm1(-(cc - 1.0) / 2.0 * log1p(bb * bb)), 0.0));
return (float)(q * r0);
}}

"#,
        v("k")
    )
}

/// T6's lookup in C: the tricubic B-spline at the incidence and width
/// coordinates of `twoscale::tables::albedo` (computed in double, as the runtime
/// does), channel `masking`. The C lookups read the header's first exported
/// precision (`value`, the C expression of stored value `k`) as the runtime
/// does (docs/export.md); `p` is the identifier prefix, `u` its upper case.
pub fn albedo(p: &str, u: &str, value: &str) -> String {
    let v = |k: &str| value_at(value, k);
    format!(
        r#"/* E(mu; beta, p) of the EPD microfacet lobe with F = 1, masking 0 (separable) or
 * 1 (height-correlated): with k_p = Gamma(3/(2p)) / (pi Gamma(1/p)),
 * y = L/(1+L), L = ln(1 + t), t = sigma tan(theta_i), sigma = s0/(1+s0^2), s0 = (1 + k_p) beta and
 * z = (x-1)/(x+1), x = (k_p beta / {centre})^{exponent}; p clamped to [0.2, 5],
 * the result to [0, 1]. */
static inline float {p}_albedo(float cos_theta_i, float beta, float p, int masking) {{
double pp = fmin(fmax((double)p, 0.2), 5.0);
double kp = tgamma(1.5 / pp) / (3.14159265358979323846 * tgamma(1.0 / pp));
double b = beta > 0.0f ? (double)beta : 0.0;
double s0 = (1.0 + kp) * b, sigma = s0 < 1e150 ? s0 / (1.0 + s0 * s0) : 1.0 / s0;
double c = fmin(fmax((double)cos_theta_i, 0.0), 1.0);
double l = c > 0.0 ? log1p(sigma * sqrt((1.0 - c) * (1.0 + c)) / c) : (sigma > 0.0 ? INFINITY : 0.0);
double y = isfinite(l) ? l / (1.0 + l) : 1.0;
double x = pow(kp * b / {centre}, {exponent});
double z = b > 0.0 ? (isfinite(x) ? (x - 1.0) / (x + 1.0) : 1.0) : -1.0;
float t0, t1, t2, w0[4], w1[4], w2[4];
int i0 = ts_cell({p}_incidence_y_position((float)y), {u}_INCIDENCE_Y_NODES, &t0);
int i1 = ts_cell({p}_width_z_position((float)z), {u}_WIDTH_Z_NODES, &t1);
int i2 = ts_cell({p}_p_position((float)pp), {u}_P_NODES, &t2);
int n1 = {u}_WIDTH_Z_NODES + 2, n2 = {u}_P_NODES + 2;
ts_bspline_weights(t0, w0);
ts_bspline_weights(t1, w1);
ts_bspline_weights(t2, w2);
float e = 0.0f;
for (int a = 0; a < 4; a++)
    for (int d = 0; d < 4; d++)
        for (int f = 0; f < 4; f++) {{
            int k = (((i0 + a) * n1 + i1 + d) * n2 + i2 + f) * 2 + masking;
            e += w0[a] * w1[d] * w2[f] * {};
        }}
return fminf(fmaxf(e, 0.0f), 1.0f);
}}

"#,
        v("k"),
        centre = twoscale::tables::albedo::WIDTH_CENTRE,
        exponent = twoscale::tables::albedo::WIDTH_EXPONENT,
    )
}

/// T3's lookup in C: the parameter-axis weights and C from T3b (as `ConvTable::at_tan`). The C lookups read the header's first exported precision
/// (`value`, the C expression of stored value `k`) as the runtime does
/// (docs/export.md); `p` is the identifier prefix, `u` its upper case.
pub fn convolution(p: &str, u: &str, value: &str) -> String {
    let v = |k: &str| value_at(value, k);
    format!(
        r#"/* T3's parameter-axis weights at node position x (docs/export.md, T3 step 2): writes the
 * weights to w, the first node to *start and returns the node count (4, or 3 in an end cell). */
static inline int {p}_axis_weights(float x, int nodes, float w[4], int *start) {{
float t;
int i = ts_cell(x, nodes, &t);
if (i >= 1 && i + 2 < nodes) {{
    ts_catmull_rom_weights(t, w);
    *start = i - 1;
    return 4;
}}
if (i == 0) {{
    w[0] = 0.5f * (t - 1.0f) * (t - 2.0f); w[1] = -t * (t - 2.0f); w[2] = 0.5f * t * (t - 1.0f);
    *start = 0;
}} else {{
    w[0] = 0.5f * t * (t - 1.0f); w[1] = (1.0f - t) * (1.0f + t); w[2] = 0.5f * t * (t + 1.0f);
    *start = i - 1;
}}
w[3] = 0.0f;
return 3;
}}
/* C(theta_h; u, c, beta, p) from T3b at tau = tan(theta_h) (docs/export.md, T3 steps 1-5), as the
 * runtime's ConvTable::at_tan: 0 for non-finite input. */
static inline float {p}_conv(double tau, float u, float c, float beta, float p) {{
if (!(isfinite(u) && isfinite(c) && isfinite(beta) && isfinite(p)) || isnan(tau)) return 0.0f;
c = fminf(fmaxf(c, {u}_C_LO), {u}_C_HI);
beta = fminf(fmaxf(beta, {u}_BETA_LO), {u}_BETA_HI);
p = fminf(fmaxf(p, {u}_P_LO), {u}_P_HI);
u = fmaxf(u, {u}_U_LO);
float factor = 1.0f;
if (u > {u}_U_HI) {{
    /* I(u) / I(u_max), I(u) = (1 - (1 + 4u^2)^((1-c)/2)) / ((c - 1) u^2) */
    double cm1 = (double)c - 1.0, uf = u, um = {u}_U_HI;
    double iu = -expm1(-0.5 * cm1 * log1p(4.0 * uf * uf)) / (cm1 * uf * uf);
    double im = -expm1(-0.5 * cm1 * log1p(4.0 * um * um)) / (cm1 * um * um);
    double ratio = iu / im;
    factor = isfinite(ratio) ? (float)ratio : 0.0f;
    u = {u}_U_HI;
}}
float w[4][4];
int start[4], count[4];
count[0] = {p}_axis_weights({p}_u_position(u), {u}_U_NODES, w[0], &start[0]);
count[1] = {p}_axis_weights({p}_c_position(c), {u}_C_NODES, w[1], &start[1]);
count[2] = {p}_axis_weights({p}_beta_position(beta), {u}_BETA_NODES, w[2], &start[2]);
count[3] = {p}_axis_weights({p}_p_position(p), {u}_P_NODES, w[3], &start[3]);
int n = (int){u}_ANGLES;
double xi = {p}_normalised_angle(tau, u, beta, p);
float position = (float)(fmin(fmax(xi, 0.0), 1.0) * (double)(n - 1));
int k = (int)floorf(position);
if (k > n - 2) k = n - 2;
float t = position - (float)k;
int first = k - 1 < 0 ? 0 : (k - 1 > n - 4 ? n - 4 : k - 1);
float win[4] = {{0.0f, 0.0f, 0.0f, 0.0f}};
for (int a = 0; a < count[0]; a++)
    for (int b = 0; b < count[1]; b++)
        for (int e = 0; e < count[2]; e++)
            for (int f = 0; f < count[3]; f++) {{
                int node = (((start[0] + a) * {u}_C_NODES + start[1] + b) * {u}_BETA_NODES
                            + start[2] + e) * {u}_P_NODES + start[3] + f;
                float weight = w[0][a] * w[1][b] * w[2][e] * w[3][f];
                for (int j = 0; j < 4; j++) {{
                    int idx = node * {u}_CHANNELS + 2 + first + j;
                    win[j] += weight * {};
                }}
            }}
float v[4];
for (int j = 0; j < 4; j++) {{
    int m = k - 1 + j;
    m = m < 0 ? 0 : (m > n - 1 ? n - 1 : m);
    v[j] = win[m - first > 3 ? 3 : m - first];
}}
float s_left = k == 0 ? v[2] - v[1] : v[1] - v[0];
float s_mid = v[2] - v[1];
float s_right = k + 2 >= n ? v[2] - v[1] : v[3] - v[2];
float d1 = 0.5f * (s_left + s_mid), d2 = 0.5f * (s_mid + s_right);
float t2 = t * t, t3 = t2 * t;
float ln_c = (2.0f * t3 - 3.0f * t2 + 1.0f) * v[1] + (t3 - 2.0f * t2 + t) * d1
           + (-2.0f * t3 + 3.0f * t2) * v[2] + (t3 - t2) * d2;
float value = expf(ln_c) * factor;
return isfinite(value) ? value : 0.0f;
}}

"#,
        v("idx")
    )
}

/// The header of one table with the encoded precisions.
pub fn header(source: &Source<'_>, encoded: &[Encoded]) -> String {
    let export = &source.export;
    let header = source.table.header();
    let id = header.table_id;
    let stem = id.name();
    let p = prefix(stem);
    let upper = p.to_uppercase();
    let mut out = String::new();
    let _ = write!(
        out,
        "/* {stem}.h: written by `generator export --format c` from {stem}.tbl; do not edit.\n\
         \x20* {}\n\
         \x20* Interpolation: {}\n\
         \x20* Every array, axis and lookup is described in docs/export.md. */\n\
         #ifndef {upper}_H\n#define {upper}_H\n#include <math.h>\n#include <stdint.h>\n\n{COMMON}\n",
        id.description(),
        export.interpolation
    );
    let _ = writeln!(out, "#define {upper}_CHANNELS {}", header.channels);
    for (name, value) in id.param_names().iter().zip(header.params) {
        let _ = writeln!(out, "#define {upper}_{} {value:e}", name.to_uppercase());
    }
    out.push('\n');
    for (d, axis) in header.used_axes().iter().enumerate() {
        let name = id.axis_names().get(d).copied().unwrap_or("axis");
        let a = format!("{upper}_{}", name.to_uppercase());
        let c_lo = coordinate_f64(axis, axis.lo);
        let c_hi = coordinate_f64(axis, axis.hi);
        let cells = axis.nodes - 1;
        let _ = write!(
            out,
            "/* Axis {d}, {name}: {} nodes on [{}, {}], evenly spaced in c(x) = {}.\n\
             \x20* Stored per axis: {} ({}). */\n\
             #define {a}_NODES {}\n#define {a}_LO {}\n#define {a}_HI {}\n\
             /* Fractional node position of x in [0, {cells}]: x clamped to [lo, hi] (NaN -> lo),\n\
             \x20* u = (c(x) - c(lo)) * {cells} / (c(hi) - c(lo)). */\n\
             static inline float {p}_{name}_position(float x) {{\n\
             \x20   x = fminf(fmaxf(x, {a}_LO), {a}_HI);\n\
             \x20   float u = ({} - ({})) * {};\n\
             \x20   return fminf(fmaxf(u, 0.0f), {}.0f);\n}}\n\n",
            axis.nodes,
            axis.lo,
            axis.hi,
            axis.mapping.describe(axis.param, axis.param2),
            header.kernel.stored_per_axis(axis.nodes),
            match header.kernel {
                twoscale::tables::format::Kernel::Multilinear
                | twoscale::tables::format::Kernel::CatmullRom => {
                    "node values"
                }
                twoscale::tables::format::Kernel::CubicBSpline =>
                    "B-spline coefficients, nodes + 2",
            },
            axis.nodes,
            c_float(axis.lo as f32),
            c_float(axis.hi as f32),
            coordinate_expression(axis.mapping, axis.param, axis.param2),
            c_float(c_lo as f32),
            c_float((f64::from(cells) / (c_hi - c_lo)) as f32),
            cells
        );
    }
    if let Some(constants) = export.c_constants {
        out.push_str(&constants(&p, &upper));
    }
    if let Some(aux) = aux_array(source) {
        array(&mut out, &format!("{p}_aux"), &aux, id.descriptor().aux);
    }
    for e in encoded {
        if let Some((offset, step)) = e.unorm {
            let _ = writeln!(
                out,
                "/* unorm16: value = {p}_unorm16_offset + code * {p}_unorm16_step (f32). */\n\
                 static const float {p}_unorm16_offset = {};\nstatic const float {p}_unorm16_step = {};\n",
                c_float(offset),
                c_float(step)
            );
        }
        for a in &e.arrays {
            let comment = match a.suffix.as_str() {
                "f32" => "values as the runtime reads them".to_string(),
                "unorm16" if e.unorm.is_none() => {
                    "u16 codes; value = scales[node][0] + code * scales[node][1]".to_string()
                }
                "unorm16" => "u16 codes".to_string(),
                "unorm16-scales" => "per node (offset, step) of the u16 codes".to_string(),
                other => other.to_string(),
            };
            let name = format!("{p}_{}", a.suffix.replace('-', "_"));
            array(&mut out, &name, a, &comment);
        }
    }
    // The lookups read the first exported precision.
    if let Some(e) = encoded.first() {
        let value = match (e.precision, e.unorm) {
            (super::Precision::F32, _) => Some(format!("{p}_f32[(k)]")),
            (super::Precision::Unorm16, Some(_)) => Some(format!(
                "({p}_unorm16_offset + (float){p}_unorm16[(k)] * {p}_unorm16_step)"
            )),
            (super::Precision::Unorm16, None) => Some(format!(
                "({p}_unorm16_scales[2 * ((k) / {upper}_CHANNELS)] + (float){p}_unorm16[(k)] * {p}_unorm16_scales[2 * ((k) / {upper}_CHANNELS) + 1])"
            )),
            _ => None,
        };
        if let Some(value) = value {
            out.push_str(&(export.c_lookups)(&p, &upper, &value));
        }
    }
    let _ = writeln!(out, "#endif /* {upper}_H */");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn float_literals_read_back_exactly() {
        for x in [0.2f32, 1.0, 1.0527e-5, -3.4e38, 0.0, 65535.0] {
            let text = c_float(x);
            assert!(text.ends_with('f'));
            assert_eq!(text.trim_end_matches('f').parse::<f32>().unwrap(), x);
        }
        assert_eq!(prefix("t3-convolution"), "ts_t3_convolution");
    }
}
