//! A minimal writer and reader of NumPy's `.npy` format, version 1.0
//! (<https://numpy.org/doc/stable/reference/generated/numpy.lib.format.html>):
//!
//! ```text
//! "\x93NUMPY" 0x01 0x00                   magic, version 1.0
//! u16 LE header_len                       length of the header dict, padding included
//! "{'descr': '<f4', 'fortran_order': False, 'shape': (64, 1000), }"
//!                                         ASCII, space-padded, ends with '\n';
//!                                         10 + header_len is a multiple of 64
//! data                                    little-endian, C order (last axis fastest)
//! ```
//!
//! Only the two element types the exporter writes are supported: `<f4`
//! (f32) and `<u2` (u16).

/// The values of an array, in C order.
#[derive(Clone, Debug, PartialEq)]
pub enum Data {
    /// IEEE 754 binary32 (`<f4`).
    F32(Vec<f32>),
    /// Unsigned 16-bit integers (`<u2`).
    U16(Vec<u16>),
}

impl Data {
    /// Number of elements.
    pub fn len(&self) -> usize {
        match self {
            Data::F32(v) => v.len(),
            Data::U16(v) => v.len(),
        }
    }

    /// Whether there are no elements.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// NumPy's type string.
    pub fn descr(&self) -> &'static str {
        match self {
            Data::F32(_) => "<f4",
            Data::U16(_) => "<u2",
        }
    }

    /// Bytes per element.
    pub fn item_size(&self) -> usize {
        match self {
            Data::F32(_) => 4,
            Data::U16(_) => 2,
        }
    }
}

/// An n-dimensional array: its shape and its values in C order.
#[derive(Clone, Debug, PartialEq)]
pub struct Array {
    /// Extent of each axis (the product is the number of values).
    pub shape: Vec<usize>,
    /// The values.
    pub data: Data,
}

/// The magic string of every `.npy` file.
const MAGIC: &[u8; 6] = b"\x93NUMPY";
/// Alignment of the data (what NumPy itself writes).
const ALIGN: usize = 64;

/// `(64, 1000)`, `(48,)` or `()` as in a Python tuple.
fn shape_tuple(shape: &[usize]) -> String {
    match shape {
        [] => "()".to_string(),
        [n] => format!("({n},)"),
        _ => {
            let parts: Vec<String> = shape.iter().map(usize::to_string).collect();
            format!("({})", parts.join(", "))
        }
    }
}

/// The bytes of a version 1.0 `.npy` file holding `array`. Fails if the
/// shape disagrees with the number of values.
pub fn encode(array: &Array) -> Result<Vec<u8>, String> {
    let count: usize = array.shape.iter().product();
    if count != array.data.len() {
        return Err(format!(
            "shape {:?} holds {count} values, the data has {}",
            array.shape,
            array.data.len()
        ));
    }
    let mut header = format!(
        "{{'descr': '{}', 'fortran_order': False, 'shape': {}, }}",
        array.data.descr(),
        shape_tuple(&array.shape)
    );
    // Pad with spaces so that magic + version + length + header (+ '\n') is aligned.
    let unpadded = MAGIC.len() + 2 + 2 + header.len() + 1;
    header.push_str(&" ".repeat(unpadded.next_multiple_of(ALIGN) - unpadded));
    header.push('\n');
    let header_len = u16::try_from(header.len()).map_err(|_| "npy header too long".to_string())?;
    let mut out = Vec::with_capacity(10 + header.len() + count * array.data.item_size());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&[1, 0]);
    out.extend_from_slice(&header_len.to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    match &array.data {
        Data::F32(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        Data::U16(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
    }
    Ok(out)
}

/// The text after `'key':` in a header dict, up to the next top-level
/// comma or closing brace.
fn dict_value<'h>(header: &'h str, key: &str) -> Result<&'h str, String> {
    let pattern = format!("'{key}':");
    let start = header
        .find(&pattern)
        .ok_or_else(|| format!("npy header has no '{key}'"))?
        + pattern.len();
    let rest = header[start..].trim_start();
    let end = if rest.starts_with('(') {
        rest.find(')').map(|i| i + 1)
    } else {
        rest.find([',', '}'])
    }
    .ok_or_else(|| format!("npy header: unterminated '{key}'"))?;
    Ok(rest[..end].trim())
}

