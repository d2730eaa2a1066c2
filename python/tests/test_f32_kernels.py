"""The f64 share of the plugin's kernels (issue 43 item 1): the float
arithmetic of the LLVM IR of `eval`, `pdf` and `sample` by precision
(`twoscale.drjit.ir`, Dr.Jit's ``KernelHistory``), in ``llvm_ad_rgb`` and
``llvm_ad_spectral``, at the Beckmann limit and for presets (gold-hp17-geometry
in its default integrated RGB, its paper's wavelengths, copper: `ir.CASES`).

The port computes in f32 throughout, the samplers (`visible.py`,
`halo.py`, counted alone too: `ir.sampler_float_ops`) included: the f64
share of every kernel is :data:`SAMPLER_F64_SHARE`, 0 (issue 43's target)."""

import os
import subprocess
import sys

import pytest

LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
if os.path.exists(LLVM):
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", LLVM)

#: The largest f64 share of a `pdf` or `sample` kernel: 0 with the samplers
#: in f32 (52.7% / 48.7% at the Beckmann limit with them in f64).
SAMPLER_F64_SHARE = 0.0

#: Run in a process per variant (one Mitsuba variant per process's tests).
SCRIPT = r"""
import json, sys
import mitsuba as mi
mi.set_variant(sys.argv[1])
import twoscale.mitsuba as tm
from twoscale.drjit import ir
tm.register()
props = ir.case(sys.argv[2], mi.is_spectral)
if props is None:
    print(json.dumps(None))
    sys.exit()
counts = ir.plugin_float_ops(props)
counts["samplers"] = ir.sampler_float_ops(mi.load_dict(props).model)
print(json.dumps(counts))
"""


def kernel_counts(variant, label):
    import json

    done = subprocess.run([sys.executable, "-c", SCRIPT, variant, label],
                          capture_output=True, text=True, env=dict(os.environ))
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.splitlines()[-1])


@pytest.mark.parametrize("variant", ["llvm_ad_rgb", "llvm_ad_spectral"])
@pytest.mark.parametrize("case", ["Beckmann limit (β = 0.1, p = 1, σs = 0)",
                                  "gold-hp17-geometry (integrated RGB)",
                                  "gold-hp17-geometry (paper's wavelengths)", "copper"])
def test_f64_share(variant, case):
    """`eval`, `pdf` and `sample` have no f64 operation, nor have the
    samplers' own functions alone (`twoscale.drjit.ir.CASES`)."""
    counts = kernel_counts(variant, case)
    if counts is None:
        pytest.skip("rgb_mode is an RGB option")
    for method in ("eval", "pdf", "sample"):
        assert counts[method]["kernels"] >= 1 and counts[method]["float"] > 0, method
    s = counts["samplers"]
    assert s["visible_pdf"]["float"] > 0 and s["visible_sample"]["float"] > 0, s
    assert all(c["double"] == 0 for c in s.values()), s
    for method in ("eval", "pdf", "sample"):
        c = counts[method]
        share = c["double"] / (c["double"] + c["float"])
        assert share <= SAMPLER_F64_SHARE, (method, c)


COUNTER = r"""
import json
import drjit as dr
import mitsuba as mi
from twoscale.drjit import ir
mi.set_variant("llvm_ad_rgb")
table = mi.Float64([1.0, 2.0, 3.0, 4.0])
x = dr.arange(mi.Float, 64)
dr.eval(table, x)

def kernel():
    y = dr.gather(mi.Float64, table, mi.UInt32(x) % 4)  # a gather: not counted
    z = dr.sqrt(mi.Float64(x)) * y + 1.0  # f64: sqrt, and an fma or fmul + fadd
    w = dr.select(x > 3.0, x * x, x)  # f32: one fmul (the comparison is not counted)
    dr.eval(z, w)

print(json.dumps(ir.kernel_float_ops(kernel)))
"""


def test_counter_reads_both_precisions():
    """The counter sees f32 and f64 arithmetic and skips gathers,
    conversions and comparisons (a kernel written for it)."""
    import json

    from twoscale.drjit import ir

    done = subprocess.run([sys.executable, "-c", COUNTER], capture_output=True, text=True,
                          env=dict(os.environ))
    assert done.returncode == 0, done.stderr
    counts = json.loads(done.stdout.splitlines()[-1])
    assert counts["kernels"] == 1
    assert counts["float"] == 1
    assert counts["double"] in (2, 3)
    assert ir.f64_share({"float": 1, "double": 3}) == 0.75
