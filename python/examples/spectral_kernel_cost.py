"""Per-call cost proxies of the spectral plugin (``SpectralModel``) in
``llvm_ad_spectral``: the IR operations of the kernel that evaluates
``eval_spectral`` at four wavelengths, ``pdf_spectral`` and
``sample_spectral`` (Dr.Jit's own count, independent of the machine's load),
and the best of seven rounds of wall time per call.

    python python/examples/spectral_kernel_cost.py [PRESET | beckmann]

``beckmann`` is the benchmark_render.py Beckmann-limit material (β = 0.1,
p = 1, σs = 0, η = 0.584 + 2.15i); 2¹⁶ random pairs, uniform wavelengths.
"""

import os
import re
import sys
import tempfile
import time

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402


def logged(run):
    """Dr.Jit's log (level Info, written by its C++ side) while `run` runs."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    with tempfile.TemporaryFile() as log:
        os.dup2(log.fileno(), 1)
        os.dup2(log.fileno(), 2)
        dr.set_log_level(dr.LogLevel.Info)
        try:
            run()
        finally:
            dr.set_log_level(dr.LogLevel.Warn)
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
        log.seek(0)
        return log.read().decode(errors="replace")


def main():
    mi.set_variant("llvm_ad_spectral")
    import twoscale
    import twoscale.drjit as tb

    name = sys.argv[1] if len(sys.argv) > 1 else "gold-hp17-geometry"
    material = (twoscale.Material(beta=0.1, p=1.0, sigma_s=0.0, eta=[(0.584, 2.15)] * 3)
                if name == "beckmann" else twoscale.Material.preset(name))
    model = tb.SpectralModel(material)
    n = 1 << 16
    rng = np.random.default_rng(1)

    def directions():
        v = rng.normal(size=(3, n))
        v[2] = np.abs(v[2])
        return mi.Vector3f(v / np.linalg.norm(v, axis=0))

    wi, wo = directions(), directions()
    lams = [mi.Float(rng.uniform(0.36, 0.83, n).astype(np.float32)) for _ in range(4)]
    u = mi.Vector3f(rng.uniform(size=(3, n)))
    calls = {
        "eval4": lambda: mi.Spectrum(*model.eval_spectral(wi, wo, lams)),
        "pdf": lambda: model.pdf_spectral(wi, wo, lams[0]),
        "sample": lambda: model.sample_spectral(wi, u, lams[0])[0],
    }
    for key, call in calls.items():
        ops = [int(x) for x in re.findall(r"ops=(\d+)", logged(lambda: dr.eval(call())))]
        best = float("inf")
        for _ in range(7):
            start = time.perf_counter()
            dr.eval(call())
            dr.sync_thread()
            best = min(best, time.perf_counter() - start)
        print(f"{name:20s} {key:7s} kernel ops {sum(ops):6d}  best {best / n * 1e9:8.1f} ns/call")


if __name__ == "__main__":
    main()
