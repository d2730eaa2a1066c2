//! The MERL BRDF file format (Matusik et al. 2003), exactly as the data set's
//! reference reader `BRDFRead.cpp` reads it.
//!
//! A file is three little-endian `i32` dimensions `(90, 90, 180)` followed by
//! `3 × 1 458 000` little-endian `f64` values: the red block, then the green
//! block, then the blue block. Within a block the value of bin
//! `(i_h, i_d, i_φ)` is at [`flat_index`] `= i_φ + 180 (i_d + 90 i_h)`, with
//!
//! * `i_h = ⌊√(θh / (π/2)) · 90⌋` (the half-vector angle, binned on its
//!   square root: [`theta_half_index`]),
//! * `i_d = ⌊θd / (π/2) · 90⌋` ([`theta_diff_index`]),
//! * `i_φ = ⌊φd / π · 180⌋` with φd folded to `[0, π)` by reciprocity
//!   (`φd → φd + π` for φd < 0: [`phi_diff_index`]),
//!
//! each clamped to its range, where `(θh, φh, θd, φd)` are Rusinkiewicz's
//! half/difference angles of the incident direction ([`half_diff`]). A value
//! read from channel `c` is multiplied by [`SCALE`]`[c]`
//! (`1/1500, 1.15/1500, 1.66/1500`) to give the BRDF in sr⁻¹; a negative
//! stored value marks a missing sample ([`scaled`] returns `None`).
//!
//! Everything here is `no_std` and allocation-free: the index and bin math
//! works on angles or direction vectors, [`decode`] and [`encode`] read and
//! write a whole file between a byte slice and a caller's `f64` buffer (the
//! stored, unscaled values, so a decode/encode round trip is byte-exact).
//! `read_file` and `write_file` (feature `std`) do the same on paths.

use crate::math::{acos, atan2, cos, sin, sqrt};
use core::f64::consts::PI;

/// Number of θh bins.
pub const THETA_H_BINS: usize = 90;
/// Number of θd bins.
pub const THETA_D_BINS: usize = 90;
/// Number of φd bins (φd over `[0, π)`; the reference reader's
/// `BRDF_SAMPLING_RES_PHI_D / 2`).
pub const PHI_D_BINS: usize = 180;
/// The dimensions a file's header must hold, in file order.
pub const DIMENSIONS: [i32; 3] = [THETA_H_BINS as i32, THETA_D_BINS as i32, PHI_D_BINS as i32];
/// Bins per colour channel: 90 × 90 × 180 = 1 458 000.
pub const BINS: usize = THETA_H_BINS * THETA_D_BINS * PHI_D_BINS;
/// Stored values in a file: three channels of [`BINS`].
pub const VALUES: usize = 3 * BINS;
/// Bytes of the header (three `i32`).
pub const HEADER_BYTES: usize = 12;
/// Bytes of a whole file: the header and [`VALUES`] `f64`.
pub const FILE_BYTES: usize = HEADER_BYTES + 8 * VALUES;
/// The reference reader's scale factors of the red, green and blue blocks
/// (`RED_SCALE`, `GREEN_SCALE`, `BLUE_SCALE`): BRDF = stored × scale.
pub const SCALE: [f64; 3] = [1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0];
/// The stored value [`raw_for`] writes for a missing sample.
pub const MISSING: f64 = -1.0;

/// Why bytes are not a MERL file, or a buffer does not fit one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MerlError {
    /// The byte length is not [`FILE_BYTES`] (or too short for the header).
    Length {
        /// [`FILE_BYTES`].
        expected: usize,
        /// The length given.
        found: usize,
    },
    /// The header's dimensions are not [`DIMENSIONS`].
    Dimensions {
        /// The three dimensions read.
        found: [i32; 3],
    },
    /// A caller's value buffer does not hold exactly [`VALUES`] values.
    Buffer {
        /// [`VALUES`].
        expected: usize,
        /// The buffer's length.
        found: usize,
    },
}

