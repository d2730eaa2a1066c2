//! Partial T3 builds for clusters: `generator build t3 --shard K/N` computes
//! the nodes `i` with `i mod N = K − 1` (interleaved, so every shard gets a
//! like share of the expensive large-u nodes) into a shard file, and
//! `generator merge` assembles the `N` shard files into the table, bit-identical
//! to a single build (the same node values go through the same encoder).
//!
//! # Shard file (little-endian)
//!
//! ```text
//!   magic "T3SHARD1" | fingerprint u64 | K u32 | N u32 | nodes u32 | channels u32
//!   | the shard's nodes in ascending index order, `channels` f32 each
//!   | FNV-1a 64 of everything before
//! ```
//!
//! The fingerprint is an FNV-1a hash of the generator version and T3's
//! layout (axes, header parameters, channels): shards of different
//! generators or grids cannot be merged.

use std::fmt;
use twoscale::tables::format::{FNV_OFFSET, fnv1a};

use super::{ANGLE, ANGLES, AXES, CHANNELS, header_params, node_count};
use crate::tables::GENERATOR_VERSION;

const MAGIC: &[u8; 8] = b"T3SHARD1";
const HEAD: usize = 8 + 8 + 4 * 4;

/// Shard `k` (1-based) of `n`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// Which shard, `1..=n`.
    pub k: u32,
    /// How many shards.
    pub n: u32,
}

impl Shard {
    /// Parses `K/N` with `1 ≤ K ≤ N`.
    pub fn parse(text: &str) -> Result<Shard, ShardError> {
        let bad = || ShardError::Parse(text.to_string());
        let (k, n) = text.split_once('/').ok_or_else(bad)?;
        let k: u32 = k.trim().parse().map_err(|_| bad())?;
        let n: u32 = n.trim().parse().map_err(|_| bad())?;
        if k == 0 || k > n {
            return Err(bad());
        }
        Ok(Shard { k, n })
    }

    /// The node indices of this shard, ascending.
    pub fn indices(&self) -> impl Iterator<Item = usize> + use<> {
        (self.k as usize - 1..node_count()).step_by(self.n as usize)
    }

    /// The shard's file name: `t3-convolution.shard-K-of-N`.
    pub fn file_name(&self) -> String {
        format!(
            "{}.shard-{}-of-{}",
            twoscale::TableId::Convolution.name(),
            self.k,
            self.n
        )
    }
}

/// Hash of the generator version and T3's layout.
fn fingerprint() -> u64 {
    let layout = format!(
        "{GENERATOR_VERSION}|{AXES:?}|{:?}|{CHANNELS}",
        header_params(ANGLES, &ANGLE).to_values()
    );
    fnv1a(FNV_OFFSET, layout.as_bytes())
}

/// Why a shard could not be parsed, written or merged.
#[derive(Clone, Debug, PartialEq)]
pub enum ShardError {
    /// `--shard` is not `K/N` with `1 ≤ K ≤ N`.
    Parse(String),
    /// A shard's node values are not its nodes' count × [`CHANNELS`].
    WrongShape {
        /// The shard.
        shard: Shard,
        /// Its node count.
        expected: usize,
    },
    /// A file does not start like a shard file.
    NotAShard(String),
    /// A file's checksum does not match (truncated or corrupted).
    Checksum(String),
    /// A file was written by another generator version or T3 layout.
    OtherGenerator(String),
    /// A file's shard numbers or channel count are invalid.
    BadHeader {
        /// The file.
        name: String,
        /// Its `K`, `N` and channel count.
        k: u32,
        /// See `k`.
        n: u32,
        /// See `k`.
        channels: u32,
    },
    /// A file holds another number of nodes than its shard has.
    NodeCount {
        /// The file.
        name: String,
        /// Its shard.
        shard: Shard,
        /// Nodes in the file.
        count: u32,
        /// Nodes of the shard.
        expected: usize,
    },
    /// No files were given.
    NoFiles,
    /// Two files are of different splits.
    MixedSplits {
        /// The file of the other split, and its shard.
        name: String,
        /// See `name`.
        shard: Shard,
        /// The first file, and its `N`.
        first: String,
        /// See `first`.
        n: u32,
    },
    /// Two files are the same shard.
    Repeated {
        /// The shard.
        shard: Shard,
        /// The two files.
        first: String,
        /// See `first`.
        second: String,
    },
    /// Shards of the split are missing (`K`s, ascending).
    Missing {
        /// The missing `K`s.
        k: Vec<u32>,
        /// The split's `N`.
        n: u32,
    },
}

