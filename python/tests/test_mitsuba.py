"""The Mitsuba 3 plugin ``twoscale`` (the Dr.Jit BSDF, llvm_ad_rgb, Mitsuba's
default symbolic mode): its interface (register, material files, context
masks), the direction convention, the consistency of eval, pdf, sample and
eval_pdf, and its agreement with the NumPy round trip (numpy_oracle.py).
The χ² tests, the white furnace and the Beckmann limit are in
test_drjit_bsdf.py."""

import os

import numpy as np
import pytest

LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
if os.path.exists(LLVM):
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", LLVM)

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

import twoscale  # noqa: E402
import twoscale.mitsuba as tm  # noqa: E402
import numpy_oracle  # noqa: E402
from test_drjit_bsdf import assert_eval_agrees, assert_pdf_agrees, assert_same_mean  # noqa: E402

mi.set_variant("llvm_ad_rgb")
tm.register()
numpy_oracle.register()

GOLD = "0.163 3.56, 0.584 2.15, 1.403 1.925"


STRONG_HALO = dict(beta=0.1, p=1.0, sigma_s=0.1, b=3.0, c=1.6, eta=GOLD)


def make_si(wi):
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = mi.Vector3f(np.ascontiguousarray(np.asarray(wi, dtype=np.float32).T))
    si.n = mi.Normal3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    return si


def test_eval_pdf_sample_consistent_and_directions():
    """eval takes Mitsuba's wo (the light) as the model's incident direction;
    pdf is the sampler's density given si.wi; sample's weight is eval / pdf;
    eval_pdf returns both. The material is non-reciprocal (strong halo), so
    swapped directions would fail the first check."""
    material = twoscale.Material(**{**STRONG_HALO, "eta": [(0.163, 3.56), (0.584, 2.15), (1.403, 1.925)]})
    bsdf = mi.load_dict(tm.bsdf_dict(material))
    rng = np.random.default_rng(3)
    n = 2000
    cam = np.stack([np.full(n, np.sin(1.2)), np.zeros(n), np.full(n, np.cos(1.2))], axis=1)
    si = make_si(cam)
    ctx = mi.BSDFContext()
    bs, weight = bsdf.sample(ctx, si, mi.Float(rng.random(n, dtype=np.float32)),
                             mi.Point2f(rng.random((2, n), dtype=np.float32)))
    wo = np.asarray(bs.wo, dtype=np.float32).T
    pdf = np.asarray(bs.pdf)
    ok = pdf > 0
    assert ok.mean() > 0.9
    value, pdf2 = bsdf.eval_pdf(ctx, si, mi.Vector3f(np.ascontiguousarray(wo.T)))
    value = np.asarray(value).T
    np.testing.assert_allclose(np.asarray(bsdf.eval(ctx, si, mi.Vector3f(np.ascontiguousarray(wo.T)))).T, value)
    np.testing.assert_allclose(np.asarray(bsdf.pdf(ctx, si, mi.Vector3f(np.ascontiguousarray(wo.T)))), pdf2)
    np.testing.assert_allclose(np.asarray(pdf2)[ok], pdf[ok], rtol=1e-5)
    np.testing.assert_allclose(np.asarray(weight).T[ok], value[ok] / pdf[ok, None], rtol=1e-4)
    expected = material.eval(wo[ok], cam[ok]) * wo[ok, 2:3]
    # the plugin's agreement with the runtime (issue 43: test_drjit_bsdf.py)
    assert_eval_agrees(value[ok], expected, "strong halo")
    swapped = material.eval(cam[ok], wo[ok]) * wo[ok, 2:3]
    # the swap differs by far more than the tolerance above
    assert (np.abs(swapped - expected) / expected).max() > 1e-2


def test_agrees_with_the_numpy_oracle():
    """The plugin and the NumPy round trip (Material's eval, pdf and sample
    called on the wavefront) agree in distribution, on 2000 camera
    directions per material with symbolic mode on: eval and pdf at the
    oracle's draws as `test_drjit_bsdf.assert_eval_agrees` and
    `assert_pdf_agrees`, the mean sampling weight with independent uniforms
    within 4 standard errors."""
    assert dr.flag(dr.JitFlag.SymbolicLoops) and dr.flag(dr.JitFlag.SymbolicCalls)
    rng = np.random.default_rng(8)
    n = 2000
    cam = rng.normal(size=(n, 3))
    cam[:, 2] = np.abs(cam[:, 2])
    cam /= np.linalg.norm(cam, axis=1, keepdims=True)
    si, ctx = make_si(cam), mi.BSDFContext()
    u = [(mi.Float(rng.random(n, dtype=np.float32)),
          mi.Point2f(rng.random((2, n), dtype=np.float32))) for _ in range(2)]
    for props in (dict(material="gold-hp17-geometry"), dict(material="marble"), STRONG_HALO):
        plugin = mi.load_dict({"type": tm.NAME, **props})
        oracle = mi.load_dict({"type": numpy_oracle.NAME, **props})
        _, weight = plugin.sample(ctx, si, *u[0])
        bs_ref, weight_ref = oracle.sample(ctx, si, *u[1])
        assert_same_mean(np.asarray(weight).T, np.asarray(weight_ref).T, str(props))
        ok = np.asarray(bs_ref.pdf) > 0
        light = mi.Vector3f(bs_ref.wo)
        value, pdf = plugin.eval_pdf(ctx, si, light)
        value_ref, pdf_ref = oracle.eval_pdf(ctx, si, light)
        assert_eval_agrees(np.asarray(value).T[ok], np.asarray(value_ref).T[ok], str(props))
        wo = np.asarray(bs_ref.wo).T
        assert_pdf_agrees(np.asarray(pdf)[ok], np.asarray(pdf_ref)[ok], cam[ok], wo[ok], str(props))


