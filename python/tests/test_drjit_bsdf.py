"""The Dr.Jit port of the model (``twoscale.drjit``, the ``twoscale``
plugin) against the runtime, in ``llvm_ad_rgb`` with Mitsuba's default
symbolic loops and calls (no file of python/tests switches them): agreement,
χ², white furnace, Beckmann limit, gradients."""

import os
import zlib

import numpy as np
import pytest

LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
if os.path.exists(LLVM):
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", LLVM)

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

import twoscale  # noqa: E402
from render_checks import beckmann_limit, chi2, direction, furnace_albedo, furnace_render  # noqa: E402,E501

mi.set_variant("llvm_ad_rgb")
import twoscale.drjit as tb  # noqa: E402
import twoscale.mitsuba as tm  # noqa: E402

tm.register()

#: Pairs per preset (issue 25 item 4 asks for 10⁵ in CI; 10⁴ keeps this file
#: under ~30 s).
PAIRS = 10_000
#: Agreement in distribution (issue 43 item 6), where a value exceeds 1e-6
#: of its peak: `eval` within 1e-4 relative of the runtime's at the 99th
#: percentile and 1e-3 at most; `pdf` within 1e-3 at most where both
#: directions are at least :data:`GRAZING` above the horizon (and 1e-4 at
#: the 99th percentile everywhere). The port computes in f32, the runtime its
#: geometry in f64: f32's rounding of a unit direction (6e-8) moves h by as
#: much, which the narrow peaks (gold-polished) and, at grazing outgoing
#: directions, the halo density (its azimuth range shrinks to 0 there: a
#: relative 1.5e-7 in cos θh moves it 1.2e-3) amplify.
EVAL_P99, EVAL_MAX, PDF_P99, PDF_MAX = 1e-4, 1e-3, 1e-4, 1e-3
#: The cosine above which `pdf` is held to :data:`PDF_MAX`.
GRAZING = 1e-3


@pytest.fixture(autouse=True)
def symbolic_mode():
    """Mitsuba's default, symbolic loops and calls, is on (nothing switches
    it off)."""
    assert dr.flag(dr.JitFlag.SymbolicLoops) and dr.flag(dr.JitFlag.SymbolicCalls)


def seed(*parts):
    """A seed fixed by the test's parameters (`hash` of a string is not)."""
    return zlib.crc32(repr(parts).encode())


def pairs(seed, n=PAIRS):
    """Random pairs (light, camera) in the upper hemisphere: half uniform,
    half within ~3° of the mirror direction (the peaks), some grazing."""
    rng = np.random.default_rng(seed)

    def unit(v):
        return (v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32)

    def upper(v):
        v[:, 2] = np.abs(v[:, 2])
        return unit(v)

    light, camera = upper(rng.normal(size=(n, 3))), upper(rng.normal(size=(n, 3)))
    k = n // 2
    mirror = light[:k] * np.array([-1.0, -1.0, 1.0], dtype=np.float32)
    camera[:k] = upper(mirror + 0.05 * rng.normal(size=(k, 3)))
    return light, camera


def agreement(got, ref, rows=None):
    """`(p99, worst, small_ok)`: the 99th percentile of |got − ref|/ref over
    the values above 1e-6 of each channel's peak, its largest over those of
    the `rows` given (a boolean mask; all by default), and whether `got` is
    within 1e-6 of the peak of `ref` elsewhere."""
    peak = ref.max(axis=0)
    big = ref > 1e-6 * peak
    rel = np.where(big, np.abs(got - ref) / np.where(big, ref, 1.0), 0.0)
    rows = np.ones(len(ref), bool) if rows is None else rows
    small_ok = np.all(np.abs(got - ref)[~big] <= (1e-6 * np.broadcast_to(peak, ref.shape))[~big])
    return np.quantile(rel[big], 0.99), rel[rows].max(), small_ok


def assert_eval_agrees(got, ref, what=""):
    """`eval` agrees in distribution (:data:`EVAL_P99`, :data:`EVAL_MAX`)."""
    p99, worst, small_ok = agreement(got, ref)
    assert p99 <= EVAL_P99 and worst <= EVAL_MAX, f"{what}: eval p99 {p99:.2e} max {worst:.2e}"
    assert small_ok, what


