"""The Dr.Jit plugin in ``llvm_ad_spectral`` (four wavelengths per path):
``twoscale.drjit.SpectralModel`` against the runtime's model at any
wavelength (``Material.eval_spectral``), Mitsuba's χ² test and the white
furnace, with Mitsuba's default symbolic loops and calls."""

import os

import numpy as np
import pytest

LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
if os.path.exists(LLVM):
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", LLVM)

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

import twoscale  # noqa: E402
import twoscale.drjit as tb  # noqa: E402
import twoscale.mitsuba as tm  # noqa: E402
from render_checks import chi2, direction, furnace_albedo, furnace_render  # noqa: E402
from test_drjit_bsdf import (  # noqa: E402
    assert_eval_agrees,
    assert_pdf_agrees,
    assert_same_mean,
    pairs,
    seed,
)


@pytest.fixture(autouse=True, scope="module")
def spectral_variant():
    """This file's variant (the previous one restored after it), in
    Mitsuba's default symbolic mode (nothing switches it off)."""
    saved = mi.variant()
    mi.set_variant("llvm_ad_spectral")
    tm.register()
    assert dr.flag(dr.JitFlag.SymbolicLoops) and dr.flag(dr.JitFlag.SymbolicCalls)
    yield
    if saved:
        mi.set_variant(saved)


def preset_with(name):
    """The preset `name`, or `preset/white` with white colour terms, or
    `preset/kulla-conty` with the energy compensation."""
    preset, _, option = name.partition("/")
    key = {"white": "colour", "kulla-conty": "multiple_scattering"}.get(option)
    return twoscale.Material.preset(preset, **({key: option} if key else {}))


@pytest.mark.parametrize("name", twoscale.Material.presets()
                         + ["white-plastic/white", "gold-rough/kulla-conty"])
def test_eval_agrees_with_the_runtime(name):
    """`SpectralModel.eval_spectral` agrees with `Material.eval_spectral`
    (`test_drjit_bsdf.assert_eval_agrees`: 1e-4 relative at p99, 1e-3 at
    most, where ρ exceeds 1e-6 of the peak) on 10⁴ pairs at four uniform
    wavelengths each (the ends included), inside a symbolic loop."""
    material = preset_with(name)
    model = tb.SpectralModel(material)
    light, camera = pairs(seed(name, "spectral"))
    rng = np.random.default_rng(seed(name, "lam"))
    lam = rng.uniform(0.36, 0.83, size=(4, len(light))).astype(np.float32)
    lam[:, :4] = [[0.36], [0.83], [0.40], [0.6]]
    ref = np.stack([material.eval_spectral(light, camera, row) for row in lam], axis=1)
    wi, wo = mi.Vector3f(light.T), mi.Vector3f(camera.T)

    def body(k, acc):
        return k + 1, acc + mi.Spectrum(*model.eval_spectral(wi, wo, [mi.Float(x) for x in lam]))

    _, acc = dr.while_loop((mi.UInt32(0), mi.Spectrum(0.0)), lambda k, acc: k < 2, body)
    got = np.array(acc).T / 2.0
    assert_eval_agrees(got.reshape(-1, 1), ref.reshape(-1, 1), name)


@pytest.mark.parametrize("base", ["plastic", "subsurface"])
def test_a_dispersive_base_agrees_with_the_runtime(base):
    """With η varying over λ the base layer's constants differ between the
    models (per-model `eta_re`, `f_dr_int`): `eval_spectral` and
    `pdf_spectral` agree with the runtime's as in `test_eval_agrees_with_the_runtime`."""
    lam_eta = np.linspace(0.36, 0.83, 30)
    material = twoscale.Material(beta=0.2, p=1.5, sigma_s=0.05, b=2.0, c=1.5,
                                 eta=(lam_eta, 1.6 - 0.2 * (lam_eta - 0.36), 0.0 * lam_eta),
                                 base=base, albedo=0.7, lambertian=0.1)
    assert {"eta_re", "f_dr_int"} <= set(material.spectral_bakes()["per_node"])
    model = tb.SpectralModel(material)
    light, camera = pairs(seed(base, "dispersive"))
    lam = np.random.default_rng(seed(base, "lam")).uniform(0.36, 0.83, (4, len(light)))
    lam = lam.astype(np.float32)
    wi, wo = mi.Vector3f(light.T), mi.Vector3f(camera.T)
    ref = np.stack([material.eval_spectral(light, camera, row) for row in lam], axis=1)
    got = np.array(mi.Spectrum(*model.eval_spectral(wi, wo, [mi.Float(x) for x in lam]))).T
    assert_eval_agrees(got.reshape(-1, 1), ref.reshape(-1, 1), base)
    got = np.array(model.pdf_spectral(wi, wo, mi.Float(lam[0])))
    assert_pdf_agrees(got, material.pdf_spectral(light, camera, lam[0]), light, camera, base)


@pytest.mark.parametrize("name", ["gold-hp17-geometry", "marble", "silver", "white-plastic/white",
                                  "gold-rough/kulla-conty"])