def test_context_without_glossy_component_gives_zero():
    bsdf = mi.load_dict({"type": "twoscale", "material": "gold-rough"})
    si = make_si([[0.0, 0.0, 1.0]])
    wo = mi.Vector3f(0.3, 0.0, 0.95)
    ctx = mi.BSDFContext()
    assert float(np.asarray(bsdf.eval(ctx, si, wo))[0].item()) > 0
    ctx.type_mask = +mi.BSDFFlags.DiffuseReflection
    assert np.all(np.asarray(bsdf.eval(ctx, si, wo)) == 0)
    assert np.all(np.asarray(bsdf.pdf(ctx, si, wo)) == 0)


def test_register_needs_a_variant_and_the_module_loads_on_first_use():
    """In a fresh interpreter: ``twoscale.mitsuba`` without an explicit import,
    ``register()`` before ``mi.set_variant`` says what to do, after it the
    BSDF loads and evaluates."""
    import subprocess
    import sys

    script = (
        "import numpy as np, mitsuba as mi, twoscale\n"
        "try:\n"
        "    twoscale.mitsuba.register()\n"
        "    raise SystemExit('register() without a variant did not raise')\n"
        "except RuntimeError as e:\n"
        "    assert 'mi.set_variant' in str(e), e\n"
        "mi.set_variant('scalar_rgb')\n"
        "twoscale.mitsuba.register()\n"
        "bsdf = mi.load_dict({'type': 'twoscale', 'material': 'gold-rough'})\n"
        "si = mi.SurfaceInteraction3f()\n"
        "si.wi = mi.Vector3f(0.5, 0.0, 0.866)\n"
        "value = bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(-0.5, 0.0, 0.866))\n"
        "assert np.all(np.asarray(value) > 0), value\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr


def test_material_file(tmp_path):
    """``filename`` loads a material file (a fit's TOML), found through
    Mitsuba's file resolver as scene files find theirs; it gives the whole
    material, so another material parameter with it is refused."""
    path = tmp_path / "params.toml"
    path.write_text(
        "[material]\nbeta = 0.12\np = 1.4\neta = [[0.2, 3.9], [0.45, 2.5], [1.4, 1.9]]\n"
        "sigma_s = 0.03\nb = 2.5\nc = 2.2\nlambertian = 0.02\nsigma_rel = \"symmetrised\"\n"
        "\n[metrics]\nrmse = [0.01, 0.01, 0.01]\n",
        encoding="utf-8",
    )
    material = twoscale.Material.from_toml(path)
    explicit = mi.load_dict(tm.bsdf_dict(material))
    from_dict = mi.load_dict({"type": "twoscale", "filename": str(path)})
    resolver = mi.file_resolver()
    saved = [str(resolver[k]) for k in range(len(resolver))]
    resolver.prepend(str(tmp_path))
    try:
        from_xml = mi.load_string(
            '<bsdf version="3.0.0" type="twoscale"><string name="filename" value="params.toml"/></bsdf>'
        )
    finally:
        resolver.clear()
        for entry in saved:
            resolver.append(entry)
    assert repr(material) in str(from_dict) and str(from_dict) == str(from_xml)
    cam = np.array([[np.sin(0.7), 0.0, np.cos(0.7)]] * 64)
    rng = np.random.default_rng(5)
    light = rng.normal(size=(64, 3))
    light[:, 2] = np.abs(light[:, 2])
    light /= np.linalg.norm(light, axis=1, keepdims=True)
    si, ctx = make_si(cam), mi.BSDFContext()
    wo = mi.Vector3f(np.ascontiguousarray(light.T.astype(np.float32)))
    want = np.asarray(explicit.eval(ctx, si, wo))
    assert want.max() > 0
    for bsdf in (from_dict, from_xml):
        np.testing.assert_array_equal(np.asarray(bsdf.eval(ctx, si, wo)), want)
    with pytest.raises(Exception, match="filename= gives the whole material, options included; remove masking"):
        mi.load_dict({"type": "twoscale", "filename": str(path), "masking": "height-correlated"})
    with pytest.raises(Exception, match=r"\[material\] p = 9: must be in \[0.2, 5\]"):
        path.write_text("[material]\nbeta = 0.1\np = 9\neta = [[1, 0], [1, 0], [1, 0]]\n", encoding="utf-8")
        mi.load_dict({"type": "twoscale", "filename": str(path)})


def test_a_bsdf_prints_its_material_options_included():
    """``print(bsdf)`` (``to_string``) shows the material's repr: a preset's
    options and rgb_mode included, and the repr rebuilds the same material."""
    bsdf = mi.load_dict({"type": "twoscale", "material": "gold-rough", "colour": "white",
                         "multiple_scattering": "kulla-conty", "rgb_mode": "paper-wavelengths"})
    want = ('twoscale.Material.preset("gold-rough", colour="white", '
            'multiple_scattering="kulla-conty", rgb_mode="paper-wavelengths")')
    assert str(bsdf) == f"TwoScaleBSDF[{want}]"
    rebuilt = eval(want, {"twoscale": twoscale})
    direct = twoscale.Material.preset("gold-rough", colour="white",
                                      multiple_scattering="kulla-conty", rgb_mode="paper-wavelengths")
    wi, wo = np.array([0.5, 0.0, 0.866]), np.array([-0.45, 0.05, 0.89])
    np.testing.assert_array_equal(rebuilt.eval(wi, wo), direct.eval(wi, wo))