impl core::fmt::Display for MerlError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            MerlError::Length { expected, found } => write!(
                f,
                "not a MERL BRDF file: {found} bytes, expected {expected} (a 12-byte header and 3 × {BINS} f64)"
            ),
            MerlError::Dimensions { found } => write!(
                f,
                "not a MERL BRDF file: header dimensions {found:?}, expected {DIMENSIONS:?}"
            ),
            MerlError::Buffer { expected, found } => write!(
                f,
                "MERL value buffer holds {found} values, expected {expected} (3 × {BINS})"
            ),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for MerlError {}

/// Rusinkiewicz's half/difference angles of a direction pair, radians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfDiff {
    /// Angle of the half vector from the normal, `[0, π]`.
    pub theta_half: f64,
    /// Azimuth of the half vector, `(−π, π]`.
    pub phi_half: f64,
    /// Angle of the incident direction from the half vector, `[0, π]`.
    pub theta_diff: f64,
    /// Azimuth of the incident direction about the half vector, `(−π, π]`.
    pub phi_diff: f64,
}

/// The reference reader's `rotate_vector`: `v` rotated by `angle` about the
/// unit `axis` (Rodrigues: `v cos a + axis (axis·v)(1 − cos a) + (axis × v) sin a`),
/// in the reader's order of operations.
fn rotate(v: [f64; 3], axis: [f64; 3], angle: f64) -> [f64; 3] {
    let (c, s) = (cos(angle), sin(angle));
    let mut out = [v[0] * c, v[1] * c, v[2] * c];
    let t = (axis[0] * v[0] + axis[1] * v[1] + axis[2] * v[2]) * (1.0 - c);
    for k in 0..3 {
        out[k] += axis[k] * t;
    }
    let cross = [
        axis[1] * v[2] - axis[2] * v[1],
        axis[2] * v[0] - axis[0] * v[2],
        axis[0] * v[1] - axis[1] * v[0],
    ];
    for k in 0..3 {
        out[k] += cross[k] * s;
    }
    out
}

/// `acos` of a cosine clamped to `[−1, 1]` (rounding can push a normalised
/// component past 1; the reference would return NaN there).
fn acos_clamped(x: f64) -> f64 {
    acos(x.max(-1.0).min(1.0))
}

/// The reference reader's `std_coords_to_half_diff_coords` on direction
/// vectors: `h = (i + o)/|i + o|`, `θh = acos h_z`, `φh = atan2(h_y, h_x)`,
/// `d = R_y(−θh) R_z(−φh) i`, `θd = acos d_z`, `φd = atan2(d_y, d_x)`.
/// `i` and `o` must be unit vectors (`i` the incident direction).
pub fn half_diff_of_vectors(i: [f64; 3], o: [f64; 3]) -> HalfDiff {
    let h = [i[0] + o[0], i[1] + o[1], i[2] + o[2]];
    let norm = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    let h = [h[0] / norm, h[1] / norm, h[2] / norm];
    let theta_half = acos_clamped(h[2]);
    let phi_half = atan2(h[1], h[0]);
    let t = rotate(i, [0.0, 0.0, 1.0], -phi_half);
    let d = rotate(t, [0.0, 1.0, 0.0], -theta_half);
    HalfDiff {
        theta_half,
        phi_half,
        theta_diff: acos_clamped(d[2]),
        phi_diff: atan2(d[1], d[0]),
    }
}

/// The unit vector at polar angle `theta` and azimuth `phi`, as the reference
/// reader builds it: `(sin θ cos φ, sin θ sin φ, cos θ)`.
pub fn direction(theta: f64, phi: f64) -> [f64; 3] {
    let st = sin(theta);
    [st * cos(phi), st * sin(phi), cos(theta)]
}

