"""Material files (TOML: a ``[material]`` table of ``twoscale.Material``'s
keywords and an optional ``[metrics]`` table, what ``python -m twoscale.fit``
writes) are one schema read by one parser (``twoscale::io::desc``): Python
(``Material.from_toml``), C (``ts_material_desc_from_toml_file``, through
``capi/tests/c/material_file.c``) and Rust (``generator query brdf
--material``) give the same BRDF values bit for bit and refuse a bad file
with the same message."""

import pathlib
import subprocess
import tomllib

import numpy as np
import pytest

import twoscale
from twoscale.fit import Fit, load

REPO = pathlib.Path(__file__).resolve().parents[2]
GOLD = [(0.163, 3.56), (0.584, 2.15), (1.403, 1.925)]

# Keywords as a fit produces them (float64 from the solver), and the other
# kinds of material: options, a Lambertian term, the two base layers.
MATERIALS = {
    "fit-conductor": dict(beta=0.07312345678901, p=1.3712, sigma_s=0.012345678, b=3.3, c=2.4,
                          eta=[(0.2123, 3.9012), (0.4501, 2.5033), (1.3999, 1.8999)],
                          base="conductor", lambertian=0.0),
    "options": dict(beta=0.2, p=0.8, eta=GOLD, sigma_s=0.05, b=2.0, c=1.7,
                    masking="height-correlated", sigma_rel="symmetrised", halo_weight="incident"),
    "lambertian": dict(beta=0.15, p=1.1, eta=GOLD, sigma_s=0.02, b=4.0, lambertian=0.03, colour="white"),
    "plastic": dict(beta=0.08, p=0.9, eta=[(1.5, 0.0)] * 3, sigma_s=0.01, b=3.0, c=2.2,
                    base="plastic", albedo=0.7),
    "subsurface": dict(beta=0.05, p=1.0, eta=[(1.4, 0.0)] * 3, base="subsurface", albedo=0.9),
}
# What the generator's f64 reference covers (`query brdf --material`):
# conductors, with a Lambertian term as a fit of measured data has one.
CONDUCTORS = ["fit-conductor", "options", "lambertian"]

# Bad files: each refused by all three with one message.
_OK = "beta = 0.1\np = 1\neta = [[1.5, 0], [1.5, 0], [1.5, 0]]\n"
BAD = {
    "beta out of range": "[material]\nbeta = 20\np = 1\neta = [[1.5, 0], [1.5, 0], [1.5, 0]]\n",
    "negative k": "[material]\nbeta = 0.1\np = 1\neta = [[1.5, 0], [1.5, -1], [1.5, 0]]\n",
    "two pairs": "[material]\nbeta = 0.1\np = 1\neta = [[1.5, 0], [1.5, 0]]\n",
    "albedo on a conductor": f"[material]\n{_OK}albedo = 0.5\n",
    "plastic without albedo": f"[material]\n{_OK}base = \"plastic\"\n",
    "unknown base": f"[material]\n{_OK}base = \"wood\"\n",
    "unknown option value": f"[material]\n{_OK}masking = \"none\"\n",
    "unknown key": f"[material]\n{_OK}colr = \"white\"\n",
    "missing key": "[material]\np = 1\neta = [[1.5, 0], [1.5, 0], [1.5, 0]]\n",
    "wrong type": f"[material]\n{_OK}sigma_s = \"small\"\n",
    "unknown table": f"[material]\n{_OK}[fit]\nseconds = 3\n",
    "not TOML": "[material\nbeta = 0.1\n",
}


def toml_of(keywords):
    """The file a fit writes for these keywords (``Fit.toml``)."""
    material = twoscale.Material(**keywords)
    metrics = {"rmse": [0.01, 0.02, 0.03], "smape": 0.1, "relative_rms": 0.05}
    return Fit(material, keywords, metrics, cost=0.0, seconds=1.0, samples=6000).toml()


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("materials")
    paths = {}
    for name, keywords in MATERIALS.items():
        paths[name] = d / f"{name}.toml"
        paths[name].write_text(toml_of(keywords), encoding="utf-8")
    for name, text in BAD.items():
        paths[name] = d / (name.replace(" ", "-") + ".toml")
        paths[name].write_text(text, encoding="utf-8")
    return paths


@pytest.fixture(scope="module")
def c_reader(tmp_path_factory, cargo_build):
    """``capi/tests/c/material_file.c`` built against the release library."""
    lib = cargo_build("twoscale-capi")
    binary = tmp_path_factory.mktemp("c") / "material_file"
    subprocess.run(
        ["cc", "-std=c11", "-Wall", "-Wextra", "-Werror", "-pedantic", "-I", REPO / "capi" / "include",
         REPO / "capi" / "tests" / "c" / "material_file.c", "-L", lib, "-ltwoscale_capi",
         f"-Wl,-rpath,{lib}", "-lm", "-o", binary],
        check=True,
    )
    return binary


@pytest.fixture(scope="module")
def generator(cargo_build):
    return cargo_build("generator") / "generator"


