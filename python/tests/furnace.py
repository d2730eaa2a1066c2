"""The white furnace of the Mitsuba plugins' tests (test_mitsuba.py,
test_drjit_bsdf.py): a material's albedo by quadrature over the runtime's
eval, and a render that estimates it in every pixel."""

import mitsuba as mi
import numpy as np


def direction(theta_deg):
    t = np.radians(theta_deg)
    return [float(np.sin(t)), 0.0, float(np.cos(t))]


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
