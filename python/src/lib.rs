//! `chisel._chisel`: the engine's operations on numpy arrays, with the GIL
//! released while they run. The Python package (`python/chisel/`) wraps
//! these functions in dataclasses, reports and the Dask batch; users call
//! that package, not this module (docs/python.md).
//!
//! Axis order: a volume crosses this boundary as a C-ordered numpy array of
//! shape `(nz, ny, nx)` — `array[k, j, i]` is the engine's sample
//! `(x = i, y = j, z = k)`, x fastest in memory — with `spacing`, `origin`
//! and the rows of `axes` in the engine's (x, y, z) order.

mod arrays;
mod blobby;
mod cut;
mod dms;
mod errors;
mod fusion;
mod gpu;
mod hull;
mod implicit;
mod io;
mod json;
mod mc;
mod options;
mod progress;
mod scan;
mod stats;
mod tissue;

use pyo3::prelude::*;

#[pymodule]
fn _chisel(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(gpu::gpu_info, m)?)?;
    m.add_function(wrap_pyfunction!(io::read_volume, m)?)?;
    m.add_function(wrap_pyfunction!(io::write_volume, m)?)?;
    m.add_function(wrap_pyfunction!(io::read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(io::write_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(io::dicom_series, m)?)?;
    m.add_function(wrap_pyfunction!(mc::marching_cubes, m)?)?;
    m.add_function(wrap_pyfunction!(scan::scan, m)?)?;
    m.add_function(wrap_pyfunction!(scan::scan_file, m)?)?;
    m.add_function(wrap_pyfunction!(stats::volume_stats, m)?)?;
    m.add_function(wrap_pyfunction!(stats::mesh_stats, m)?)?;
    m.add_function(wrap_pyfunction!(hull::hull, m)?)?;
    m.add_function(wrap_pyfunction!(hull::hull_scan, m)?)?;
    m.add_function(wrap_pyfunction!(hull::polyhedrize, m)?)?;
    m.add_function(wrap_pyfunction!(cut::cut, m)?)?;
    m.add_function(wrap_pyfunction!(tissue::relax, m)?)?;
    m.add_function(wrap_pyfunction!(dms::spline, m)?)?;
    m.add_function(wrap_pyfunction!(implicit::implicit, m)?)?;
    m.add_function(wrap_pyfunction!(implicit::scene_examples, m)?)?;
    m.add_function(wrap_pyfunction!(fusion::fuse, m)?)?;
    m.add_function(wrap_pyfunction!(fusion::morph, m)?)?;
    m.add_function(wrap_pyfunction!(blobby::blobby_fit, m)?)?;
    Ok(())
}
