"""The Dr.Jit port of the model (twoscale.drjit_bsdf) against the runtime."""

import numpy as np

import twoscale


def test_bakes_are_the_runtime_bakes():
    """Material.bakes(): three channels of named scalars and float32 arrays,
    at the channels' wavelengths, with the layouts the port reads."""
    m = twoscale.Material.preset("gold-hp17-geometry")
    bakes = m.bakes()
    assert len(bakes) == 3
    assert [round(b["lambda"], 3) for b in bakes] == [0.645, 0.526, 0.444]
    for b in bakes:
        assert b["direction_rows"].shape == (257, 8)
        assert b["direction_rows"].dtype == np.float32
        assert b["masking_g1"].shape == (1025,)
        assert b["conv_ln_c"].shape == (35, 132)
        assert b["conv_baked"] == 1.0
        # Nodes even in √cos θ: node 0 is grazing (F = 1), the last normal incidence.
        assert abs(b["direction_rows"][0, 6] - 1.0) < 1e-6
        # G1 is 1 at normal incidence and 0 at the horizon node.
        assert abs(b["masking_g1"][0] - 1.0) < 1e-6 and b["masking_g1"][-1] == 0.0
    for b, (n, k) in zip(bakes, m.eta):
        f = float(twoscale.reference.fresnel(n, k, 1.0))
        assert abs(b["direction_rows"][-1, 6] - f) < 2e-5
