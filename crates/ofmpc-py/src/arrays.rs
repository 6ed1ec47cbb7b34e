//! numpy in and out: inputs are any array-like of numbers (lists too),
//! converted to contiguous `float64`; outputs are new `float64` arrays.

use numpy::ndarray::Array2;
use numpy::{AllowTypeChange, IntoPyArray, PyArray1, PyArray2, PyArrayLike1, PyArrayLike2};
use pyo3::prelude::*;

/// A 1-D input vector.
pub type Vector<'py> = PyArrayLike1<'py, f64, AllowTypeChange>;
/// A 2-D input matrix.
pub type Matrix<'py> = PyArrayLike2<'py, f64, AllowTypeChange>;

/// The values of a 1-D input, copied (inputs may be non-contiguous views).
pub fn vec_of(v: &Vector<'_>) -> Vec<f64> {
    v.as_array().iter().copied().collect()
}

/// A new 1-D array.
pub fn array1<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, v)
}

/// A new `rows × cols` array from row-major values.
pub fn array2<'py>(
    py: Python<'py>,
    rows: usize,
    cols: usize,
    v: Vec<f64>,
) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_vec((rows, cols), v)
        .expect("rows·cols values")
        .into_pyarray(py)
}

/// A new array from a column-major nalgebra matrix.
pub fn matrix<'py>(py: Python<'py>, m: &nalgebra::DMatrix<f64>) -> Bound<'py, PyArray2<f64>> {
    let (r, c) = m.shape();
    let v = (0..r)
        .flat_map(|i| (0..c).map(move |j| m[(i, j)]))
        .collect();
    array2(py, r, c, v)
}