/// [`half_diff_of_vectors`] of the directions at `(θi, φi)` and `(θo, φo)`:
/// the reference reader's `std_coords_to_half_diff_coords`.
pub fn half_diff(theta_in: f64, phi_in: f64, theta_out: f64, phi_out: f64) -> HalfDiff {
    half_diff_of_vectors(direction(theta_in, phi_in), direction(theta_out, phi_out))
}

/// `x as usize` clamped to `0..n` (NaN → 0).
fn bin(x: f64, n: usize) -> usize {
    // `as` saturates (negative and NaN → 0).
    (x as usize).min(n - 1)
}

/// The θh bin: `⌊√(θh / (π/2) · 90 · 90)⌋` clamped to `0..90`, 0 for
/// `θh ≤ 0` (the reference's `theta_half_index`).
pub fn theta_half_index(theta_half: f64) -> usize {
    if !(theta_half > 0.0) {
        return 0;
    }
    let theta_half_deg = (theta_half / (PI / 2.0)) * THETA_H_BINS as f64;
    bin(sqrt(theta_half_deg * THETA_H_BINS as f64), THETA_H_BINS)
}

/// The θd bin: `⌊θd / (π/2) · 90⌋` clamped to `0..90` (`theta_diff_index`).
pub fn theta_diff_index(theta_diff: f64) -> usize {
    bin(theta_diff / (PI * 0.5) * THETA_D_BINS as f64, THETA_D_BINS)
}

/// The φd bin: φd folded to `[0, π]` by reciprocity (`+π` when negative),
/// then `⌊φd / π · 360 / 2⌋` clamped to `0..180` (`phi_diff_index`).
pub fn phi_diff_index(phi_diff: f64) -> usize {
    let phi = if phi_diff < 0.0 {
        phi_diff + PI
    } else {
        phi_diff
    };
    bin(phi / PI * (2 * PHI_D_BINS) as f64 / 2.0, PHI_D_BINS)
}

/// The position in a channel block of bin `(i_h, i_d, i_φ)`:
/// `i_φ + 180 (i_d + 90 i_h)`.
pub const fn flat_index(i_h: usize, i_d: usize, i_phi: usize) -> usize {
    i_phi + PHI_D_BINS * (i_d + THETA_D_BINS * i_h)
}

/// The bin (position in a channel block, `0..BINS`) of a direction pair
/// given by its half/difference angles.
pub fn index_of_half_diff(a: HalfDiff) -> usize {
    flat_index(
        theta_half_index(a.theta_half),
        theta_diff_index(a.theta_diff),
        phi_diff_index(a.phi_diff),
    )
}

/// The bin of the directions at `(θi, φi)` and `(θo, φo)`: the reference
/// reader's `lookup_brdf_val` index.
pub fn index(theta_in: f64, phi_in: f64, theta_out: f64, phi_out: f64) -> usize {
    index_of_half_diff(half_diff(theta_in, phi_in, theta_out, phi_out))
}

/// The bin of the unit direction vectors `i` (incident) and `o`.
pub fn index_of_vectors(i: [f64; 3], o: [f64; 3]) -> usize {
    index_of_half_diff(half_diff_of_vectors(i, o))
}

/// The half/difference angles at the centre of bin `index` (`None` past
/// [`BINS`]): `θh = (π/2) ((i_h + ½)/90)²`, `θd = (π/2)(i_d + ½)/90`,
/// `φd = π (i_φ + ½)/180`, `φh = 0`.
pub fn bin_centre(index: usize) -> Option<HalfDiff> {
    if index >= BINS {
        return None;
    }
    let i_phi = index % PHI_D_BINS;
    let i_d = (index / PHI_D_BINS) % THETA_D_BINS;
    let i_h = index / (PHI_D_BINS * THETA_D_BINS);
    let t = (i_h as f64 + 0.5) / THETA_H_BINS as f64;
    Some(HalfDiff {
        theta_half: PI / 2.0 * t * t,
        phi_half: 0.0,
        theta_diff: PI / 2.0 * (i_d as f64 + 0.5) / THETA_D_BINS as f64,
        phi_diff: PI * (i_phi as f64 + 0.5) / PHI_D_BINS as f64,
    })
}

