//! The sets parameters must lie in ([`Domain`]), the error that names a
//! parameter outside its set ([`Invalid`], from [`check`]), and numbers
//! printed for users in the shortest form that reads back to the same value
//! ([`Shortest`], [`Shortest32`], [`widen`]). Every table reader and every
//! validation ([`crate::validate`]) reports through these.

use core::fmt;

/// The set a parameter must lie in. NaN lies in none.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Domain {
    /// `lo ≤ x ≤ hi`; a bound may be infinite (`[0, inf]` admits `+∞`).
    Closed(f64, f64),
    /// Finite and `x ≥ lo`.
    AtLeast(f64),
    /// Finite and `x > lo`.
    Above(f64),
    /// Finite and `lo < x ≤ hi`.
    LeftOpen(f64, f64),
}

impl Domain {
    /// Whether `x` lies in the domain.
    pub fn contains(self, x: f64) -> bool {
        match self {
            Domain::Closed(lo, hi) => lo <= x && x <= hi,
            Domain::AtLeast(lo) => x.is_finite() && x >= lo,
            Domain::Above(lo) => x.is_finite() && x > lo,
            Domain::LeftOpen(lo, hi) => x.is_finite() && lo < x && x <= hi,
        }
    }
}

impl fmt::Display for Domain {
    /// `in [0.2, 5]`, `finite and ≥ 0`, `finite and > 1`, `in (1, 100]`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Domain::Closed(lo, hi) => write!(f, "in [{}, {}]", Shortest(lo), Shortest(hi)),
            Domain::AtLeast(lo) => write!(f, "finite and ≥ {}", Shortest(lo)),
            Domain::Above(lo) => write!(f, "finite and > {}", Shortest(lo)),
            Domain::LeftOpen(lo, hi) => write!(f, "in ({}, {}]", Shortest(lo), Shortest(hi)),
        }
    }
}

/// A parameter outside its domain.
///
/// Displays as `p = 0.15: must be in [0.2, 5] (T1's domain)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Invalid {
    /// The parameter's name as the caller's interface spells it (`beta`,
    /// `sigma_s`, `eta[1].k`, `lambda`, …).
    pub name: &'static str,
    /// The value given.
    pub value: f64,
    /// Where it must lie.
    pub domain: Domain,
    /// Unit or context appended in parentheses (`µm`, `T1's domain`); may be empty.
    pub note: &'static str,
}

impl fmt::Display for Invalid {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} = {}: must be {}",
            self.name,
            Shortest(self.value),
            self.domain
        )?;
        if !self.note.is_empty() {
            write!(f, " ({})", self.note)?;
        }
        Ok(())
    }
}

#[cfg(feature = "std")]
impl std::error::Error for Invalid {}

/// `Ok(())` if `value` lies in `domain`, else the [`Invalid`] that says so.
pub fn check(
    name: &'static str,
    value: f64,
    domain: Domain,
    note: &'static str,
) -> Result<(), Invalid> {
    if domain.contains(value) {
        Ok(())
    } else {
        Err(Invalid {
            name,
            value,
            domain,
            note,
        })
    }
}

/// `x` as the `f64` of its shortest decimal form (`0.15f32` → `0.15`, not
/// `0.15000000596046448`), so that messages show the number the user gave.
/// NaN and infinities are kept.
pub fn widen(x: f32) -> f64 {
    if !x.is_finite() {
        return f64::from(x);
    }
    let mut buffer = Buffer::default();
    // `{:e}` of an f32 is at most 15 bytes (`-1.1754944e-38`).
    let written = fmt::Write::write_fmt(&mut buffer, format_args!("{x:e}"));
    let text = buffer.bytes.get(..buffer.len).unwrap_or(&[]);
    match (written, core::str::from_utf8(text).map(str::parse::<f64>)) {
        (Ok(()), Ok(Ok(wide))) => wide,
        _ => f64::from(x),
    }
}

/// A small stack buffer for [`widen`].
#[derive(Default)]
struct Buffer {
    bytes: [u8; 32],
    len: usize,
}

impl fmt::Write for Buffer {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let end = self.len + s.len();
        let slot = self.bytes.get_mut(self.len..end).ok_or(fmt::Error)?;
        slot.copy_from_slice(s.as_bytes());
        self.len = end;
        Ok(())
    }
}

/// Displays an `f64` in the shortest form that parses back to the same
/// value: positional for magnitudes in `[1e-5, 1e16)`, else exponent form
/// (`3.5449073e-30`). Integers print without a fraction (`32`), infinities
/// as `inf` and `-inf` (what Rust and Python parse).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shortest(pub f64);

/// [`Shortest`] for an `f32` (shortest form of the `f32` value: `0.0774`,
/// not `0.07739999890327454`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shortest32(pub f32);

/// Whether `x` is printed positionally (else in exponent form).
fn positional(x: f64) -> bool {
    let a = x.abs();
    a == 0.0 || !a.is_finite() || (1e-5..1e16).contains(&a)
}

impl fmt::Display for Shortest {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        if x.is_infinite() {
            f.write_str(if x > 0.0 { "inf" } else { "-inf" })
        } else if positional(x) {
            write!(f, "{x}")
        } else {
            write!(f, "{x:e}")
        }
    }
}

impl fmt::Display for Shortest32 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        if x.is_infinite() {
            f.write_str(if x > 0.0 { "inf" } else { "-inf" })
        } else if positional(f64::from(x)) {
            write!(f, "{x}")
        } else {
            write!(f, "{x:e}")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shortest_round_trips() {
        let s = |x: f64| Shortest(x).to_string();
        assert_eq!(s(3.5449073e-30), "3.5449073e-30");
        assert_eq!(s(0.0774), "0.0774");
        assert_eq!(s(32.0), "32");
        assert_eq!(s(-1.5e20), "-1.5e20");
        assert_eq!(s(0.0), "0");
        assert_eq!(Shortest32(0.0774).to_string(), "0.0774");
        assert_eq!(Shortest32(1.0e-30).to_string(), "1e-30");
        for x in [0.15f32, 0.2, -1.1754944e-38, f32::MAX, 3.4e-45, 5.0] {
            assert_eq!(widen(x) as f32, x);
            assert_eq!(Shortest(widen(x)).to_string(), Shortest32(x).to_string());
        }
        let mut rng = crate::test_rng::Lcg(7);
        for _ in 0..10_000 {
            rng.next();
            let x = f64::from_bits(rng.0);
            if x.is_finite() {
                assert_eq!(s(x).parse::<f64>().unwrap(), x);
            }
        }
    }
}
