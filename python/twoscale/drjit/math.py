"""The runtime's arithmetic (runtime/src/math/) in Dr.Jit: the cheap
logarithm of the bakes' axes, the arc cosine and the bracketed Newton solve
that the samplers share."""

import math

import drjit as dr
import mitsuba as mi
import numpy as np

# The constants of `math::log2_axis` (runtime/src/math/mod.rs), in f32.
_LOG2_E = np.float32(math.log2(math.e))
_AXIS_D0 = float(_LOG2_E)
_AXIS_C2 = float(np.float32(3.0) - np.float32(2.5) * _LOG2_E)
_AXIS_C3 = float(np.float32(1.5) * _LOG2_E - np.float32(2.0))


def log2_axis(x):
    """`math::log2_axis`: `e + m (d0 + m (c2 + m c3))` for `x = 2^e (1 + m)`."""
    bits = dr.reinterpret_array(mi.UInt32, x)
    exponent = mi.Float(mi.Int32((bits >> 23) & 0xFF) - 127)
    m = dr.reinterpret_array(mi.Float, (bits & 0x007FFFFF) | 0x3F800000) - 1.0
    return exponent + m * (_AXIS_D0 + m * (_AXIS_C2 + m * _AXIS_C3))


#: The Newton solves' stopping step, f32-sized: four f32 ulps of 1
#: (relative to `|x0| + τmax` in the visible sampler's cell, in radians for
#: the halo's azimuth). The residuals are f32, so a step below a few ulps of
#: the root is rounding noise; once a step is this small, Newton's error
#: after it (quadratic convergence) is far below the f32 direction returned.
NEWTON_TOL = 4.0 * float(np.finfo(np.float32).eps)


def newton_in_bracket(residual, slope, t, hi, tol, curvature=None):
    """The root in [0, hi] of the increasing `residual` from `t`: Newton's
    method kept in a shrinking bracket (a step leaving it, or a slope ≤ 0,
    bisects), a symbolic loop, each lane until a step is ≤ `tol`, at most 40
    steps (`visible::solve_cell`, `halo::Azimuth::solve`), in the type of `t`."""
    lo = dr.zeros(type(t), dr.width(t))

    def body(step, done, t, lo, hi):
        f = residual(t)
        lo = dr.select(f < 0.0, t, lo)
        hi = dr.select(f < 0.0, hi, t)
        d = slope(t)
        newton = t - f / d
        inside = (d > 0.0) & (newton >= lo) & (newton <= hi)
        # A converged step is taken even where it rounds onto the bracket's
        # end (f = 0 puts it there): bisecting would leave the root.
        step_size = dr.abs(newton - t)
        converged = inside & (step_size <= tol)
        if curvature is not None:
            # Newton's error after the step, |f''| δ²/(2 f'), within `tol`.
            converged |= inside & (step_size * step_size * dr.abs(curvature(t)) <= 2.0 * tol * d)
        nxt = dr.select(inside & (newton > lo) & (newton < hi), newton, 0.5 * (lo + hi))
        nxt = dr.select(converged, newton, nxt)
        done = converged | (dr.abs(nxt - t) <= tol)
        return step + 1, done, nxt, lo, hi

    _, _, t, _, _ = dr.while_loop(
        (mi.UInt32(0), mi.Bool(False), t, lo, hi),
        lambda step, done, t, lo, hi: (step < 40) & ~done,
        body,
    )
    return t


def acos_approx(x):
    """`math::acos_approx` (Abramowitz & Stegun 4.4.46), in the type of `x`."""
    a = dr.minimum(dr.abs(x), 1.0)
    p = 1.5707963050 + a * (-0.2145988016 + a * (0.0889789874 + a * (
        -0.0501743046 + a * (0.0308918810 + a * (-0.0170881256 + a * (
            0.0066700901 - 0.0012624911 * a))))))
    r = dr.sqrt(1.0 - a) * p
    return dr.select(x < 0.0, math.pi - r, r)


def finite_or_zero(x):
    return dr.select(dr.isfinite(x), x, 0.0)
