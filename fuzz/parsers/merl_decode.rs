//! The MERL decoder's fuzz harness (`twoscale::io::merl`, what
//! `twoscale.merl.read` calls), shared by the libFuzzer target
//! (`fuzz/fuzz_targets/merl_decode.rs`) and the stable-Rust replay
//! (`tests/fuzz_regressions.rs`).
//!
//! A file is 11 MB: random bytes never have its length, so the input edits
//! a valid file (all values 0). Byte 0 holds flags, bytes 1..49 two
//! directions `i`, `o` (six little-endian f64, any bits), the rest 12-byte
//! patches (a little-endian u32 position, then 8 bytes XORed there). Flag
//! bit 0 lets the patches reach the 12-byte header (else they land in the
//! values), bit 1 truncates the file to `len · (flags >> 4) / 16`. What
//! decodes is looked up at `i`, `o` and at fixed directions (any `i`, `o`,
//! NaN included, must give a bin or `None`, never a panic), and each
//! patched value is scaled and encoded back: a stored value ≥ 0 scales to
//! a finite BRDF whose `raw_for` scales back to it exactly
//! (`merl::raw_for`'s contract).

use std::cell::RefCell;
use twoscale::io::merl;

thread_local! {
    /// A valid file (the header, every value 0), patched and restored in place.
    static FILE: RefCell<Vec<u8>> = RefCell::new({
        let mut bytes = vec![0u8; merl::FILE_BYTES];
        merl::encode(&vec![0.0; merl::VALUES], &mut bytes).expect("a zero file encodes");
        bytes
    });
    /// The decoded values.
    static STORED: RefCell<Vec<f64>> = RefCell::new(vec![0.0; merl::VALUES]);
}

fn f64_at(bytes: &[u8], k: usize) -> f64 {
    let mut b = [0u8; 8];
    b.copy_from_slice(&bytes[8 * k..8 * k + 8]);
    f64::from_le_bytes(b)
}

/// Runs one input (module documentation); true if the file decoded.
pub fn run(data: &[u8]) -> bool {
    let Some((&flags, rest)) = data.split_first() else {
        return false;
    };
    let Some(directions) = rest.get(..48) else {
        return false;
    };
    let i = [0, 1, 2].map(|k| f64_at(directions, k));
    let o = [3, 4, 5].map(|k| f64_at(directions, k));
    let patches: Vec<(usize, [u8; 8])> = rest[48..]
        .chunks_exact(12)
        .map(|p| {
            let position = u32::from_le_bytes([p[0], p[1], p[2], p[3]]) as usize;
            let mut xor = [0u8; 8];
            xor.copy_from_slice(&p[4..12]);
            let at = if flags & 1 != 0 {
                position % (merl::FILE_BYTES - 7)
            } else {
                merl::HEADER_BYTES + 8 * (position % merl::VALUES)
            };
            (at, xor)
        })
        .collect();
    FILE.with_borrow_mut(|file| {
        let apply = |file: &mut Vec<u8>| {
            for (at, xor) in &patches {
                for (b, x) in file[*at..*at + 8].iter_mut().zip(xor) {
                    *b ^= x;
                }
            }
        };
        apply(file);
        let len = if flags & 2 != 0 {
            file.len() * usize::from(flags >> 4) / 16
        } else {
            file.len()
        };
        let decoded = STORED.with_borrow_mut(|stored| {
            let ok = merl::decode(&file[..len], stored).is_ok();
            if ok {
                check(stored, &patches, i, o);
            }
            ok
        });
        // XOR again: the file is valid and all zero for the next input.
        apply(file);
        decoded
    })
}

/// The lookups and the scaling of a decoded file.
fn check(stored: &[f64], patches: &[(usize, [u8; 8])], i: [f64; 3], o: [f64; 3]) {
    let fixed = [
        ([0.3, 0.1, 0.95], [-0.3, 0.0, 0.95]),
        ([0.0, 0.0, 1.0], [0.0, 0.0, 1.0]),
        ([1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]),
    ];
    for (i, o) in [(i, o), (o, i)].into_iter().chain(fixed) {
        let k = merl::index_of_vectors(i, o);
        assert!(k < merl::BINS, "bin {k} of {i:?}, {o:?}");
        if let Some(rgb) = merl::lookup(stored, i, o) {
            assert!(rgb.iter().all(|v| *v >= 0.0), "{rgb:?} at {i:?}, {o:?}");
        }
    }
    for &(at, _) in patches {
        if at < merl::HEADER_BYTES {
            continue;
        }
        let k = (at - merl::HEADER_BYTES) / 8;
        let (value, channel) = (stored[k], k / merl::BINS);
        match merl::scaled(value, channel) {
            Some(brdf) => {
                assert!(value >= 0.0 && !brdf.is_nan(), "{value} scaled to {brdf}");
                let back = merl::raw_for(brdf, channel);
                assert_eq!(
                    merl::scaled(back, channel),
                    Some(brdf),
                    "stored {value:e} (channel {channel}) → {brdf:e} → {back:e}"
                );
            }
            None => assert!(value < 0.0 || value.is_nan(), "{value} is a sample"),
        }
    }
}