/// Reads a version 1.0 `.npy` file of `<f4` or `<u2` values in C order.
pub fn decode(bytes: &[u8]) -> Result<Array, String> {
    if bytes.len() < 10 || &bytes[..6] != MAGIC {
        return Err("not a .npy file (bad magic)".into());
    }
    if bytes[6..8] != [1, 0] {
        return Err(format!(
            "npy version {}.{} is not supported (1.0 only)",
            bytes[6], bytes[7]
        ));
    }
    let header_len = usize::from(u16::from_le_bytes([bytes[8], bytes[9]]));
    let header = bytes
        .get(10..10 + header_len)
        .ok_or("npy file truncated in its header")?;
    let header = std::str::from_utf8(header).map_err(|_| "npy header is not ASCII")?;
    if dict_value(header, "fortran_order")? != "False" {
        return Err("Fortran-ordered npy arrays are not supported".into());
    }
    let shape_text = dict_value(header, "shape")?;
    let shape = shape_text
        .trim_start_matches('(')
        .trim_end_matches(')')
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| {
            s.parse::<usize>()
                .map_err(|_| format!("bad npy shape {shape_text}"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let count = shape
        .iter()
        .try_fold(1usize, |acc, &n| acc.checked_mul(n))
        .ok_or("npy shape overflows")?;
    let body = &bytes[10 + header_len..];
    let descr = dict_value(header, "descr")?.trim_matches('\'');
    let item = match descr {
        "<f4" => 4,
        "<u2" => 2,
        other => return Err(format!("npy type {other} is not supported (<f4, <u2 only)")),
    };
    if Some(body.len()) != count.checked_mul(item) {
        return Err(format!(
            "npy data is {} bytes, shape {shape:?} of {descr} needs {}",
            body.len(),
            count.saturating_mul(item)
        ));
    }
    let data = match item {
        4 => Data::F32(
            body.chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect(),
        ),
        _ => Data::U16(
            body.chunks_exact(2)
                .map(|b| u16::from_le_bytes([b[0], b[1]]))
                .collect(),
        ),
    };
    Ok(Array { shape, data })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_is_aligned_and_readable_by_its_layout() {
        let array = Array {
            shape: vec![2, 3],
            data: Data::F32(vec![0.0, 1.0, -2.5, 1e-30, f32::MAX, 7.0]),
        };
        let bytes = encode(&array).unwrap();
        assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
        let header_len = usize::from(u16::from_le_bytes([bytes[8], bytes[9]]));
        assert_eq!((10 + header_len) % 64, 0);
        assert_eq!(bytes[10 + header_len - 1], b'\n');
        let header = std::str::from_utf8(&bytes[10..10 + header_len]).unwrap();
        assert!(
            header.starts_with("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }"),
            "{header}"
        );
        assert_eq!(bytes.len(), 10 + header_len + 6 * 4);
        // The data are little-endian f32 in C order.
        assert_eq!(&bytes[10 + header_len + 8..][..4], &(-2.5f32).to_le_bytes());
        assert_eq!(decode(&bytes).unwrap(), array);
    }

    #[test]
    fn round_trips_u16_and_one_dimensional_shapes() {
        for shape in [vec![5], vec![1, 1, 5], vec![]] {
            let n: usize = shape.iter().product();
            let array = Array {
                shape: shape.clone(),
                data: Data::U16((0..n as u16).map(|k| k * 13107).collect()),
            };
            let bytes = encode(&array).unwrap();
            let text = String::from_utf8_lossy(&bytes[10..]).to_string();
            assert!(text.contains(&format!("'shape': {}", shape_tuple(&shape))));
            assert_eq!(decode(&bytes).unwrap(), array);
        }
        assert_eq!(shape_tuple(&[5]), "(5,)");
    }

    #[test]
    fn rejects_bad_input_with_a_message() {
        let array = Array {
            shape: vec![3],
            data: Data::F32(vec![1.0, 2.0]),
        };
        assert!(encode(&array).unwrap_err().contains("holds 3 values"));
        let good = encode(&Array {
            shape: vec![2],
            data: Data::F32(vec![1.0, 2.0]),
        })
        .unwrap();
        assert!(
            decode(&good[..good.len() - 1])
                .unwrap_err()
                .contains("needs 8")
        );
        assert!(decode(b"PK\x03\x04").unwrap_err().contains("magic"));
        let mut v2 = good.clone();
        v2[6] = 2;
        assert!(decode(&v2).unwrap_err().contains("version 2.0"));
        let f8 = String::from_utf8_lossy(&good).replace("<f4", "<f8");
        assert!(decode(f8.as_bytes()).is_err());
    }
}
