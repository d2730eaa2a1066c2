"""Render checks of the Mitsuba plugin's tests (test_drjit_bsdf.py,
test_drjit_spectral.py): the χ² test, the white furnace (a material's albedo by quadrature
over the runtime's eval, and a render that estimates it in every pixel) and
the Beckmann limit against Mitsuba's roughconductor."""

import importlib
import pathlib
import sys

import mitsuba as mi
import numpy as np


def example(name):
    """The module python/examples/`name`.py (the directory joins the path,
    as when the example runs, so that examples import each other)."""
    examples = str(pathlib.Path(__file__).resolve().parents[1] / "examples")
    if examples not in sys.path:
        sys.path.append(examples)
    return importlib.import_module(name)


#: The sphere scene and the Beckmann-limit pair of BSDFs.
benchmark_render = example("benchmark_render")


def direction(theta_deg):
    t = np.radians(theta_deg)
    return [float(np.sin(t)), 0.0, float(np.cos(t))]


def chi2(sample, pdf):
    """Mitsuba's χ² test (spherical domain, 3 uniforms) of `sample` against
    `pdf`, with ires=16: the tester integrates the pdf over each cell with
    16×16 points; its default, 4, under-resolves lobes of β ≈ 0.06
    (docs/python.md). Returns the test, run."""
    test = mi.chi2.ChiSquareTest(
        domain=mi.chi2.SphericalDomain(), sample_func=sample, pdf_func=pdf,
        sample_dim=3, ires=16,
    )
    test.passed = test.run(quiet=True)
    return test


def furnace_albedo(material, theta_deg, k=1500):
    """∫ ρ(i, o) cos θi dωi for the viewer at θo, by the midpoint rule in
    (cos θi, φi) over the runtime's eval."""
    o = np.array([direction(theta_deg)])
    z = (np.arange(k) + 0.5) / k
    phi = (np.arange(2 * k) + 0.5) / (2 * k) * 2 * np.pi
    total = np.zeros(3)
    for zi in np.array_split(z, 10):
        zz, pp = np.meshgrid(zi, phi, indexing="ij")
        r = np.sqrt(1 - zz**2)
        wi = np.stack([r * np.cos(pp), r * np.sin(pp), zz], axis=-1).reshape(-1, 3)
        value = material.eval(wi, np.broadcast_to(o, wi.shape))
        total += (value * wi[:, 2:3]).sum(axis=0)
    return total * (1 / k) * (np.pi / k)


def furnace_render(bsdf, theta_deg, seed):
    """A flat patch seen by an orthographic camera at θo under a constant
    emitter of radiance 1: every pixel estimates the albedo."""
    t = np.radians(theta_deg)
    look = mi.ScalarTransform4f().look_at(origin=[5 * np.sin(t), 0, 5 * np.cos(t)],
                                          target=[0, 0, 0], up=[0, 1, 0])
    scene = mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 2},
        "sensor": {
            "type": "orthographic", "to_world": look @ mi.ScalarTransform4f().scale([0.5, 0.5, 1]),
            "film": {"type": "hdrfilm", "width": 64, "height": 64, "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": 64},
        },
        "patch": {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale(5), "bsdf": bsdf},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
    })
    return np.asarray(mi.render(scene, seed=seed, spp=64)).reshape(-1, 3)


def beckmann_limit(alpha, plugin="twoscale"):
    """Mean |difference| between the plugin `plugin` (p = 1, σs = 0) and
    roughconductor (beckmann, same α, η, k) renders, over the noise level
    expected for two independent renders, from two seeds of each."""
    twoscale_bsdf, rough = benchmark_render.beckmann_pair(alpha, plugin=plugin)
    img = {}
    for name, bsdf in (("twoscale", twoscale_bsdf), ("rough", rough)):
        scene = benchmark_render.sphere_scene(bsdf)
        for seed in (0, 1):
            img[name, seed] = np.asarray(mi.render(scene, seed=seed, spp=64))
    mad = lambda a, b: float(np.abs(a - b).mean())  # noqa: E731
    noise_rough = mad(img["rough", 0], img["rough", 1])
    noise_twoscale = mad(img["twoscale", 0], img["twoscale", 1])
    diff = (mad(img["twoscale", 0], img["rough", 1]) + mad(img["twoscale", 1], img["rough", 0])) / 2
    # independent renders A, B: E|A − B| ∝ sqrt(σA² + σB²)
    noise = np.sqrt((noise_rough**2 + noise_twoscale**2) / 2)
    bias = (img["twoscale", 0] + img["twoscale", 1]).mean() / (img["rough", 0] + img["rough", 1]).mean() - 1
    return diff, noise, bias