/// The incident and outgoing unit vectors of half/difference angles:
/// `i = R_z(φh) R_y(θh) d` with `d` the direction at `(θd, φd)`, and `o` the
/// mirror of `i` about the half vector, `o = R_z(φh) R_y(θh) (−d_x, −d_y, d_z)`.
/// Either may lie below the horizon (`z < 0`): such bins hold no measurement.
pub fn vectors_of_half_diff(a: HalfDiff) -> ([f64; 3], [f64; 3]) {
    let d = direction(a.theta_diff, a.phi_diff);
    let to_world = |v: [f64; 3]| {
        rotate(
            rotate(v, [0.0, 1.0, 0.0], a.theta_half),
            [0.0, 0.0, 1.0],
            a.phi_half,
        )
    };
    (to_world(d), to_world([-d[0], -d[1], d[2]]))
}

/// The BRDF (sr⁻¹) of a stored value of `channel` (0 red, 1 green, 2 blue):
/// `stored × SCALE[channel]`, `None` for a missing (negative or NaN) value
/// or a channel past 2.
pub fn scaled(stored: f64, channel: usize) -> Option<f64> {
    let scale = *SCALE.get(channel)?;
    (stored >= 0.0).then_some(stored * scale)
}

/// The stored value whose [`scaled`] value is `brdf`: the `f64` nearest
/// `brdf / SCALE[channel]` among those that scale back to exactly `brdf`
/// when there is one (always, for a value [`scaled`] returned), else
/// `brdf / SCALE[channel]`; [`MISSING`] for a negative or NaN `brdf`.
/// A channel past 2 gives [`MISSING`].
pub fn raw_for(brdf: f64, channel: usize) -> f64 {
    let Some(&scale) = SCALE.get(channel) else {
        return MISSING;
    };
    if !(brdf >= 0.0) {
        return MISSING;
    }
    let y = brdf / scale;
    if y * scale == brdf || !y.is_finite() || y == 0.0 {
        return y;
    }
    // A non-negative finite f64's neighbours are its bit pattern ± 1.
    let bits = y.to_bits();
    for candidate in [bits - 1, bits + 1] {
        let z = f64::from_bits(candidate);
        if z * scale == brdf {
            return z;
        }
    }
    y
}

/// Checks a file's header and length.
fn check(bytes: &[u8]) -> Result<(), MerlError> {
    let length = MerlError::Length {
        expected: FILE_BYTES,
        found: bytes.len(),
    };
    let Some(header) = bytes.get(..HEADER_BYTES) else {
        return Err(length);
    };
    let mut found = [0i32; 3];
    for (k, dim) in found.iter_mut().enumerate() {
        let mut b = [0u8; 4];
        b.copy_from_slice(&header[4 * k..4 * k + 4]);
        *dim = i32::from_le_bytes(b);
    }
    if found != DIMENSIONS {
        return Err(MerlError::Dimensions { found });
    }
    if bytes.len() != FILE_BYTES {
        return Err(length);
    }
    Ok(())
}

/// Decodes a whole file into `stored` ([`VALUES`] values in file order: red,
/// green, blue blocks of [`BINS`], each indexed by [`flat_index`]), unscaled.
/// Rejects a wrong header or length, or a wrong-sized buffer.
pub fn decode(bytes: &[u8], stored: &mut [f64]) -> Result<(), MerlError> {
    check(bytes)?;
    if stored.len() != VALUES {
        return Err(MerlError::Buffer {
            expected: VALUES,
            found: stored.len(),
        });
    }
    for (value, chunk) in stored.iter_mut().zip(bytes[HEADER_BYTES..].chunks_exact(8)) {
        let mut b = [0u8; 8];
        b.copy_from_slice(chunk);
        *value = f64::from_le_bytes(b);
    }
    Ok(())
}

