"""The package as NumPy users expect it: inputs of shape (..., 3) broadcast,
every public function and getter documented with its arguments in order,
type stubs that match the extension (mypy's stubtest) and ship in the
installed package."""

import importlib.resources
import inspect
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import twoscale
from twoscale import lookup, reference

RNG = np.random.default_rng(23)
GOLD = "gold-hp17-geometry"


def hemisphere(*shape):
    """Unit vectors of shape (*shape, 3) with z in [0.05, 1]."""
    z = RNG.uniform(0.05, 1.0, shape)
    phi = RNG.uniform(0.0, 2 * np.pi, shape)
    r = np.sqrt(1 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def test_eval_pdf_sample_broadcast_leading_shapes():
    m = twoscale.Material.preset(GOLD)
    wi, wo = hemisphere(4, 5), hemisphere(4, 5)
    flat = m.eval(wi.reshape(-1, 3), wo.reshape(-1, 3))
    value = m.eval(wi, wo)
    assert value.shape == (4, 5, 3)
    np.testing.assert_array_equal(value, flat.reshape(4, 5, 3))
    assert m.pdf(wi, wo).shape == (4, 5)
    np.testing.assert_array_equal(m.pdf(wi, wo), m.pdf(wi.reshape(-1, 3), wo.reshape(-1, 3)).reshape(4, 5))
    # one wo against a (4, 5) batch of wi, and (4, 1) against (5,): NumPy's rules
    np.testing.assert_array_equal(m.eval(wi, wo[0, 0]), m.eval(wi, np.broadcast_to(wo[0, 0], wi.shape)))
    column, row = hemisphere(4, 1), hemisphere(5)
    expected = m.eval(np.broadcast_to(column, (4, 5, 3)), np.broadcast_to(row, (4, 5, 3)))
    np.testing.assert_array_equal(m.eval(column, row), expected)
    u = RNG.random((4, 5, 3))
    dirs, pdf, weight = m.sample(wi, u)
    assert dirs.shape == (4, 5, 3) and pdf.shape == (4, 5) and weight.shape == (4, 5, 3)
    flat_dirs, flat_pdf, _ = m.sample(wi.reshape(-1, 3), u.reshape(-1, 3))
    np.testing.assert_array_equal(dirs.reshape(-1, 3), flat_dirs)
    np.testing.assert_array_equal(pdf.reshape(-1), flat_pdf)


def test_single_directions_and_lists():
    m = twoscale.Material.preset(GOLD)
    wi, wo = [0.5, 0.0, 0.866], [-0.45, 0.05, 0.89]
    value = m.eval(np.array(wi), np.array(wo))
    assert value.shape == (3,) and value.dtype == np.float32
    np.testing.assert_array_equal(value, m.eval(np.array([wi]), np.array([wo]))[0])
    np.testing.assert_array_equal(m.eval(wi, wo), value)  # lists, as numpy.asarray reads them
    assert m.pdf(wi, wo).shape == ()
    assert m.pdf(wi, wo) == m.pdf([wi], [wo])[0]
    np.testing.assert_array_equal(m.eval([0, 0, 1], [0, 0, 1]), m.eval([0.0, 0.0, 1.0], [0.0, 0.0, 1.0]))
    assert m.eval_reference(np.array(wi), np.array(wo)).shape == (3,)


def test_one_wavelength_brdf_broadcasts():
    params = dict(beta=0.1, p=1.0, sigma_s=0.02, b=3.0, c=2.0, n=0.584, k=2.15, lam=0.526)
    wi, wo = hemisphere(2, 3), hemisphere(3)
    value = lookup.brdf(wi, wo, **params)
    assert value.shape == (2, 3)
    flat = lookup.brdf(wi.reshape(-1, 3), np.tile(wo, (2, 1)), **params)
    np.testing.assert_array_equal(value.reshape(-1), flat)
    assert reference.brdf(wi[0, 0], wo[0], **params).shape == ()


def test_shapes_that_do_not_broadcast_are_named():
    m = twoscale.Material.preset(GOLD)
    with pytest.raises(ValueError, match=r"wi of shape \[2, 3\] and wo of shape \[3, 3\] do not broadcast"):
        m.eval(hemisphere(2), hemisphere(3))
    with pytest.raises(ValueError, match=r"u must have shape \(\.\.\., 3\)"):
        m.sample(hemisphere(2), np.zeros((2, 2)))


def public_callables():
    """(qualified name, object) of every public function, method and getter
    of the package, the extension, lookup and reference (twoscale.merl
    documents its functions in its module docstring)."""
    out = []
    for module in (twoscale, twoscale._native, lookup, reference):
        for name in getattr(module, "__all__", dir(module)):
            obj = getattr(module, name)
            if not name.startswith("_") and (inspect.isroutine(obj) or inspect.isclass(obj)):
                out.append((f"{module.__name__}.{name}", obj))
    for name, obj in vars(twoscale.Material).items():
        if not name.startswith("_"):
            out.append((f"Material.{name}", getattr(twoscale.Material, name)))
    return out


def call_arguments(text):
    """The top-level comma-separated arguments of the call ``(…)`` that
    ``text`` opens with (defaults may hold parentheses: ``fixed=()``)."""
    depth, current, out = 0, "", []
    for ch in text:
        if ch in "([{":
            depth += 1
            if depth == 1:
                continue
        elif ch in ")]}":
            depth -= 1
            if depth == 0:
                break
        if ch == "," and depth == 1:
            out.append(current.replace("\n", " "))
            current = ""
        else:
            current += ch
    return out + [current.replace("\n", " ")]


@pytest.mark.parametrize("name,obj", public_callables(), ids=[n for n, _ in public_callables()])
def test_public_names_are_documented_with_their_arguments_in_order(name, obj):
    doc = inspect.getdoc(obj)
    assert doc and len(doc) > 20, f"{name} has no docstring"
    if inspect.isroutine(obj) or inspect.isclass(obj):
        params = [p for p in inspect.signature(obj).parameters if p not in ("self", "cls")]
        # the docstring opens with the call: name(the parameters in order)
        assert doc.startswith(obj.__name__ + "("), f"{name}: {doc[:60]!r}"
        listed = call_arguments(doc[len(obj.__name__) :])
        listed = [a.split("=")[0].strip().lstrip("*") for a in listed]
        listed = [a for a in listed if a not in ("", "/")]
        assert listed == params, f"{name}: the docstring lists {listed}, the signature {params}"


@pytest.mark.parametrize("module", [twoscale, twoscale._native, lookup, reference])
def test_modules_are_documented(module):
    assert module.__doc__ and len(module.__doc__) > 100


def test_stubs_and_py_typed_ship_with_the_package():
    files = importlib.resources.files("twoscale")
    for name in ("py.typed", "_native.pyi"):
        assert files.joinpath(name).is_file(), name


def test_stubs_match_the_extension():
    """mypy's stubtest: every name, signature and property of the installed
    extension against _native.pyi (and the modules' own annotations)."""
    done = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "twoscale._native", "twoscale.lookup",
         "twoscale.reference", "twoscale._columns"],
        capture_output=True, text=True,
    )
    assert done.returncode == 0, done.stdout + done.stderr


def test_package_type_checks(tmp_path):
    """mypy --strict on a user's script: the stubs give the result types."""
    script = tmp_path / "use.py"
    script.write_text(
        "import numpy as np\n"
        "from numpy.typing import NDArray\n"
        "import twoscale\n"
        "m = twoscale.Material.preset('gold-rough')\n"
        "rho: NDArray[np.float32] = m.eval(np.zeros((4, 5, 3)), [0.0, 0.0, 1.0])\n"
        "wo, pdf, weight = m.sample([0.0, 0.0, 1.0], np.zeros(3))\n"
        "g: float | NDArray[np.float64] = twoscale.lookup.g1(1.0, 0.5)\n"
        "beta: float = m.beta\n"
    )
    done = subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", script],
        capture_output=True, text=True, cwd=tmp_path,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    bad = tmp_path / "bad.py"
    bad.write_text("import twoscale\nx: str = twoscale.Material.preset('gold-rough').beta\n")
    done = subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", bad],
        capture_output=True, text=True, cwd=tmp_path,
    )
    assert done.returncode == 1 and "Incompatible types" in done.stdout, done.stdout
