"""The float arithmetic of Dr.Jit's LLVM kernels by precision: how much of
the plugin's `eval`, `pdf` and `sample` runs in f64 (issue 43: Mitsuba's
BSDFs are f32 throughout, and f64 runs at 1/32–1/64 of f32's rate on most
GPUs).

:func:`count_float_ops` reads one kernel's IR (the ``ir`` of an entry of
``dr.kernel_history()``), :func:`kernel_float_ops` runs a function with
``dr.JitFlag.KernelHistory`` on and adds up the kernels it launched. An
operation is an instruction whose result is a float vector or scalar
(``float`` or ``double``): ``fadd``, ``fsub``, ``fmul``, ``fdiv``,
``frem``, ``fneg`` and calls (``llvm.fma``, ``llvm.sqrt``, ``llvm.floor``,
``llvm.minnum`` …, and Dr.Jit's own float functions); memory intrinsics
(``llvm.masked.gather``, ``llvm.masked.load`` …) are reads, not
arithmetic, and conversions (``fpext``, ``fptrunc``, ``sitofp``),
comparisons and selects are not counted. The count is static (an
instruction of a symbolic loop's body counts once), as in the IR.
"""

import re

import drjit as dr

#: `%x = OP <16 x double> …`, `%x = call <16 x float> @f(…)`, scalar forms too.
_OP = re.compile(
    r"=\s*(?:(fadd|fsub|fmul|fdiv|frem|fneg)(?:\s+[a-z]+)*\s+"
    r"(<\d+ x (float|double)>|float\b|double\b)"
    r"|(?:tail\s+)?call(?:\s+[a-z]+)*\s+(<\d+ x (float|double)>|float|double)\s+@([\w.$]+))")

#: Intrinsics that read or move memory rather than compute.
_MEMORY = ("llvm.masked.", "llvm.memcpy", "llvm.memset", "llvm.prefetch")


def count_float_ops(ir):
    """`{"float": n, "double": m}`: the float arithmetic instructions of
    one kernel's LLVM IR (text) by precision."""
    counts = {"float": 0, "double": 0}
    for m in _OP.finditer(ir):
        if m.group(1):
            counts[m.group(3)] += 1
        elif not m.group(6).startswith(_MEMORY):
            counts[m.group(5)] += 1
    return counts


def _ir_text(entry):
    ir = entry.get("ir")
    return ir.getvalue() if hasattr(ir, "getvalue") else (ir or "")


def kernel_float_ops(fn):
    """Runs `fn()` (which must evaluate what it computes, e.g. with
    ``dr.eval``) with ``dr.JitFlag.KernelHistory`` on, and returns the sum
    of :func:`count_float_ops` over the LLVM kernels it launched, with
    ``"kernels"`` their number. A kernel found in Dr.Jit's cache is counted
    too: its IR is generated before the look-up."""
    previous = dr.flag(dr.JitFlag.KernelHistory)
    dr.kernel_history()  # clears what came before
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        fn()
        history = dr.kernel_history()
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, previous)
    total = {"float": 0, "double": 0, "kernels": 0}
    for entry in history:
        if str(entry.get("backend", "")).lower().endswith("llvm") and _ir_text(entry):
            counts = count_float_ops(_ir_text(entry))
            total["float"] += counts["float"]
            total["double"] += counts["double"]
            total["kernels"] += 1
    return total


def f64_share(counts):
    """The f64 share `double / (float + double)` of :func:`kernel_float_ops`' counts."""
    n = counts["float"] + counts["double"]
    return counts["double"] / n if n else 0.0


def plugin_float_ops(props, n=4096, seed=1):
    """:func:`kernel_float_ops` of the ``twoscale`` plugin of `props` (a
    ``mi.load_dict`` dict; the plugin registered, a Dr.Jit variant set) for
    each of ``eval``, ``pdf`` and ``sample``, over `n` random directions in
    the upper hemisphere (uploaded first, so that only the BSDF's kernel is
    counted), with Mitsuba's default symbolic loops and calls: a dict
    method → counts."""
    import mitsuba as mi
    import numpy as np

    bsdf = mi.load_dict(props)
    rng = np.random.default_rng(seed)

    def upper(v):
        v[:, 2] = np.abs(v[:, 2]) + 1e-3
        return (v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32)

    wi_np, wo_np = upper(rng.normal(size=(n, 3))), upper(rng.normal(size=(n, 3)))
    u_np = rng.random((n, 3)).astype(np.float32)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(wi_np.T)
    if mi.is_spectral:
        si.wavelengths = mi.Spectrum(*[mi.Float(x) for x in 400.0 + 300.0 * rng.random((4, n))])
    wo, u1, u2 = mi.Vector3f(wo_np.T), mi.Float(u_np[:, 0]), mi.Point2f(u_np[:, 1:].T)
    dr.eval(si, wo, u1, u2)
    ctx = mi.BSDFContext()
    return {
        "eval": kernel_float_ops(lambda: dr.eval(bsdf.eval(ctx, si, wo))),
        "pdf": kernel_float_ops(lambda: dr.eval(bsdf.pdf(ctx, si, wo))),
        "sample": kernel_float_ops(lambda: dr.eval(bsdf.sample(ctx, si, u1, u2))),
    }