def test_pdf_and_sample_agree_with_the_runtime(name):
    """`pdf_spectral` (the model nearest the hero wavelength) agrees with
    `Material.pdf_spectral` (`test_drjit_bsdf.assert_pdf_agrees`) on 10⁴
    pairs at uniform wavelengths, and `sample_spectral` draws what
    `Material.sample_spectral` draws, in distribution: over 2·10⁴
    incidences with independent uniforms, the mean sampling weight
    `ρ(λ) cos θo/pdf` is the runtime's within 4 standard errors."""
    material = preset_with(name)
    model = tb.SpectralModel(material)
    light, camera = pairs(seed(name, "spectral pdf"))
    rng = np.random.default_rng(seed(name, "spectral u"))
    lam = rng.uniform(0.36, 0.83, size=len(light)).astype(np.float32)
    got = np.array(model.pdf_spectral(mi.Vector3f(light.T), mi.Vector3f(camera.T), mi.Float(lam)))
    assert_pdf_agrees(got, material.pdf_spectral(light, camera, lam), light, camera, name)
    light, _ = pairs(seed(name, "spectral sample"), 20_000)
    lam = rng.uniform(0.36, 0.83, size=len(light)).astype(np.float32)
    u = rng.random((2, len(light), 3)).astype(np.float32)
    wi, lam_f = mi.Vector3f(light.T), mi.Float(lam)
    o, ok = model.sample_spectral(wi, mi.Vector3f(u[0].T), lam_f)
    value = model.eval_spectral(wi, o, [lam_f])[0]
    pdf = model.pdf_spectral(wi, o, lam_f)
    ok = np.array(ok).astype(bool) & (np.array(pdf) > 0.0)
    port = np.where(ok, np.array(value) * np.array(o.z) / np.where(ok, np.array(pdf), 1.0), 0.0)
    ref_o, ref_pdf = material.sample_spectral(light, u[1], lam)
    has = ref_pdf > 0.0
    ref = np.where(has, material.eval_spectral(light, ref_o, lam) * ref_o[:, 2]
                   / np.where(has, ref_pdf, 1.0), 0.0)
    assert_same_mean(port[:, None], ref[:, None], name)


class _Poisoned:
    """`material` whose `spectral_bakes()` has NaN in every stacked quantity
    (those named by `only`, if given) of the models not in `keep`."""

    def __init__(self, material, keep, only=None):
        self.material, self.keep, self.only = material, keep, only

    def __getattr__(self, name):
        return getattr(self.material, name)

    def spectral_bakes(self):
        bakes = self.material.spectral_bakes()
        for name in bakes["per_node"]:
            if self.only is not None and not self.only(name):
                continue
            value = np.array(bakes["models"][name], copy=True)
            value[[k for k in range(len(value)) if k not in self.keep]] = np.nan
            bakes["models"][name] = value
        return bakes


@pytest.mark.parametrize("name", ["gold-hp17-geometry", "marble"])
def test_each_wavelength_reads_its_models_only(name):
    """With every model but those around the path's four wavelengths (and
    model 0, the shared surface's source) made NaN, `eval_spectral` is
    unchanged bit for bit, and so it is with C's bake and the constants
    scaled to λ made NaN in all but the lower model of each wavelength's
    cell; with every model but the hero wavelength's
    nearest, `pdf_spectral` and `sample_spectral` are."""
    material = preset_with(name)
    light, camera = pairs(seed(name, "poison"), 1000)
    wi, wo = mi.Vector3f(light.T), mi.Vector3f(camera.T)
    u = mi.Vector3f(np.random.default_rng(seed(name, "poison u")).random((3, len(light))))
    # Cells 1, 7, 10 and 17 (from the nodes 0.40, 0.54, 0.60 and 0.795 µm).
    lams = [mi.Float(x) for x in (0.41, 0.545, 0.61, 0.80)]
    model = tb.SpectralModel(material)
    poisoned = tb.SpectralModel(_Poisoned(material, {0, 1, 2, 7, 8, 10, 11, 17, 18}))
    for a, b in zip(model.eval_spectral(wi, wo, lams), poisoned.eval_spectral(wi, wo, lams)):
        assert np.array_equal(np.array(a), np.array(b))
    assert np.array(model.eval_spectral(wi, wo, lams)[1]).max() > 0.0
    # C and the constants scaled to λ: the lower model's only.
    def scaled(n):
        return n.startswith("conv_") or n in ("lambda", "x_scale", "halo_scale", "big_b")

    lower_only = tb.SpectralModel(_Poisoned(material, {0, 1, 7, 10, 17}, scaled))
    for a, b in zip(model.eval_spectral(wi, wo, lams), lower_only.eval_spectral(wi, wo, lams)):
        assert np.array_equal(np.array(a), np.array(b))
    upper_only = tb.SpectralModel(_Poisoned(material, {0, 2, 8, 11, 18}, scaled))
    assert not all(np.array_equal(np.array(a), np.array(b)) for a, b in
                   zip(model.eval_spectral(wi, wo, lams), upper_only.eval_spectral(wi, wo, lams)))
    # The sampler models are the even ones: 0.545 µm is nearest 0.56 (8) of
    # 0.52 (6) and 0.56.
    hero = mi.Float(0.545)
    nearest = tb.SpectralModel(_Poisoned(material, {0, 8}))
    assert np.array_equal(np.array(model.pdf_spectral(wi, wo, hero)),
                          np.array(nearest.pdf_spectral(wi, wo, hero)))
    (o, ok), (o_p, ok_p) = (m.sample_spectral(wi, u, hero) for m in (model, nearest))
    assert np.array_equal(np.array(ok), np.array(ok_p)) and np.array(ok).any()
    assert np.array_equal(np.array(o), np.array(o_p))
    # The poison is seen where it is read: the pdf at a model made NaN.
    assert not np.array_equal(np.array(model.pdf_spectral(wi, wo, mi.Float(0.6))),
                              np.array(nearest.pdf_spectral(wi, wo, mi.Float(0.6))))