/// Encodes [`VALUES`] stored values (file order, unscaled) and the header
/// into `bytes`, which must be [`FILE_BYTES`] long.
pub fn encode(stored: &[f64], bytes: &mut [u8]) -> Result<(), MerlError> {
    if stored.len() != VALUES {
        return Err(MerlError::Buffer {
            expected: VALUES,
            found: stored.len(),
        });
    }
    if bytes.len() != FILE_BYTES {
        return Err(MerlError::Length {
            expected: FILE_BYTES,
            found: bytes.len(),
        });
    }
    for (k, dim) in DIMENSIONS.iter().enumerate() {
        bytes[4 * k..4 * k + 4].copy_from_slice(&dim.to_le_bytes());
    }
    for (value, chunk) in stored.iter().zip(bytes[HEADER_BYTES..].chunks_exact_mut(8)) {
        chunk.copy_from_slice(&value.to_le_bytes());
    }
    Ok(())
}

/// The BRDF (sr⁻¹, red, green, blue) of the stored values `stored` (as
/// [`decode`] fills them) at the unit directions `i` and `o`: the reference
/// reader's `lookup_brdf_val`. `None` when a channel is missing there or the
/// buffer is not [`VALUES`] long.
pub fn lookup(stored: &[f64], i: [f64; 3], o: [f64; 3]) -> Option<[f64; 3]> {
    if stored.len() != VALUES {
        return None;
    }
    let k = index_of_vectors(i, o);
    Some([
        scaled(stored[k], 0)?,
        scaled(stored[k + BINS], 1)?,
        scaled(stored[k + 2 * BINS], 2)?,
    ])
}

/// Reads a MERL file's stored values ([`decode`]); a malformed file is an
/// [`std::io::ErrorKind::InvalidData`] error carrying the [`MerlError`].
#[cfg(feature = "std")]
pub fn read_file(path: impl AsRef<std::path::Path>) -> std::io::Result<std::vec::Vec<f64>> {
    let bytes = std::fs::read(path)?;
    let mut stored = std::vec![0.0; VALUES];
    decode(&bytes, &mut stored)
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))?;
    Ok(stored)
}

