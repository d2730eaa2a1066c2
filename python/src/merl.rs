//! Bindings of `twoscale::io::merl`, the MERL BRDF file format, for
//! `twoscale.merl` (python/twoscale/merl.py): decoding and encoding whole
//! files between bytes and `(3, 90, 90, 180)` float64 arrays (channel, θh
//! bin, θd bin, φd bin), the bin of direction pairs and the bin centres.

use numpy::ndarray::{Array1, Array2, Array4};
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyArray4, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray4,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use twoscale::io::merl;

/// The `(3, 90, 90, 180)` shape of a file's values.
const SHAPE: (usize, usize, usize, usize) =
    (3, merl::THETA_H_BINS, merl::THETA_D_BINS, merl::PHI_D_BINS);

fn value_error(e: impl ToString) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// merl_decode(data, scaled): a file's values as a (3, 90, 90, 180) float64
/// array; `scaled` gives the BRDF (stored × SCALE, NaN where missing), else
/// the stored values as they are.
#[pyfunction]
fn merl_decode<'py>(
    py: Python<'py>,
    data: &[u8],
    scaled: bool,
) -> PyResult<Bound<'py, PyArray4<f64>>> {
    let mut stored = vec![0.0; merl::VALUES];
    merl::decode(data, &mut stored).map_err(value_error)?;
    if scaled {
        for (k, v) in stored.iter_mut().enumerate() {
            *v = merl::scaled(*v, k / merl::BINS).unwrap_or(f64::NAN);
        }
    }
    let array = Array4::from_shape_vec(SHAPE, stored).map_err(value_error)?;
    Ok(array.into_pyarray(py))
}

/// merl_encode(values, scaled): the bytes of a file of a (3, 90, 90, 180)
/// float64 array; `scaled` takes BRDF values (NaN or negative: missing) and
/// stores `merl::raw_for` of each, else the array is stored as it is.
#[pyfunction]
fn merl_encode<'py>(
    py: Python<'py>,
    values: PyReadonlyArray4<'py, f64>,
    scaled: bool,
) -> PyResult<Bound<'py, PyBytes>> {
    let view = values.as_array();
    if view.dim() != SHAPE {
        return Err(value_error(format!(
            "MERL values must have shape {SHAPE:?}, got {:?}",
            view.shape()
        )));
    }
    // Iteration of an ndarray view is in logical (C) order whatever its strides.
    let mut stored: Vec<f64> = view.iter().copied().collect();
    if scaled {
        for (k, v) in stored.iter_mut().enumerate() {
            *v = merl::raw_for(*v, k / merl::BINS);
        }
    }
    let mut bytes = vec![0u8; merl::FILE_BYTES];
    merl::encode(&stored, &mut bytes).map_err(value_error)?;
    Ok(PyBytes::new(py, &bytes))
}

/// The rows of an `(N, 3)` float64 array.
fn vectors(name: &str, a: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<[f64; 3]>> {
    let view = a.as_array();
    if view.ncols() != 3 {
        return Err(value_error(format!(
            "{name} must have shape (N, 3), got {:?}",
            view.shape()
        )));
    }
    Ok(view
        .rows()
        .into_iter()
        .map(|r| [r[0], r[1], r[2]])
        .collect())
}

/// merl_index(wi, wo): the bin (0..1 458 000, position in a channel block)
/// of each pair of unit vectors, (N,) int64.
#[pyfunction]
fn merl_index<'py>(
    py: Python<'py>,
    wi: PyReadonlyArray2<'py, f64>,
    wo: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let (wi, wo) = (vectors("wi", &wi)?, vectors("wo", &wo)?);
    if wi.len() != wo.len() {
        return Err(value_error(format!(
            "wi has {} rows but wo has {}",
            wi.len(),
            wo.len()
        )));
    }
    let index: Vec<i64> = py.detach(|| {
        wi.iter()
            .zip(&wo)
            .map(|(i, o)| merl::index_of_vectors(*i, *o) as i64)
            .collect()
    });
    Ok(Array1::from_vec(index).into_pyarray(py))
}

/// `(wi, wo)` arrays of directions.
type DirectionPair<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>);

/// merl_bin_centres(bins): (wi, wo), each (N, 3) float64, the incident and
/// outgoing directions at the centre (φh = 0) of each bin of `bins`
/// ((N,) int64), or of every bin in order when `bins` is None.
#[pyfunction]
#[pyo3(signature = (bins=None))]
fn merl_bin_centres<'py>(
    py: Python<'py>,
    bins: Option<PyReadonlyArray1<'py, i64>>,
) -> PyResult<DirectionPair<'py>> {
    let bins: Vec<i64> = match bins {
        Some(b) => b.as_array().to_vec(),
        None => (0..merl::BINS as i64).collect(),
    };
    let (mut wi, mut wo) = (
        Array2::zeros((bins.len(), 3)),
        Array2::zeros((bins.len(), 3)),
    );
    for (row, &k) in bins.iter().enumerate() {
        let centre = usize::try_from(k)
            .ok()
            .and_then(merl::bin_centre)
            .ok_or_else(|| value_error(format!("bin {k} is outside 0..{}", merl::BINS)))?;
        let (i, o) = merl::vectors_of_half_diff(centre);
        for c in 0..3 {
            wi[[row, c]] = i[c];
            wo[[row, c]] = o[c];
        }
    }
    Ok((wi.into_pyarray(py), wo.into_pyarray(py)))
}

/// Adds the MERL functions and constants to the extension module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(merl_decode, m)?)?;
    m.add_function(wrap_pyfunction!(merl_encode, m)?)?;
    m.add_function(wrap_pyfunction!(merl_index, m)?)?;
    m.add_function(wrap_pyfunction!(merl_bin_centres, m)?)?;
    m.add("MERL_SCALE", merl::SCALE.to_vec())?;
    m.add("MERL_FILE_BYTES", merl::FILE_BYTES)?;
    Ok(())
}