def assert_pdf_agrees(got, ref, light, camera, what=""):
    """`pdf` agrees (:data:`PDF_P99` everywhere; :data:`PDF_MAX` where both
    cosines are ≥ :data:`GRAZING`)."""
    rows = np.minimum(light[:, 2], camera[:, 2]) >= GRAZING
    p99, worst, small_ok = agreement(got[:, None], ref[:, None], rows)
    assert p99 <= PDF_P99 and worst <= PDF_MAX, f"{what}: pdf p99 {p99:.2e} max {worst:.2e}"
    assert small_ok, what


def assert_same_mean(a, b, what=""):
    """Two samples of sampling weights, row `k` of each at the same incidence
    (and wavelength) from independent uniforms, have the same mean per
    channel: the mean of the paired differences is 0 within 4 of its
    standard errors. Returns the differences' means in standard errors."""
    d = np.asarray(a, np.float64) - np.asarray(b, np.float64)
    diff, se = d.mean(axis=0), d.std(axis=0) / np.sqrt(len(d))
    assert np.all(np.abs(diff) <= 4.0 * se), f"{what}: means {np.mean(a, 0)} {np.mean(b, 0)} ± {se}"
    return diff / se


def test_bakes_are_the_runtime_bakes():
    """Material.bakes(): three channels of named scalars and float32 arrays,
    at the channels' wavelengths, with the layouts the port reads."""
    m = twoscale.Material.preset("gold-hp17-geometry", rgb_mode="paper-wavelengths")
    bakes = m.bakes()
    assert len(bakes) == 3
    assert [round(b["lambda"], 3) for b in bakes] == [0.645, 0.526, 0.444]
    for b, (n, k) in zip(bakes, m.eta):
        assert b["direction_rows"].shape == (257, 8)
        assert b["direction_rows"].dtype == np.float32
        assert b["masking_g1"].shape == (1025,)
        assert b["conv_ln_c"].shape == (35, 132)
        assert b["conv_baked"] == 1.0
        # Nodes even in √cos θ: node 0 is grazing (F = 1), the last normal incidence.
        assert abs(b["direction_rows"][0, 6] - 1.0) < 1e-6
        f = float(twoscale.reference.fresnel(n, k, 1.0))
        assert abs(b["direction_rows"][-1, 6] - f) < 2e-5
        # G1 is 1 at normal incidence and 0 at the horizon node.
        assert abs(b["masking_g1"][0] - 1.0) < 1e-6 and b["masking_g1"][-1] == 0.0


MATERIALS = [(name, {}) for name in twoscale.Material.presets()] + [
    ("gold-hp17-geometry", {"masking": "height-correlated"}),
    ("gold-hp17-geometry", {"sigma_rel": "symmetrised"}),
    ("gold-hp17-geometry", {"halo_weight": "incident"}),
    ("white-plastic", {"colour": "white"}),
    ("gold-rough", {"multiple_scattering": "kulla-conty"}),
    ("white-plastic", {"multiple_scattering": "kulla-conty"}),
    ("beckmann-limit", {}),
] + [
    # The paper's wavelengths (`tb.Model`; the presets' default is the
    # integrated RGB, `tb.IntegratedModel`): a halo, a polished lobe, a
    # plastic and a subsurface base, compensation, white colour terms.
    (name, {"rgb_mode": "paper-wavelengths", **options}) for name, options in [
        ("gold-hp17-geometry", {}), ("gold-polished", {}), ("silver", {}), ("white-plastic", {}),
        ("marble", {}), ("gold-rough", {"multiple_scattering": "kulla-conty"}),
        ("white-plastic", {"colour": "white"}), ("gold-hp17-geometry", {"masking": "height-correlated"}),
    ]
]


def material_of(name, options):
    """The preset `name` with `options`; "beckmann-limit" is the render
    benchmark's p = 1, σs = 0 gold conductor (the specular lobe alone: the
    port's specialised code without the diffraction, base and compensation
    lobes)."""
    if name == "beckmann-limit":
        return twoscale.Material(beta=0.1, p=1.0, sigma_s=0.0,
                                 eta=[(0.163, 3.56), (0.584, 2.15), (1.403, 1.925)], **options)
    return twoscale.Material.preset(name, **options)


def test_specular_only_material_is_specialised():
    """The Beckmann-limit material traces the specular lobe alone: constant
    lobe weights [1, 0, 0, 0], no diffraction, no compensation lobe (the
    agreement tests below check it against the runtime)."""
    model = tb.Model(material_of("beckmann-limit", {}))
    assert all(ch.weight_columns == [0] and not ch.diffraction and ch.s["multiple_scale"] == 0.0
               for ch in model.channels)
    assert model.diffraction_stack is None
    gold = tb.Model(twoscale.Material.preset("gold-hp17-geometry", rgb_mode="paper-wavelengths"))
    assert all(ch.weight_columns == [0, 1] for ch in gold.channels)
    assert gold.diffraction_stack is not None


