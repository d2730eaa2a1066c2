"""twoscale.merl against an independent transcription of the MERL data
set's reference reader (BRDFRead.cpp), byte-exact round trips and the
rejection of malformed files."""

import math
import struct

import numpy as np
import pytest

from twoscale import merl

# --- BRDFRead.cpp, transcribed line by line (NumPy over arrays) -------------
RES_THETA_H, RES_THETA_D, RES_PHI_D = 90, 90, 360
RED_SCALE, GREEN_SCALE, BLUE_SCALE = 1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0


def cross_product(v1, v2):
    return np.stack(
        [
            v1[1] * v2[2] - v1[2] * v2[1],
            v1[2] * v2[0] - v1[0] * v2[2],
            v1[0] * v2[1] - v1[1] * v2[0],
        ]
    )


def normalize(v):
    length = np.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    return v / length


def rotate_vector(vector, axis, angle):
    cos_ang, sin_ang = np.cos(angle), np.sin(angle)
    out = vector * cos_ang
    temp = axis[0] * vector[0] + axis[1] * vector[1] + axis[2] * vector[2]
    temp = temp * (1.0 - cos_ang)
    out = out + axis * temp
    cross = cross_product(axis, vector)
    return out + cross * sin_ang


def std_coords_to_half_diff_coords(theta_in, fi_in, theta_out, fi_out):
    in_vec = np.stack([np.sin(theta_in) * np.cos(fi_in), np.sin(theta_in) * np.sin(fi_in), np.cos(theta_in)])
    out_vec = np.stack([np.sin(theta_out) * np.cos(fi_out), np.sin(theta_out) * np.sin(fi_out), np.cos(theta_out)])
    half = normalize(in_vec + out_vec)
    theta_half = np.arccos(half[2])
    fi_half = np.arctan2(half[1], half[0])
    bi_normal = np.array([0.0, 1.0, 0.0])[:, None]
    normal = np.array([0.0, 0.0, 1.0])[:, None]
    temp = rotate_vector(in_vec, normal, -fi_half)
    diff = rotate_vector(temp, bi_normal, -theta_half)
    theta_diff = np.arccos(diff[2])
    fi_diff = np.arctan2(diff[1], diff[0])
    return theta_half, fi_half, theta_diff, fi_diff


def theta_half_index(theta_half):
    theta_half_deg = (theta_half / (math.pi / 2.0)) * RES_THETA_H
    temp = np.sqrt(theta_half_deg * RES_THETA_H)
    ret_val = temp.astype(np.int64)
    ret_val = np.clip(ret_val, 0, RES_THETA_H - 1)
    return np.where(theta_half <= 0.0, 0, ret_val)


def theta_diff_index(theta_diff):
    tmp = (theta_diff / (math.pi * 0.5) * RES_THETA_D).astype(np.int64)
    return np.clip(tmp, 0, RES_THETA_D - 1)


def phi_diff_index(phi_diff):
    phi_diff = np.where(phi_diff < 0.0, phi_diff + math.pi, phi_diff)
    tmp = (phi_diff / math.pi * RES_PHI_D / 2).astype(np.int64)
    return np.clip(tmp, 0, RES_PHI_D // 2 - 1)


def lookup_index(theta_in, fi_in, theta_out, fi_out):
    theta_half, _, theta_diff, fi_diff = std_coords_to_half_diff_coords(theta_in, fi_in, theta_out, fi_out)
    return (
        phi_diff_index(fi_diff)
        + theta_diff_index(theta_diff) * RES_PHI_D // 2
        + theta_half_index(theta_half) * RES_PHI_D // 2 * RES_THETA_D
    )


def read_brdf(data):
    dims = struct.unpack_from("<3i", data, 0)
    n = dims[0] * dims[1] * dims[2]
    assert n == RES_THETA_H * RES_THETA_D * RES_PHI_D // 2
    return np.frombuffer(data, dtype="<f8", count=3 * n, offset=12)


# ---------------------------------------------------------------------------


def _directions(theta, phi):
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=1)