def adapter(props, wi, nm):
    """`mi.chi2.BSDFAdapter` with the paths' wavelengths set to `nm` (the
    adapter leaves them 0, which would test only the bluest model)."""
    bsdf = mi.load_dict({"type": tm.NAME, **props})

    def context(n):
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = wi
        si.wavelengths = mi.Spectrum(nm)
        return si, mi.BSDFContext()

    def sample(u, *args):
        si, ctx = context(dr.width(u))
        bs, weight = bsdf.sample(ctx, si, u[0], mi.Vector2f(u[1], u[2]))
        return bs.wo, dr.select(dr.all(weight == 0), 0.0, mi.Float(1.0))

    def pdf(wo, *args):
        si, ctx = context(dr.width(wo))
        return bsdf.pdf(ctx, si, wo)

    return sample, pdf


@pytest.mark.parametrize(
    "label,props,theta,nm",
    [
        ("gold-hp17-geometry", dict(material="gold-hp17-geometry"), 40.0, 550.0),
        ("strong halo", dict(beta=0.1, p=1.0, sigma_s=0.1, b=3.0, c=1.6,
                             eta="0.5 2.5, 0.5 2.5, 0.5 2.5"), 45.0, 700.0),
        ("marble", dict(material="marble"), 60.0, 400.0),
    ],
)
def test_chi2(label, props, theta, nm):
    """Mitsuba's χ² test of `sample` against `pdf` in llvm_ad_spectral at a
    hero wavelength (the nearest model's sampler), symbolic mode on."""
    test = chi2(*adapter(props, direction(theta), nm))
    print(f"chi2 spectral {label} at {nm} nm: p = {test.p_value:.4f}")
    assert test.passed, test.messages


def _spread(material, theta, wavelengths=(0.36, 0.45, 0.55, 0.65, 0.83), k=300):
    """min and max over λ of ∫ ρ(i, o, λ) cos θi dωi (midpoint rule)."""
    o = np.array([direction(theta)])
    z = (np.arange(k) + 0.5) / k
    phi = (np.arange(2 * k) + 0.5) / (2 * k) * 2 * np.pi
    zz, pp = np.meshgrid(z, phi, indexing="ij")
    r = np.sqrt(1 - zz**2)
    wi = np.stack([r * np.cos(pp), r * np.sin(pp), zz], axis=-1).reshape(-1, 3)
    a = [float((material.eval_spectral(wi, np.broadcast_to(o, wi.shape), np.full(len(wi), lam))
                * wi[:, 2]).sum()) * np.pi / k**2 for lam in wavelengths]
    return min(a), max(a)


def test_white_furnace():
    """Renders in llvm_ad_spectral estimate the albedo. Without diffraction
    (σs = 0) the white-colour model does not depend on λ, so every pixel
    estimates the RGB quadrature of `Material.eval`; with it
    (gold-hp17-geometry, white), the albedo varies with λ (0.985–0.994 at
    30°) and each channel must lie within its range over λ."""
    flat = twoscale.Material(beta=0.2, p=1.5, eta=[(0.5, 2.0)] * 3, colour="white")
    cases = [
        ({"type": tm.NAME, "beta": 0.2, "p": 1.5, "eta": "0.5 2, 0.5 2, 0.5 2",
          "colour": "white"}, furnace_albedo(flat, 30), furnace_albedo(flat, 30)),
        ({"type": tm.NAME, "material": "gold-hp17-geometry", "colour": "white"},
         *_spread(twoscale.Material.preset("gold-hp17-geometry", colour="white"), 30)),
    ]
    for props, lo, hi in cases:
        pixels = furnace_render(props, 30, seed=0)
        mean = pixels.mean(axis=0)
        standard_error = pixels.std(axis=0) / np.sqrt(len(pixels))
        print(f"spectral furnace {props}: render {mean}, expected [{lo}, {hi}], SE {standard_error}")
        margin = 4 * standard_error + 2e-3
        assert np.all(mean > np.asarray(lo) - margin) and np.all(mean < np.asarray(hi) + margin)