@pytest.mark.parametrize("name,options", MATERIALS, ids=lambda x: str(x))
def test_eval_agrees_with_the_runtime(name, options):
    """`Model.eval` agrees with `Material.eval` (:func:`assert_eval_agrees`)
    on 10⁴ pairs, evaluated inside a symbolic loop (symbolic mode on:
    nothing in eval may be evaluated eagerly). Measured on 10⁵ pairs: p99
    ≤ 6.0e-5 and max ≤ 6.8e-4 (gold-polished), ≤ 2.6e-5 / 3.8e-4 for the other presets."""
    for key, value in options.items():
        assert value in twoscale.OPTIONS.get(key, twoscale.RGB_MODES), key
    material = material_of(name, options)
    model = tb.rgb_model(material)
    light, camera = pairs(seed(name, "eval", options))
    ref = material.eval(light, camera)
    wi, wo = mi.Vector3f(light.T), mi.Vector3f(camera.T)

    def body(k, acc):
        return k + 1, acc + model.eval(wi, wo)

    _, acc = dr.while_loop((mi.UInt32(0), mi.Color3f(0.0)), lambda k, acc: k < 2, body)
    got = np.array(acc).T / 2.0
    assert_eval_agrees(got, ref, f"{name} {options}")


@pytest.mark.parametrize("name,options", MATERIALS, ids=lambda x: str(x))
def test_pdf_agrees_with_the_runtime(name, options):
    """`Model.pdf` (the sampler's density: the visible-slope tables, the
    diffraction sampler's law, the cosine lobe and the bake's lobe weights,
    averaged over the channels) agrees with `Material.pdf`
    (:func:`assert_pdf_agrees`) on 10⁴ pairs, inside a symbolic loop.
    Measured on 10⁵ pairs: p99 ≤ 5.1e-5, max ≤ 8.6e-4 where both cosines
    are ≥ 1e-3 (gold-polished), 1.4e-2 below (aluminium's halo)."""
    material = material_of(name, options)
    model = tb.rgb_model(material)
    light, camera = pairs(seed(name, "pdf", options))
    ref = material.pdf(light, camera)[:, None]
    wi, wo = mi.Vector3f(light.T), mi.Vector3f(camera.T)

    def body(k, acc):
        return k + 1, acc + model.pdf(wi, wo)

    _, acc = dr.while_loop((mi.UInt32(0), mi.Float(0.0)), lambda k, acc: k < 2, body)
    got = np.array(acc) / 2.0
    assert_pdf_agrees(got, ref[:, 0], light, camera, f"{name} {options}")


def sampling_weights(model, material, light, u_port, u_ref):
    """The sampling weights `ρ(wi, o) cos θo / pdf(wi, o)` (0 where no
    direction is drawn) of the port's draws from `u_port` and the runtime's
    from `u_ref` (each its own `eval` and `pdf`), at the incidences `light`."""
    wi = mi.Vector3f(light.T)
    o, ok = model.sample_direction(wi, mi.Vector3f(u_port.T))
    value, pdf = model.eval(wi, o), model.pdf(wi, o)
    ok = np.array(ok).astype(bool) & (np.array(pdf) > 0.0)
    o = np.array(o).T
    port = np.where(ok[:, None], np.array(value).T * o[:, 2:3]
                    / np.where(ok, np.array(pdf), 1.0)[:, None], 0.0)
    ref_o, ref_pdf, _ = material.sample(light, u_ref)
    has = ref_pdf > 0.0
    ref = np.where(has[:, None], material.eval(light, ref_o) * ref_o[:, 2:3]
                   / np.where(has, ref_pdf, 1.0)[:, None], 0.0)
    return port, ref