impl fmt::Display for ShardError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ShardError::Parse(text) => write!(
                f,
                "invalid shard '{text}': expected K/N with 1 <= K <= N, e.g. 2/8"
            ),
            ShardError::WrongShape { shard, expected } => write!(
                f,
                "shard {}/{} must hold {expected} nodes of {CHANNELS} values",
                shard.k, shard.n
            ),
            ShardError::NotAShard(name) => write!(f, "{name}: not a T3 shard file"),
            ShardError::Checksum(name) => {
                write!(f, "{name}: checksum mismatch (truncated or corrupted)")
            }
            ShardError::OtherGenerator(name) => write!(
                f,
                "{name}: built by a different generator version or T3 layout \
                 (this is generator {GENERATOR_VERSION})"
            ),
            ShardError::BadHeader {
                name,
                k,
                n,
                channels,
            } => write!(
                f,
                "{name}: invalid shard header ({k}/{n}, {channels} channels)"
            ),
            ShardError::NodeCount {
                name,
                shard,
                count,
                expected,
            } => write!(
                f,
                "{name}: shard {}/{} holds {count} nodes, expected {expected}",
                shard.k, shard.n
            ),
            ShardError::NoFiles => write!(f, "no shard files given"),
            ShardError::MixedSplits {
                name,
                shard,
                first,
                n,
            } => write!(
                f,
                "{name} is shard {}/{} but {first} is of {n} shards",
                shard.k, shard.n
            ),
            ShardError::Repeated {
                shard,
                first,
                second,
            } => write!(
                f,
                "shard {}/{} given twice: {first} and {second}",
                shard.k, shard.n
            ),
            ShardError::Missing { k, n } => {
                let shown: Vec<String> = k.iter().take(10).map(|k| format!("{k}/{n}")).collect();
                write!(f, "missing shards: {}", shown.join(", "))?;
                if k.len() > shown.len() {
                    write!(f, " and {} more", k.len() - shown.len())?;
                }
                Ok(())
            }
        }
    }
}

impl std::error::Error for ShardError {}

/// The bytes of shard `shard` holding `nodes` (its nodes' values in
/// ascending index order, [`CHANNELS`] each).
pub fn encode(shard: Shard, nodes: &[Vec<f32>]) -> Result<Vec<u8>, ShardError> {
    let expected = shard.indices().count();
    if nodes.len() != expected || nodes.iter().any(|v| v.len() != CHANNELS) {
        return Err(ShardError::WrongShape { shard, expected });
    }
    let mut out = Vec::with_capacity(HEAD + expected * CHANNELS * 4 + 8);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&fingerprint().to_le_bytes());
    for v in [shard.k, shard.n, expected as u32, CHANNELS as u32] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in nodes.iter().flatten() {
        out.extend_from_slice(&v.to_bits().to_le_bytes());
    }
    let sum = fnv1a(FNV_OFFSET, &out);
    out.extend_from_slice(&sum.to_le_bytes());
    Ok(out)
}

/// One decoded shard file.
struct Decoded {
    shard: Shard,
    values: Vec<f32>,
}

fn decode(name: &str, bytes: &[u8]) -> Result<Decoded, ShardError> {
    let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().expect("4 bytes"));
    if bytes.len() < HEAD + 8 || &bytes[..8] != MAGIC {
        return Err(ShardError::NotAShard(name.to_string()));
    }
    let (body, sum) = bytes.split_at(bytes.len() - 8);
    if fnv1a(FNV_OFFSET, body).to_le_bytes() != sum {
        return Err(ShardError::Checksum(name.to_string()));
    }
    if bytes[8..16] != fingerprint().to_le_bytes() {
        return Err(ShardError::OtherGenerator(name.to_string()));
    }
    let (k, n, count, channels) = (u32_at(16), u32_at(20), u32_at(24), u32_at(28));
    if k == 0 || k > n || channels as usize != CHANNELS {
        return Err(ShardError::BadHeader {
            name: name.to_string(),
            k,
            n,
            channels,
        });
    }
    let shard = Shard { k, n };
    let expected = shard.indices().count();
    if count as usize != expected || body.len() != HEAD + expected * CHANNELS * 4 {
        return Err(ShardError::NodeCount {
            name: name.to_string(),
            shard,
            count,
            expected,
        });
    }
    let values = body[HEAD..]
        .chunks_exact(4)
        .map(|b| f32::from_bits(u32::from_le_bytes(b.try_into().expect("4 bytes"))))
        .collect();
    Ok(Decoded { shard, values })
}

