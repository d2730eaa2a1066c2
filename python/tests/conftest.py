"""Shared fixtures: the `generator query` CLI (built once per session)."""

import csv
import io
import pathlib
import subprocess

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def generator_query():
    """``query(quantity, columns)``: runs ``generator query`` on the rows
    given as a dict of equal-length columns and returns the output columns
    (float64 arrays by name). Fails if any row is reported bad."""
    subprocess.run(
        ["cargo", "build", "--release", "--locked", "-p", "generator"],
        cwd=REPO,
        check=True,
    )
    binary = REPO / "target" / "release" / "generator"

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