/// Writes [`VALUES`] stored values as a MERL file ([`encode`]).
#[cfg(feature = "std")]
pub fn write_file(path: impl AsRef<std::path::Path>, stored: &[f64]) -> std::io::Result<()> {
    let mut bytes = std::vec![0u8; FILE_BYTES];
    encode(stored, &mut bytes)
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidInput, e))?;
    std::fs::write(path, bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::Lcg;

    #[test]
    fn bins_follow_the_reference_formulas() {
        // θh is binned on its square root: θh = (π/2)(k/90)² starts bin k.
        for k in 1..THETA_H_BINS {
            let t = k as f64 / 90.0;
            let start = PI / 2.0 * t * t;
            assert_eq!(theta_half_index(start * (1.0 + 1e-9)), k);
            assert_eq!(theta_half_index(start * (1.0 - 1e-9)), k - 1);
        }
        assert_eq!(theta_half_index(0.0), 0);
        assert_eq!(theta_half_index(PI), THETA_H_BINS - 1);
        assert_eq!(theta_diff_index(PI / 4.0 + 1e-9), 45);
        // φd folds by π: −π/2 and π/2 share a bin; π clamps into the last.
        assert_eq!(phi_diff_index(-PI / 2.0), phi_diff_index(PI / 2.0));
        assert_eq!(phi_diff_index(PI / 2.0 + 1e-9), 90);
        assert_eq!(phi_diff_index(PI), PHI_D_BINS - 1);
        assert_eq!(flat_index(1, 2, 3), 3 + 180 * (2 + 90));
    }

    #[test]
    fn bin_centres_map_back_to_their_bin() {
        let mut rng = Lcg(7);
        for _ in 0..20_000 {
            let k = (rng.next() * BINS as f64) as usize;
            let centre = bin_centre(k).unwrap();
            let (i, o) = vectors_of_half_diff(centre);
            assert_eq!(index_of_vectors(i, o), k, "bin {k}");
            let back = half_diff_of_vectors(i, o);
            assert!((back.theta_half - centre.theta_half).abs() < 1e-9);
            assert!((back.theta_diff - centre.theta_diff).abs() < 1e-9);
        }
        assert!(bin_centre(BINS).is_none());
    }

    #[test]
    fn index_is_reciprocal_and_rotation_invariant() {
        let mut rng = Lcg(11);
        let mut mismatches = 0;
        for _ in 0..10_000 {
            let (ti, to) = (rng.next() * PI / 2.0, rng.next() * PI / 2.0);
            let (pi, po) = (rng.next() * 2.0 * PI, rng.next() * 2.0 * PI);
            let k = index(ti, pi, to, po);
            // Exchanging i and o moves φd by π; a bin boundary can split them.
            mismatches += usize::from(index(to, po, ti, pi) != k);
            mismatches += usize::from(index(ti, pi + 1.0, to, po + 1.0) != k);
        }
        assert!(mismatches < 20, "{mismatches}");
    }

    #[test]
    fn encode_decode_round_trip_is_byte_exact() {
        let mut rng = Lcg(3);
        let mut bytes = std::vec![0u8; FILE_BYTES];
        bytes[..HEADER_BYTES].copy_from_slice(&[90, 0, 0, 0, 90, 0, 0, 0, 180, 0, 0, 0]);
        for chunk in bytes[HEADER_BYTES..].chunks_exact_mut(8) {
            let bits = (rng.next().to_bits() << 11) ^ rng.next().to_bits();
            chunk.copy_from_slice(&bits.to_le_bytes());
        }
        let mut stored = std::vec![0.0; VALUES];
        decode(&bytes, &mut stored).unwrap();
        let mut again = std::vec![0u8; FILE_BYTES];
        encode(&stored, &mut again).unwrap();
        assert!(bytes == again);
    }

    #[test]
    fn wrong_files_and_buffers_are_rejected() {
        let mut stored = std::vec![0.0; VALUES];
        let mut bytes = std::vec![0u8; FILE_BYTES];
        encode(&stored, &mut bytes).unwrap();
        assert_eq!(
            decode(&bytes[..FILE_BYTES - 8], &mut stored),
            Err(MerlError::Length {
                expected: FILE_BYTES,
                found: FILE_BYTES - 8
            })
        );
        assert!(matches!(
            decode(&bytes[..5], &mut stored),
            Err(MerlError::Length { found: 5, .. })
        ));
        bytes[8] = 90;
        assert_eq!(
            decode(&bytes, &mut stored),
            Err(MerlError::Dimensions {
                found: [90, 90, 90]
            })
        );
        assert!(matches!(
            encode(&stored[1..], &mut bytes),
            Err(MerlError::Buffer { .. })
        ));
        assert!(matches!(
            decode(&bytes, &mut stored[1..]),
            Err(MerlError::Dimensions { .. })
        ));
    }

    #[test]
    fn raw_for_inverts_scaled() {
        let mut rng = Lcg(5);
        for _ in 0..100_000 {
            let stored = rng.next() * 1e4;
            for c in 0..3 {
                let v = scaled(stored, c).unwrap();
                assert_eq!(scaled(raw_for(v, c), c), Some(v));
            }
        }
        assert_eq!(scaled(-1.0, 0), None);
        assert_eq!(scaled(f64::NAN, 0), None);
        assert_eq!(raw_for(f64::NAN, 1), MISSING);
        assert_eq!(raw_for(0.0, 2), 0.0);
    }
}