@pytest.mark.parametrize("name,options", MATERIALS, ids=lambda x: str(x))
def test_sample_agrees_in_distribution(name, options):
    """`Model.sample_direction` draws what `Material.sample` draws, in
    distribution (issue 43 item 6; the directions for the same uniforms are
    not compared): over 2·10⁴ incidences with independent uniforms, the mean
    sampling weight `ρ cos θo/pdf` of each channel is the runtime's within 4
    standard errors of the difference (≈ 0.1–0.3% of the mean); the χ²
    tests check the shape."""
    material = material_of(name, options)
    model = tb.rgb_model(material)
    rng = np.random.default_rng(seed(name, "sample", options))
    light, _ = pairs(int(rng.integers(2**31)), 20_000)
    u = rng.random((2, len(light), 3)).astype(np.float32)
    port, ref = sampling_weights(model, material, light, u[0], u[1])
    assert_same_mean(port, ref, f"{name} {options}")


def test_plugin_through_a_symbolic_call():
    """The plugin through a `BSDFPtr` (a symbolic call): `eval` is
    ρ(wi=wo, wo=si.wi) cos θ(wo), the convention of `twoscale.mitsuba`, 0
    below the horizon; `pdf` is `Material.pdf(si.wi, wo)`; `sample` returns
    that pdf at its direction and weight eval / pdf, of the runtime's mean."""
    assert dr.flag(dr.JitFlag.SymbolicCalls)
    name = "gold-rough"
    material = twoscale.Material.preset(name)
    bsdf = mi.load_dict({"type": tm.NAME, "material": name})
    light, camera = pairs(5, 2000)
    light[:100, 2] *= -1.0  # below the horizon
    n = len(light)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(camera.T)
    ptr = dr.gather(mi.BSDFPtr, mi.BSDFPtr(bsdf), dr.zeros(mi.UInt32, n))
    ctx = mi.BSDFContext()
    value, pdf = ptr.eval_pdf(ctx, si, mi.Vector3f(light.T), mi.Bool(True))
    ref = material.eval(light, camera) * np.maximum(light[:, 2:3], 0.0)
    got = np.array(value).T
    assert_eval_agrees(got[100:], ref[100:], name)
    assert np.all(got[:100] == 0.0)
    ref_pdf = material.pdf(camera, light)
    assert_pdf_agrees(np.array(pdf)[100:], ref_pdf[100:], camera[100:], light[100:], name)
    assert np.all(np.array(pdf)[:100] == 0.0)
    rng = np.random.default_rng(9)
    u = rng.random((2, 3, n)).astype(np.float32)
    bs, weight = ptr.sample(ctx, si, mi.Float(u[0, 0]), mi.Point2f(u[0, 1:]), mi.Bool(True))
    p2 = np.array(bs.pdf)
    ok = p2 > 0
    wo = np.array(bs.wo).T
    assert ok.mean() > 0.9
    assert_pdf_agrees(p2[ok], material.pdf(camera[ok], wo[ok]), camera[ok], wo[ok], name)
    v2 = np.array(ptr.eval(ctx, si, bs.wo, mi.Bool(True))).T
    assert np.allclose(np.array(weight).T[ok], v2[ok] / p2[ok, None], rtol=1e-5)
    ref_o, ref_p, _ = material.sample(camera, u[1].T)
    has = ref_p > 0
    ref_w = np.where(has[:, None], material.eval(ref_o, camera) * ref_o[:, 2:3]
                     / np.where(has, ref_p, 1.0)[:, None], 0.0)
    assert_same_mean(np.where(ok[:, None], np.array(weight).T, 0.0), ref_w, name)


GOLD = "0.163 3.56, 0.584 2.15, 1.403 1.925"


def xml(**props):
    """Plugin properties as the XML the χ² adapter expects."""
    out = []
    for key, value in props.items():
        kind = "float" if isinstance(value, float) else "string"
        out.append(f'<{kind} name="{key}" value="{value}"/>')
    return "".join(out)


STRONG_HALO = dict(beta=0.1, p=1.0, sigma_s=0.1, b=3.0, c=1.6, eta=GOLD)
CHI2_CASES = [
    ("gold-hp17-geometry, 40°", dict(material="gold-hp17-geometry"), 40.0),
    ("gold-rough, 30°", dict(material="gold-rough"), 30.0),
    ("gold-rough, grazing 85°", dict(material="gold-rough"), 85.0),
    ("white-plastic, 50°", dict(material="white-plastic"), 50.0),
    ("marble, 10°", dict(material="marble"), 10.0),
    ("strong halo, 20°", STRONG_HALO, 20.0),
    ("strong halo, grazing 80°", STRONG_HALO, 80.0),
    ("compensated gold-rough, 60°",
     dict(material="gold-rough", multiple_scattering="kulla-conty"), 60.0),
    ("paper's wavelengths gold-hp17-geometry, 40°",
     dict(material="gold-hp17-geometry", rgb_mode="paper-wavelengths"), 40.0),
    ("silver, grazing 80°", dict(material="silver"), 80.0),
]