@pytest.fixture(scope="module")
def directions():
    """float32 pairs over the hemisphere, a few below the horizon."""
    rng = np.random.default_rng(28)

    def unit(n):
        v = rng.normal(size=(n, 3))
        v[:, 2] = np.abs(v[:, 2])
        return v / np.linalg.norm(v, axis=1, keepdims=True)

    wi, wo = unit(300), unit(300)
    wo[:5, 2] *= -1
    return wi.astype(np.float32), wo.astype(np.float32)


def c_eval(binary, path, wi, wo):
    lines = "".join(" ".join(float(x).hex() for x in row) + "\n" for row in np.hstack([wi, wo]))
    done = subprocess.run([binary, "eval", path], input=lines, capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr
    rows = [[float.fromhex(x) for x in line.split()] for line in done.stdout.splitlines()]
    return np.array(rows, dtype=np.float32)


def generator_eval(binary, path, wi, wo):
    lines = ["channel,ix,iy,iz,ox,oy,oz"]
    for i, o in zip(wi, wo):
        for ch in range(3):
            lines.append(",".join([str(ch)] + [repr(float(x)) for x in (*i, *o)]))
    done = subprocess.run([binary, "query", "brdf", "--material", path], input="\n".join(lines) + "\n",
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    header, *rows = done.stdout.splitlines()
    column = header.split(",").index("table")
    return np.array([float(r.split(",")[column]) for r in rows], dtype=np.float32).reshape(-1, 3)


def bits(a):
    return np.ascontiguousarray(a, dtype=np.float32).view(np.uint32)


@pytest.mark.parametrize("name", MATERIALS)
def test_the_fit_toml_round_trips(files, directions, name):
    """``Material(**tomllib.load(f)["material"])``, ``Material.from_toml``,
    ``from_toml_string`` and ``twoscale.fit.load`` give the same material."""
    path = files[name]
    with open(path, "rb") as f:
        table = tomllib.load(f)
    assert set(table) == {"material", "metrics"}
    by_keywords = twoscale.Material(**table["material"])
    wi, wo = directions
    want = bits(twoscale.Material(**MATERIALS[name]).eval(wi, wo))
    for m in (by_keywords, twoscale.Material.from_toml(path), twoscale.Material.from_toml(str(path)),
              twoscale.Material.from_toml_string(path.read_text()), load(path)):
        assert repr(m) == repr(by_keywords)
        assert m.options == by_keywords.options
        np.testing.assert_array_equal(bits(m.eval(wi, wo)), want)


@pytest.mark.parametrize("name", MATERIALS)
def test_python_c_and_rust_give_the_same_values(files, directions, c_reader, generator, name):
    path = files[name]
    wi, wo = directions
    python = twoscale.Material.from_toml(path).eval(wi, wo)
    assert (python[:5] == 0).all() and (python[5:] > 0).mean() > 0.5
    np.testing.assert_array_equal(bits(c_eval(c_reader, path, wi, wo)), bits(python))
    if name in CONDUCTORS:
        np.testing.assert_array_equal(bits(generator_eval(generator, path, wi, wo)), bits(python))


@pytest.mark.parametrize("name", BAD)
def test_a_bad_file_is_refused_with_one_message(files, c_reader, generator, name):
    path = files[name]
    with pytest.raises(ValueError) as raised:
        twoscale.Material.from_toml(path)
    message = str(raised.value)
    assert message.startswith(f"{path}: "), message
    with pytest.raises(ValueError) as raised:
        twoscale.Material.from_toml_string(path.read_text())
    assert f"{path}: {raised.value}" == message

    done = subprocess.run([c_reader, "eval", path], input="", capture_output=True, text=True)
    assert done.returncode == 3, done.stdout + done.stderr
    code, c_message = done.stdout.split(": ", 1)
    assert c_message.rstrip("\n") == message
    # TS_ERR_INVALID for a refused value, TS_ERR_PARSE for the schema.
    assert code == ("error 3" if "[material] " in message else "error 8"), done.stdout

    done = subprocess.run([generator, "query", "brdf", "--material", path], input="", capture_output=True,
                          text=True)
    assert done.returncode == 1
    assert done.stderr.rstrip("\n") == f"error: {message}"


def test_refused_values_read_as_the_keywords_are_refused(files):
    """A value the file refuses is refused by ``Material(**keywords)`` with
    the same words: one validation."""
    for name in ["beta out of range", "negative k", "two pairs", "albedo on a conductor",
                 "plastic without albedo", "unknown base", "unknown option value"]:
        path = files[name]
        with pytest.raises(ValueError) as from_file:
            twoscale.Material.from_toml(path)
        with open(path, "rb") as f:
            keywords = tomllib.load(f)["material"]
        with pytest.raises(ValueError) as from_keywords:
            twoscale.Material(**keywords)
        assert str(from_file.value) == f"{path}: [material] {from_keywords.value}", name


def test_an_unreadable_file_is_an_os_error(tmp_path):
    with pytest.raises(OSError, match="cannot read"):
        twoscale.Material.from_toml(tmp_path / "absent.toml")