/// The grid of the whole table (every node's [`CHANNELS`] values, in index
/// order) from the `N` shard files `files` (name, bytes), in any order.
/// Errors name the missing, repeated or mismatched shards.
pub fn merge_grid(files: &[(String, Vec<u8>)]) -> Result<Vec<f32>, ShardError> {
    let decoded = files
        .iter()
        .map(|(name, bytes)| decode(name, bytes))
        .collect::<Result<Vec<_>, ShardError>>()?;
    let Some(first) = decoded.first() else {
        return Err(ShardError::NoFiles);
    };
    let n = first.shard.n;
    if let Some((i, d)) = decoded.iter().enumerate().find(|(_, d)| d.shard.n != n) {
        return Err(ShardError::MixedSplits {
            name: files[i].0.clone(),
            shard: d.shard,
            first: files[0].0.clone(),
            n,
        });
    }
    let mut owner: Vec<Option<usize>> = vec![None; n as usize];
    for (i, d) in decoded.iter().enumerate() {
        let slot = &mut owner[d.shard.k as usize - 1];
        if let Some(j) = *slot {
            return Err(ShardError::Repeated {
                shard: d.shard,
                first: files[j].0.clone(),
                second: files[i].0.clone(),
            });
        }
        *slot = Some(i);
    }
    let missing: Vec<u32> = (1..=n)
        .filter(|&k| owner[k as usize - 1].is_none())
        .collect();
    if !missing.is_empty() {
        return Err(ShardError::Missing { k: missing, n });
    }
    let mut grid = vec![0.0f32; node_count() * CHANNELS];
    for d in &decoded {
        for (node, values) in d.shard.indices().zip(d.values.chunks_exact(CHANNELS)) {
            grid[node * CHANNELS..(node + 1) * CHANNELS].copy_from_slice(values);
        }
    }
    Ok(grid)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fake shard's node values (the merge does not look at them).
    fn fake(shard: Shard) -> Vec<Vec<f32>> {
        shard
            .indices()
            .map(|i| (0..CHANNELS).map(|c| (i * CHANNELS + c) as f32).collect())
            .collect()
    }

    fn files(shards: &[Shard]) -> Vec<(String, Vec<u8>)> {
        shards
            .iter()
            .map(|&s| (s.file_name(), encode(s, &fake(s)).unwrap()))
            .collect()
    }

    fn err(files: &[(String, Vec<u8>)]) -> String {
        merge_grid(files).unwrap_err().to_string()
    }

    #[test]
    fn shards_partition_the_nodes_and_merge_in_any_order() {
        let s = |k| Shard { k, n: 3 };
        let mut all: Vec<usize> = (1..=3).flat_map(|k| s(k).indices()).collect();
        all.sort_unstable();
        assert_eq!(all, (0..node_count()).collect::<Vec<_>>());
        let grid = merge_grid(&files(&[s(2), s(3), s(1)])).unwrap();
        let want: Vec<f32> = (0..node_count() * CHANNELS).map(|x| x as f32).collect();
        assert_eq!(grid, want);
    }

    #[test]
    fn parse_accepts_k_of_n_only() {
        assert_eq!(Shard::parse("2/8"), Ok(Shard { k: 2, n: 8 }));
        for bad in ["0/3", "4/3", "3", "a/3", "1/0", ""] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn missing_repeated_mismatched_and_corrupt_shards_are_errors() {
        let s = |k, n| Shard { k, n };
        assert!(err(&files(&[s(1, 3), s(3, 3)])).ends_with("missing shards: 2/3"));
        let many = err(&files(&[s(2, 40)]));
        let want = "missing shards: 1/40, 3/40, 4/40, 5/40, 6/40, 7/40, 8/40, 9/40, 10/40, 11/40 and 29 more";
        assert!(many.ends_with(want), "{many}");
        assert!(err(&files(&[s(1, 2), s(1, 2), s(2, 2)])).contains("shard 1/2 given twice"));
        assert!(err(&files(&[s(1, 2), s(2, 3)])).contains("of 2 shards"));
        assert!(err(&[]).contains("no shard files"));
        let mut f = files(&[s(1, 1)]);
        let last = f[0].1.len() - 20;
        f[0].1[last] ^= 1;
        assert!(err(&f).contains("checksum mismatch"));
        f[0].1.truncate(40);
        assert!(err(&f).contains("checksum mismatch"));
        assert!(err(&[("x".into(), b"not a shard".to_vec())]).contains("not a T3 shard"));
    }
}