def sampler_float_ops(model, n=4096, seed=1):
    """:func:`kernel_float_ops` of the samplers' own functions
    (:mod:`~twoscale.drjit.visible`, :mod:`~twoscale.drjit.halo`) as
    `model` (a :class:`~twoscale.drjit.models.Model` or subclass) calls them,
    each alone, on f32 unit directions: ``visible_pdf`` and
    ``visible_sample`` of the shared surface, ``halo_pdf`` summed over the
    channels (models) `pdf` reads and ``halo_sample`` over those `sample`
    draws from. An upper bound of the f64 these functions put into the
    plugin's kernels (fused there, Dr.Jit's common-subexpression elimination
    only removes operations)."""
    import mitsuba as mi
    import numpy as np

    rng = np.random.default_rng(seed)

    def upper(v):
        v[:, 2] = np.abs(v[:, 2]) + 1e-3
        return (v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32)

    wi = mi.Vector3f(upper(rng.normal(size=(n, 3))).T)
    wo = mi.Vector3f(upper(rng.normal(size=(n, 3))).T)
    u = rng.random((3, n)).astype(np.float32)
    u1, u2, k = mi.Float(u[1]), mi.Float(u[2]), mi.UInt32(np.minimum(3 * u[0], 2).astype(np.uint32))
    dr.eval(wi, wo, u1, u2, k)
    _, geo = model.geometry(wi, wo)
    dr.eval(geo)
    surface = model.channels[0]
    if hasattr(model, "stack"):  # spectral: the sampler model of each lane
        halo_pdf = halo_draw = [model.stack.at(2 * k)] if model.stack.diffraction else []
    else:
        halo_pdf = [ch for ch in model.channels if ch.diffraction]
        stack = getattr(model, "diffraction_stack", None)
        halo_draw = [stack.at(k)] if stack is not None else halo_pdf

    def total(calls):
        out = {"float": 0, "double": 0, "kernels": 0}
        for call in calls:
            counts = kernel_float_ops(lambda: dr.eval(call()))
            out = {key: out[key] + counts[key] for key in out}
        return out

    return {
        "visible_pdf": total([lambda: surface.visible_pdf(wi, wo)]),
        "visible_sample": total([lambda: surface.visible_sample(wi, u1, u2)]),
        "halo_pdf": total([lambda ch=ch: ch.halo_pdf(wi, geo["sin_h"], geo["cos_h"], wo.z)
                           for ch in halo_pdf]),
        "halo_sample": total([lambda ch=ch: ch.halo_sample(wi, u1, u2) for ch in halo_draw]),
    }


def main():
    """Prints the f64 share of the plugin's kernels (``python -m
    twoscale.drjit.ir``): the Beckmann limit and presets, llvm_ad_rgb and
    llvm_ad_spectral."""
    import argparse
    import os
    import subprocess
    import sys

    parser = argparse.ArgumentParser(description=main.__doc__.splitlines()[0])
    parser.add_argument("--variant", choices=["llvm_ad_rgb", "llvm_ad_spectral"])
    args = parser.parse_args()
    if args.variant is None:
        for variant in ("llvm_ad_rgb", "llvm_ad_spectral"):
            subprocess.run([sys.executable, "-m", "twoscale.drjit.ir", "--variant", variant],
                           env=dict(os.environ), check=True)
        return
    import mitsuba as mi

    mi.set_variant(args.variant)
    import twoscale.mitsuba as tm

    tm.register()
    for label in CASES:
        props = case(label, mi.is_spectral)
        if props is None:
            continue
        if mi.is_spectral:
            label = label.replace(" (integrated RGB)", "")
        counts = plugin_float_ops(props)
        total = {k: sum(c[k] for c in counts.values()) for k in ("float", "double")}
        parts = "  ".join(f"{m} {c['double']}/{c['float'] + c['double']} ({f64_share(c):.1%})"
                          for m, c in counts.items())
        print(f"{args.variant:16s} {label:40s} f64 {f64_share(total):6.1%}  {parts}")
        model = mi.load_dict(props).model
        parts = "  ".join(f"{m} {c['double']}/{c['float'] + c['double']}"
                          for m, c in sampler_float_ops(model).items())
        print(f"{'':16s} {'  the samplers alone (f64/all)':40s} {parts}")


#: What :func:`main` measures: the Beckmann limit and presets (the
#: presets' default RGB is the integrated one).
CASES = {
    "Beckmann limit (β = 0.1, p = 1, σs = 0)": {
        "type": "twoscale", "beta": 0.1, "p": 1.0, "sigma_s": 0.0,
        "eta": "0.163 3.56, 0.584 2.15, 1.403 1.925"},
    "gold-hp17-geometry (integrated RGB)": {"type": "twoscale", "material": "gold-hp17-geometry"},
    "gold-hp17-geometry (paper's wavelengths)": {
        "type": "twoscale", "material": "gold-hp17-geometry", "rgb_mode": "paper-wavelengths"},
    "gold-rough": {"type": "twoscale", "material": "gold-rough"},
    "copper": {"type": "twoscale", "material": "copper"},
}


def case(label, spectral):
    """The plugin's properties of :data:`CASES`' `label` in an RGB or a
    spectral variant (None where it is an RGB mode's): an explicit
    material's index for every channel in spectral variants."""
    props = CASES[label]
    if spectral and "rgb_mode" in props:
        return None
    if spectral and "eta" in props:
        return dict(props, eta=", ".join(["0.584 2.15"] * 3))
    return props


if __name__ == "__main__":
    main()