@pytest.mark.parametrize("label,props,theta", CHI2_CASES, ids=[c[0] for c in CHI2_CASES])
def test_chi2(label, props, theta):
    """Mitsuba's χ² test of the plugin's `sample` against its `pdf`, with
    symbolic mode on (`render_checks.chi2`)."""
    test = chi2(*mi.chi2.BSDFAdapter(tm.NAME, xml(**props), wi=direction(theta)))
    print(f"chi2 {label}: p = {test.p_value:.4f}")
    assert test.passed, test.messages


@pytest.mark.parametrize("name,theta,rgb_mode", [("gold-rough", 30, "integrated"),
                                                  ("gold-hp17-geometry", 60, "integrated"),
                                                  ("gold-rough", 45, "paper-wavelengths")])
def test_white_furnace(name, theta, rgb_mode):
    """A render with the plugin (symbolic mode on) estimates the albedo of
    the white-colour material, ∫ ρ cos θi dωi by quadrature over the
    runtime's eval."""
    material = twoscale.Material.preset(name, colour="white", rgb_mode=rgb_mode)
    expected = furnace_albedo(material, theta)
    props = {"type": tm.NAME, "material": name, "colour": "white", "rgb_mode": rgb_mode}
    pixels = furnace_render(props, theta, seed=0)
    mean = pixels.mean(axis=0)
    standard_error = pixels.std(axis=0) / np.sqrt(len(pixels))
    print(f"furnace {name} θo={theta}: render {mean}, quadrature {expected}, SE {standard_error}")
    assert np.all(np.abs(mean - expected) < 4 * standard_error + 2e-3)


def test_white_furnace_with_energy_compensation():
    """A β = 0.8 conductor (σs = 0, reciprocal, so the render's integral over
    the light's directions is the albedo) renders at 1 ± 0.005 with
    ``multiple_scattering="kulla-conty"``; without, it is dark."""
    kw = dict(beta=0.8, p=1.0, eta=[(0.163, 3.56), (0.584, 2.15), (1.403, 1.925)], colour="white")
    for options, lo, hi in [({}, 0.0, 0.95), ({"multiple_scattering": "kulla-conty"}, 0.995, 1.005)]:
        material = twoscale.Material(**kw, **options)
        pixels = furnace_render(tm.bsdf_dict(material), 45, seed=0)
        mean = pixels.mean(axis=0)
        standard_error = pixels.std(axis=0) / np.sqrt(len(pixels))
        print(f"furnace β = 0.8 {options} θo=45: render {mean} ± {standard_error}")
        assert np.all((mean > lo - 4 * standard_error) & (mean < hi + 4 * standard_error))


@pytest.mark.parametrize("alpha", [0.1, 0.3])
def test_beckmann_limit(alpha):
    """At p = 1, σs = 0 the plugin renders as Mitsuba's roughconductor
    (Beckmann, same α, η, k), in symbolic mode: the renders differ by their
    noise (mean |Δ| within 1.1× the noise level, mean bias below 1%)."""
    diff, noise, bias = beckmann_limit(alpha, plugin=tm.NAME)
    print(f"Beckmann limit α={alpha}: mean|Δ| = {diff:.5f}, noise = {noise:.5f}, "
          f"ratio = {diff / noise:.3f}, mean bias = {bias:+.4%}")
    assert diff / noise < 1.1
    assert abs(bias) < 0.01


def _eval_sum(bsdf, light, camera):
    """Σ eval over pairs (light = Mitsuba's wo, camera = si.wi), an mi.Float."""
    si = dr.zeros(mi.SurfaceInteraction3f, len(light))
    si.wi = mi.Vector3f(camera.T)
    return dr.sum(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(light.T)), axis=None)


