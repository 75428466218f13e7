//! `developable_sim.step_many(sims, targets)`: one step of many simulations in one call,
//! in parallel on the library's threads with the GIL released once. Each simulation
//! is independent and steps exactly as `sim.step` would: results do not depend on the
//! batch or the thread count.

use developable_sim::geometry::Pose;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use rayon::prelude::*;

use crate::errors::simulation_error;
use crate::simulation::{Inner, Simulation};
use crate::targets;

/// Step every simulation of `sims` once. `targets`, when given, has one entry per
/// simulation: a dict as `Simulation.step` takes, or None (its handles follow their
/// scripts). The same simulation may not appear twice. Every simulation is stepped
/// even when one fails; then the first failure is raised.
#[pyfunction]
#[pyo3(signature = (sims, targets = None))]
pub fn step_many(
    py: Python<'_>,
    sims: &Bound<'_, PyAny>,
    targets: Option<&Bound<'_, PyAny>>,
) -> PyResult<()> {
    let sims: Vec<Bound<'_, Simulation>> = sims
        .try_iter()?
        .map(|s| s?.cast_into::<Simulation>().map_err(PyErr::from))
        .collect::<PyResult<_>>()
        .map_err(|_| PyTypeError::new_err("sims must be an iterable of Simulation"))?;
    let mut borrowed = Vec::with_capacity(sims.len());
    for (i, s) in sims.iter().enumerate() {
        borrowed.push(s.try_borrow_mut().map_err(|_| {
            PyValueError::new_err(format!(
                "sims[{i}] is already in use (listed twice, or stepped by another thread)"
            ))
        })?);
    }
    let per_sim = per_sim_targets(&borrowed, targets)?;
    let mut inners: Vec<&mut Inner> = borrowed.iter_mut().map(|s| &mut s.inner).collect();
    let results: Vec<Result<(), String>> = py.detach(|| {
        inners
            .par_iter_mut()
            .zip(per_sim)
            .map(|(inner, t)| inner.step(t))
            .collect()
    });
    for (i, r) in results.into_iter().enumerate() {
        r.map_err(|e| simulation_error(format!("sims[{i}]: {e}")))?;
    }
    Ok(())
}

/// Each simulation's targets, parsed while the GIL is held.
fn per_sim_targets(
    sims: &[PyRefMut<'_, Simulation>],
    targets: Option<&Bound<'_, PyAny>>,
) -> PyResult<Vec<Vec<Option<Pose>>>> {
    let Some(targets) = targets.filter(|t| !t.is_none()) else {
        return Ok(vec![Vec::new(); sims.len()]);
    };
    let list: Vec<Bound<'_, PyAny>> = targets
        .try_iter()
        .map_err(|_| {
            PyTypeError::new_err("targets must be a list with one dict (or None) per simulation")
        })?
        .collect::<PyResult<_>>()?;
    if list.len() != sims.len() {
        return Err(PyValueError::new_err(format!(
            "{} targets for {} simulations",
            list.len(),
            sims.len()
        )));
    }
    sims.iter()
        .zip(&list)
        .enumerate()
        .map(|(i, (s, t))| {
            targets::parse(&s.inner.world, Some(t)).map_err(|e| {
                let py = t.py();
                PyErr::from_type(e.get_type(py), format!("targets[{i}]: {}", e.value(py)))
            })
        })
        .collect()
}
