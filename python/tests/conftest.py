"""Shared fixtures: Rust builds of the repository (skipped without a Rust
toolchain, as for an installed wheel's tests) and the `generator query` CLI
(built once per session)."""

import csv
import io
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def cargo():
    """The path of ``cargo``. The tests that use it (through ``cargo_build``
    too) are skipped where it is not on PATH, as for a wheel installed
    without the Rust toolchain: they build Rust code of this source tree."""
    found = shutil.which("cargo")
    if found is None:
        pytest.skip("needs the Rust toolchain (cargo) to build from the source tree")
    return found


@pytest.fixture(scope="session")
def cargo_build(cargo):
    """``build(package)``: ``cargo build --release --locked -p package`` in
    the repository (once per package), returning ``target/release``."""
    built = set()

    def build(package):
        if package not in built:
            subprocess.run(
                [cargo, "build", "--release", "--locked", "-p", package], cwd=REPO, check=True
            )
            built.add(package)
        return REPO / "target" / "release"

    return build


@pytest.fixture(scope="session")
def generator_query(cargo_build):
    """``query(quantity, columns)``: runs ``generator query`` on the rows
    given as a dict of equal-length columns and returns the output columns
    (float64 arrays by name). Fails if any row is reported bad."""
    binary = cargo_build("generator") / "generator"

    def query(quantity, columns):
        names = list(columns)
        arrays = [np.asarray(columns[n], dtype=np.float64).reshape(-1) for n in names]
        lines = [",".join(names)]
        lines += [",".join(repr(float(x)) for x in row) for row in zip(*arrays)]
        done = subprocess.run(
            [binary, "query", quantity, "--tables", REPO / "tables"],
            input="\n".join(lines) + "\n",
            capture_output=True,
            text=True,
        )
        assert done.returncode == 0, done.stderr
        rows = list(csv.DictReader(io.StringIO(done.stdout)))
        assert len(rows) == len(arrays[0])
        return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}

    return query