@pytest.mark.parametrize("name,key,x0", [
    ("white-plastic", "albedo", 0.8),
    ("marble", "albedo", 0.6),
    ("white-plastic", "lambertian", 0.1),
    ("gold-hp17-geometry", "halo_factor", 1.0),
])
def test_gradient_equals_finite_differences(name, key, x0):
    """`dr.backward` of Σ eval over 500 pairs with respect to a parameter
    `traverse` exposes equals the central finite difference (step 1% of
    the value, through `params.update()`, which re-bakes) within 2%, in
    symbolic mode."""
    bsdf = mi.load_dict({"type": tm.NAME, "material": name})
    params = mi.traverse(bsdf)
    assert key in params
    light, camera = pairs(seed(name, key), 500)
    params[key] = mi.Float(x0)
    params.update()
    dr.enable_grad(params[key])
    params.update()
    dr.backward(_eval_sum(bsdf, light, camera))
    grad = dr.grad(params[key])[0]
    dr.disable_grad(params[key])
    h = 0.01 * x0
    values = []
    for x in (x0 + h, x0 - h):
        params[key] = mi.Float(x)
        params.update()
        values.append(float(mi.Float64(_eval_sum(bsdf, light, camera))[0]))
    fd = (values[0] - values[1]) / (2 * h)
    print(f"{name} ∂/∂{key}: backward {grad:.6g}, central difference {fd:.6g}")
    assert abs(grad) > 0 and abs(grad / fd - 1) < 0.02


def test_parameters_changed_rebakes():
    """Setting k_d through `mi.traverse` gives the runtime's material with
    that k_d: `eval` and `pdf` (whose lobe weights k_d changes) agree with those
    of `Material.with_layer(lambertian=...)`; the exposed keys are the
    material's (no albedo for a conductor, no halo factor without σs)."""
    bsdf = mi.load_dict({"type": tm.NAME, "material": "gold-hp17-geometry"})
    params = mi.traverse(bsdf)
    assert set(params.keys()) == {"lambertian", "halo_factor"}
    params["lambertian"] = mi.Float(0.3)
    params.update()
    ref = twoscale.Material.preset("gold-hp17-geometry").with_layer(lambertian=0.3)
    light, camera = pairs(11, 2000)
    si = dr.zeros(mi.SurfaceInteraction3f, len(light))
    si.wi = mi.Vector3f(camera.T)
    value, pdf = bsdf.eval_pdf(mi.BSDFContext(), si, mi.Vector3f(light.T))
    assert_eval_agrees(np.array(value).T, ref.eval(light, camera) * light[:, 2:3], "k_d 0.3")
    assert_pdf_agrees(np.array(pdf), ref.pdf(camera, light), camera, light, "k_d 0.3")
    plain = mi.traverse(mi.load_dict({"type": tm.NAME, "beta": 0.2, "p": 1.0, "eta": GOLD}))
    assert set(plain.keys()) == {"lambertian"}


def test_render_gradient_equals_finite_differences():
    """`dr.backward` of a tiny render (16×16, 1024 spp, Mitsuba's `prb`,
    direct light from a sun and a constant environment on a white-plastic
    sphere) with respect to the base albedo equals the central difference
    of two renders (albedo ± 1%, re-baked, same seed) within 2%. The
    adjoint pass draws its own samples (Mitsuba requires a seed other than
    the primal's), so both sides carry Monte Carlo noise: measured 0.10%
    here; at 512 spp two other seed pairs gave 0.46% and 0.51%."""
    look = mi.ScalarTransform4f().look_at(origin=[0, 0, 4.5], target=[0, 0, 0], up=[0, 1, 0])
    scene = mi.load_dict({
        "type": "scene",
        "integrator": {"type": "prb", "max_depth": 2},
        "sensor": {"type": "perspective", "fov": 30, "to_world": look,
                   "film": {"type": "hdrfilm", "width": 16, "height": 16,
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": 1024}},
        "sphere": {"type": "sphere", "bsdf": {"type": tm.NAME, "material": "white-plastic"}},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 0.5}},
        "sun": {"type": "directional", "direction": [-1, -1, -2],
                "irradiance": {"type": "rgb", "value": 5.0}},
    })
    params = mi.traverse(scene)
    key, x0, h = "sphere.bsdf.albedo", 0.8, 0.008
    dr.enable_grad(params[key])
    params.update()
    dr.backward(dr.sum(mi.render(scene, params, seed=3, seed_grad=4), axis=None))
    grad = dr.grad(params[key])[0]
    dr.disable_grad(params[key])
    values = []
    for x in (x0 + h, x0 - h):
        params[key] = mi.Float(x)
        params.update()
        values.append(float(dr.sum(mi.Float64(mi.render(scene, seed=3).array))[0]))
    fd = (values[0] - values[1]) / (2 * h)
    print(f"render ∂/∂albedo: backward {grad:.6g}, central difference {fd:.6g}")
    assert abs(grad / fd - 1) < 0.02