def test_index_matches_the_reference_reader_on_a_million_pairs():
    rng = np.random.default_rng(2003)
    n = 1_000_000
    ti, to = rng.uniform(0, np.pi / 2, n), rng.uniform(0, np.pi / 2, n)
    pi, po = rng.uniform(-np.pi, np.pi, n), rng.uniform(-np.pi, np.pi, n)
    # A tenth near the mirror direction, to reach the smallest θh bins.
    m = n // 10
    to[:m] = ti[:m] + rng.normal(0, 2e-4, m)
    po[:m] = pi[:m] + np.pi + rng.normal(0, 2e-4, m) / np.maximum(np.sin(ti[:m]), 1e-3)
    to[:m] = np.abs(to[:m])
    expected = lookup_index(ti, pi, to, po)
    got = merl.index(_directions(ti, pi), _directions(to, po))
    assert got.shape == (n,)
    assert np.count_nonzero(got != expected) == 0
    # The pairs reach every θh, θd and φd bin.
    assert len(np.unique(expected // 16200)) == 90
    assert len(np.unique(expected % 180)) == 180


def _random_file(rng):
    stored = rng.uniform(0, 3000, merl.SHAPE)
    stored[rng.uniform(size=merl.SHAPE) < 0.01] = -1.0
    return struct.pack("<3i", 90, 90, 180) + stored.astype("<f8").tobytes()


def test_values_and_scale_follow_the_reference_reader(tmp_path):
    rng = np.random.default_rng(1)
    data = _random_file(rng)
    path = tmp_path / "x.binary"
    path.write_bytes(data)
    brdf = merl.read(path)
    stored = read_brdf(data).reshape(3, -1)
    k = rng.integers(0, merl.BINS, 10000)
    for c, scale in enumerate([RED_SCALE, GREEN_SCALE, BLUE_SCALE]):
        expected = stored[c, k] * scale
        expected[stored[c, k] < 0] = np.nan
        np.testing.assert_array_equal(brdf.reshape(3, -1)[c, k], expected)
    # lookup: the value at the bin of the directions, via the reference index.
    ti, to = rng.uniform(0, np.pi / 2, 1000), rng.uniform(0, np.pi / 2, 1000)
    pi, po = rng.uniform(-np.pi, np.pi, 1000), rng.uniform(-np.pi, np.pi, 1000)
    ref = lookup_index(ti, pi, to, po)
    np.testing.assert_array_equal(
        merl.lookup(brdf, _directions(ti, pi), _directions(to, po)),
        brdf.reshape(3, -1)[:, ref].T,
    )


def test_round_trips_are_byte_exact(tmp_path):
    rng = np.random.default_rng(2)
    # Every bit pattern, as the stored values of a file: raw mode.
    stored = rng.integers(0, 2**63, merl.SHAPE[0] * merl.BINS, dtype=np.int64).view(np.float64)
    data = struct.pack("<3i", 90, 90, 180) + stored.astype("<f8").tobytes()
    (tmp_path / "a").write_bytes(data)
    merl.write(tmp_path / "b", merl.read(tmp_path / "a", raw=True), raw=True)
    assert (tmp_path / "b").read_bytes() == data
    # BRDF values: array → file → array, and file → array → file, exact.
    brdf = rng.uniform(0, 5, merl.SHAPE)
    brdf[rng.uniform(size=merl.SHAPE) < 0.01] = np.nan
    merl.write(tmp_path / "c", brdf)
    back = merl.read(tmp_path / "c")
    assert back.tobytes() == merl.read(tmp_path / "c").tobytes()
    once = (tmp_path / "c").read_bytes()
    merl.write(tmp_path / "d", back)
    assert (tmp_path / "d").read_bytes() == once
    # What the reference reader scales back is what read gives, and within
    # an ulp of the array (not every f64 is a stored value times the scale).
    ref = read_brdf(once).reshape(merl.SHAPE) * np.array([RED_SCALE, GREEN_SCALE, BLUE_SCALE])[:, None, None, None]
    finite = ~np.isnan(brdf)
    np.testing.assert_array_equal(ref[finite], back[finite])
    assert np.all(np.abs(ref[finite] - brdf[finite]) <= np.spacing(brdf[finite]))
    assert np.all(read_brdf(once).reshape(merl.SHAPE)[~finite] < 0)
    np.testing.assert_array_equal(np.isnan(back), ~finite)


def test_malformed_files_are_rejected(tmp_path):
    good = struct.pack("<3i", 90, 90, 180) + bytes(8 * 3 * merl.BINS)
    assert len(good) == merl.FILE_BYTES
    with pytest.raises(ValueError, match="bytes, expected"):
        merl.decode(good[:-8])
    with pytest.raises(ValueError, match="bytes, expected"):
        merl.decode(good + b"\0")
    with pytest.raises(ValueError, match="bytes, expected"):
        merl.decode(b"\x5a\0\0\0")
    with pytest.raises(ValueError, match=r"header dimensions \[180, 90, 90\]"):
        merl.decode(struct.pack("<3i", 180, 90, 90) + good[12:])
    with pytest.raises(ValueError, match="shape"):
        merl.encode(np.zeros((3, 90, 90, 179)))
    # The expected shape is named (it was "dimensionality mismatch: from=3, to=4").
    with pytest.raises(ValueError, match=r"must have shape \(3, 90, 90, 180\) .*got \[3, 90, 90\]"):
        merl.write(tmp_path / "x", np.zeros((3, 90, 90)))
    assert not (tmp_path / "x").exists()
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        merl.index(np.zeros((4, 2)), np.zeros((4, 2)))


def test_write_refuses_values_a_brdf_cannot_have(tmp_path):
    """A negative BRDF value used to be stored as missing and an infinite
    one as is; both are refused, naming the first one's index. NaN is the
    missing marker; raw=True writes stored values as they are."""
    values = np.ones(merl.SHAPE)
    values[0, 0, 0, 0] = np.nan
    for bad in (-0.5, np.inf, -np.inf):
        values[1, 2, 3, 4] = bad
        with pytest.raises(ValueError, match=rf"^values\[1, 2, 3, 4\] = {bad}: a BRDF value must be finite and ≥ 0"):
            merl.write(tmp_path / "bad", values)
        assert not (tmp_path / "bad").exists()
    values[1, 2, 3, 4] = 0.0
    merl.write(tmp_path / "good", values)
    assert np.isnan(merl.read(tmp_path / "good")[0, 0, 0, 0])
    values[1, 2, 3, 4] = -1.0
    merl.write(tmp_path / "raw", values, raw=True)
    assert np.isnan(merl.read(tmp_path / "raw")[1, 2, 3, 4])


def test_bin_centres_lie_in_their_bins():
    wi, wo = merl.bin_centres()
    assert wi.shape == wo.shape == (merl.BINS, 3)
    up = (wi[:, 2] > 0) & (wo[:, 2] > 0)
    k = np.flatnonzero(up)
    np.testing.assert_array_equal(merl.index(wi[k], wo[k]), k)
    # Via the reference's own index from angles.
    ti, pi = np.arccos(wi[k, 2]), np.arctan2(wi[k, 1], wi[k, 0])
    to, po = np.arccos(wo[k, 2]), np.arctan2(wo[k, 1], wo[k, 0])
    assert np.count_nonzero(lookup_index(ti, pi, to, po) != k) == 0
    np.testing.assert_allclose(np.linalg.norm(wi, axis=1), 1.0, atol=1e-12)
