//! numpy in and out: inputs are any array-like of numbers (lists too),
//! converted to contiguous `float64`; outputs are new `float64` arrays.

use crate::errors::to_py;
use numpy::ndarray::Array2;
use numpy::{
    AllowTypeChange, IntoPyArray, PyArray1, PyArray2, PyArrayLike1, PyArrayLike2, PyArrayLikeDyn,
};
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

/// numpy dtype kinds that are never read as real numbers: complex (`c`, the imaginary part
/// would be dropped), datetime and timedelta (`M`, `m`: ticks, not values), bytes and strings
/// (`S`, `U`: "1.5" would be parsed) and void records (`V`).
const REFUSED_KINDS: &[(&str, &str)] = &[
    ("c", "complex"),
    ("M", "datetime64"),
    ("m", "timedelta64"),
    ("S", "bytes"),
    ("U", "string"),
    ("V", "record"),
];

/// Refuses arrays whose dtype is not a real number (see [`REFUSED_KINDS`]), naming `name`.
pub fn check_dtype(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<()> {
    let Ok(dtype) = obj.getattr("dtype") else {
        return Ok(());
    };
    let kind: String = dtype.getattr("kind")?.extract()?;
    if let Some((_, what)) = REFUSED_KINDS.iter().find(|(k, _)| *k == kind) {
        return Err(to_py(format!(
            "{name} has dtype {} ({what}): give real numbers (float64)",
            dtype.str()?
        )));
    }
    Ok(())
}

/// A shape in words: `(10, 6)`, `(12,)`.
fn shape_text(s: &[usize]) -> String {
    match s {
        [one] => format!("({one},)"),
        _ => format!(
            "({})",
            s.iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// Copies the array-like `obj` (argument `name`) into `out`, after checking its dtype and that
/// its shape is one of `shapes` (each with the words of its meaning, e.g. `(horizon, dof)`):
/// values of the right count in a wrong shape (a transposed preview, `x` as a column) are
/// refused, never read by position.
pub fn fill_shaped(
    name: &str,
    obj: &Bound<'_, PyAny>,
    shapes: &[(&str, &[usize])],
    out: &mut [f64],
) -> PyResult<()> {
    check_dtype(name, obj)?;
    let v: PyArrayLikeDyn<'_, f64, AllowTypeChange> = obj
        .extract()
        .map_err(|e| to_py(format!("{name}: {e} (give an array of real numbers)")))?;
    let a = v.as_array();
    if !shapes.iter().any(|(_, s)| a.shape() == *s) {
        let want: Vec<String> = shapes
            .iter()
            .map(|(w, s)| format!("{w} = {}", shape_text(s)))
            .collect();
        let (want, got) = (want.join(" or "), shape_text(a.shape()));
        let need = shapes[0].1.iter().product::<usize>();
        return Err(to_py(if a.len() == need {
            format!("{name} must be {want}, got {got}")
        } else {
            format!(
                "{name} has {} values (shape {got}) but {need} are needed: {name} must be {want}",
                a.len()
            )
        }));
    }
    for (o, x) in out.iter_mut().zip(a.iter()) {
        *o = *x;
    }
    Ok(())
}
