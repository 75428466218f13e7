//! `developable_sim.Simulation`: one world stepped from Python. The GIL is released
//! while the world steps (and renders), so simulations in several Python threads step
//! in parallel; each simulation is stepped by one thread at a time (a second thread
//! gets "already borrowed").

use std::time::Instant;

use developable_sim::geometry::Pose;
use developable_sim::scene::Scene as LoadedScene;
use developable_sim::sim::{GraspAt, GraspError as RustGraspError, Grasped, Hold};
use developable_sim::sim::{ObjectStepReport, World};
use numpy::PyArray1;
use pyo3::exceptions::{PyIndexError, PyKeyError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyTuple};

use crate::camera::{frame_to_py, CameraFrame, Cameras};
use crate::errors::{guarded, simulation_error};
use crate::grasp::{self, GraspResult, HandleState};
use crate::origin::Origin;
use crate::save::{self, Entry, Saved};
use crate::state::{object_state, ObjectState};
use crate::targets;

/// The state behind a Python `Simulation` (what `step_many` steps in parallel).
#[derive(Clone)]
pub struct Inner {
    origin: Origin,
    /// The scene as built, at t = 0 (reset clones its world).
    pristine: LoadedScene,
    pub(crate) world: World,
    /// Every command since t = 0: steps with their targets, grasps and releases that
    /// changed a hold (`save`).
    log: Vec<Entry>,
    /// Each object's report of the last step (empty before the first).
    last: Vec<ObjectStepReport>,
    /// Wall time of the last world step, s (measured around `World::step` alone).
    last_step_s: f64,
    /// Set when a step panicked: the world may be half-stepped, only reset helps.
    broken: Option<String>,
    cameras: Cameras,
}

impl Inner {
    fn new(origin: Origin, pristine: LoadedScene) -> Inner {
        Inner {
            origin,
            world: pristine.world.clone(),
            pristine,
            log: Vec::new(),
            last: Vec::new(),
            last_step_s: 0.0,
            broken: None,
            cameras: Cameras::default(),
        }
    }

    fn usable(&self) -> Result<(), String> {
        match &self.broken {
            Some(why) => Err(format!(
                "this simulation stopped after an internal error ({why}); call reset()"
            )),
            None => Ok(()),
        }
    }

    /// One world step with `targets` (one entry per handle or none). Runs without the
    /// GIL; a panic is caught and leaves the simulation unusable until a reset.
    pub fn step(&mut self, targets: Vec<Option<Pose>>) -> Result<(), String> {
        self.usable()?;
        let world = &mut self.world;
        let start = Instant::now();
        match guarded("step", || world.step(&targets)) {
            Ok(report) => {
                self.last_step_s = start.elapsed().as_secs_f64();
                self.last = report.objects;
                self.log.push(Entry::Step(targets));
                Ok(())
            }
            Err(e) => {
                self.broken = Some(e.clone());
                Err(e)
            }
        }
    }

    /// `World::grasp`, logged when it changed the hold. The outer error is a panic
    /// (the simulation is then unusable), the inner one the world's refusal.
    pub fn grasp(
        &mut self,
        handle: usize,
        object: usize,
        at: GraspAt,
        hold: Option<Hold>,
    ) -> Result<Result<Grasped, RustGraspError>, String> {
        self.usable()?;
        let world = &mut self.world;
        let r = guarded("grasp", || world.grasp(handle, object, at, hold))
            .inspect_err(|e| self.broken = Some(e.clone()))?;
        if matches!(r, Ok(Grasped { changed: true, .. })) {
            self.log.push(Entry::Grasp {
                handle,
                object,
                at,
                hold,
            });
        }
        Ok(r)
    }

    /// `World::release`, logged when it let go of something; errors as [`Inner::grasp`].
    pub fn release(&mut self, handle: usize) -> Result<Result<bool, RustGraspError>, String> {
        self.usable()?;
        let world = &mut self.world;
        let r = guarded("release", || world.release(handle))
            .inspect_err(|e| self.broken = Some(e.clone()))?;
        if r == Ok(true) {
            self.log.push(Entry::Release { handle });
        }
        Ok(r)
    }

    /// Apply a saved command again (`Simulation.load`): it must do what it did.
    fn replay(&mut self, entry: Entry) -> Result<(), String> {
        match entry {
            Entry::Step(targets) => self.step(targets),
            Entry::Grasp {
                handle,
                object,
                at,
                hold,
            } => match self.grasp(handle, object, at, hold)? {
                Ok(Grasped { changed: true, .. }) => Ok(()),
                other => Err(format!("a saved grasp did not replay: {other:?}")),
            },
            Entry::Release { handle } => match self.release(handle)? {
                Ok(true) => Ok(()),
                other => Err(format!("a saved release did not replay: {other:?}")),
            },
        }
    }

    /// Back to t = 0 of the scene as built (not `World::reset`: a fresh copy also
    /// resets the contact stage's buffers).
    fn reset(&mut self) {
        self.world = self.pristine.world.clone();
        self.log.clear();
        self.last.clear();
        self.broken = None;
        self.cameras.clear();
    }

    fn saved(&self) -> Saved {
        Saved {
            text: self.origin.text.clone(),
            file: self.origin.file.display().to_string(),
            overrides: self.origin.overrides.clone(),
            seed: self.pristine.source.seed,
            handles: self.world.handles().len(),
            log: self.log.clone(),
            fingerprint: save::fingerprint(&self.world),
        }
    }

    /// Object index of `object`: a name, an index, or None for the first object.
    fn object_index(&self, object: Option<&Bound<'_, PyAny>>) -> PyResult<usize> {
        let names = self.world.object_names();
        let Some(object) = object.filter(|o| !o.is_none()) else {
            return Ok(0);
        };
        if let Ok(i) = object.extract::<usize>() {
            return if i < names.len() {
                Ok(i)
            } else {
                Err(PyIndexError::new_err(format!(
                    "object {i} out of range: the scene has {} objects ({})",
                    names.len(),
                    names.join(", ")
                )))
            };
        }
        let name: String = object
            .extract()
            .map_err(|_| PyTypeError::new_err("object must be a name (str) or an index (int)"))?;
        names.iter().position(|n| *n == name).ok_or_else(|| {
            PyKeyError::new_err(format!(
                "no object `{name}` in this scene (objects: {})",
                names.join(", ")
            ))
        })
    }
}

/// A simulation of a scene: step it, read its state, render its cameras, reset, save.
#[pyclass(module = "developable_sim", name = "Simulation")]
pub struct Simulation {
    pub(crate) inner: Inner,
}

impl Simulation {
    pub fn new(origin: Origin, scene: LoadedScene) -> Simulation {
        Simulation {
            inner: Inner::new(origin, scene),
        }
    }
}

#[pymethods]
impl Simulation {
    /// Advance by one time step `dt`. `targets` maps handle names to their target
    /// `world_from_gripper` at the end of the step: `(position, quaternion)` with the
    /// position in m (scene frame) and the quaternion (x, y, z, w), or a position alone
    /// (the orientation stays the handle's current target's), or 7 numbers
    /// `[x, y, z, qx, qy, qz, qw]`. Handles not named follow the scene's scripted
    /// trajectory (as in the node when nobody publishes). The GIL is released while the
    /// world steps.
    #[pyo3(signature = (targets = None))]
    fn step(&mut self, py: Python<'_>, targets: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
        let targets = targets::parse(&self.inner.world, targets)?;
        let inner = &mut self.inner;
        py.detach(|| inner.step(targets)).map_err(simulation_error)
    }

    /// The state of `object` (its name or index; the first object when None).
    #[pyo3(signature = (object = None))]
    fn state(&self, py: Python<'_>, object: Option<&Bound<'_, PyAny>>) -> PyResult<ObjectState> {
        self.inner.usable().map_err(simulation_error)?;
        let o = self.inner.object_index(object)?;
        object_state(py, &self.inner.world, o, self.inner.last.get(o))
    }

    /// The handles' current targets `{name: (position (3,), quaternion (4,) x, y, z,
    /// w)}`: where each handle was driven at the end of the last step (its scripted
    /// start pose at t = 0).
    fn targets<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        let world = &self.inner.world;
        for (h, pose) in world.handles().iter().zip(world.current_targets()) {
            let (p, q) = targets::parts(pose);
            let pair = PyTuple::new(
                py,
                [
                    PyArray1::from_slice(py, &p).into_any(),
                    PyArray1::from_slice(py, &q).into_any(),
                ],
            )?;
            out.set_item(&h.name, pair)?;
        }
        Ok(out)
    }

    /// Close handle `handle` on an object, at the next step boundary (now, between
    /// steps). Where: `point`, [u, v] of the object's flat pattern (m); or the graspable
    /// point nearest `near` ([x, y, z], m, scene frame) within `max_distance` (m, default
    /// the handle's `grasp_radius`); with neither, the point nearest the handle's
    /// current target within its `grasp_radius` (a gripper that closes). `object`: its
    /// name or index (default the handle's object in the scene). `hold`: 'position',
    /// 'normal' or 'full' (default the handle's scene setting). Nothing snaps: the
    /// point is held where it is, relative to the handle's current target. Grasping
    /// what the handle already holds changes nothing (`changed` False); elsewhere moves
    /// the hold. A refusal raises GraspError and changes nothing. Logged for `save`.
    #[pyo3(signature = (handle, object = None, *, point = None, near = None, max_distance = None, hold = None))]
    #[allow(clippy::too_many_arguments)] // the Python keywords
    fn grasp(
        &mut self,
        py: Python<'_>,
        handle: &str,
        object: Option<&Bound<'_, PyAny>>,
        point: Option<&Bound<'_, PyAny>>,
        near: Option<&Bound<'_, PyAny>>,
        max_distance: Option<f64>,
        hold: Option<&str>,
    ) -> PyResult<GraspResult> {
        self.inner.usable().map_err(simulation_error)?;
        let world = &self.inner.world;
        let h = grasp::handle_index(world, handle)?;
        let o = match object.filter(|o| !o.is_none()) {
            Some(o) => self.inner.object_index(Some(o))?,
            None => world.handles()[h].object,
        };
        let at = grasp::at(world, h, point, near, max_distance)?;
        let hold = grasp::hold(world, h, hold)?;
        let g = self
            .inner
            .grasp(h, o, at, hold)
            .map_err(simulation_error)?
            .map_err(|e| grasp::refused(&e))?;
        Ok(GraspResult::new(py, &self.inner.world, &g))
    }

    /// Open handle `handle`: it lets go of what it holds. Returns False when it held
    /// nothing (nothing changed). A handle that drives a ribbon's prescribed base
    /// cannot let go (GraspError). Logged for `save`.
    fn release(&mut self, handle: &str) -> PyResult<bool> {
        self.inner.usable().map_err(simulation_error)?;
        let h = grasp::handle_index(&self.inner.world, handle)?;
        self.inner
            .release(h)
            .map_err(simulation_error)?
            .map_err(|e| grasp::refused(&e))
    }

    /// What handle `handle` holds (attached, object, material point, generation) and
    /// the wrench it feels (`HandleState`).
    fn handle_state(&self, py: Python<'_>, handle: &str) -> PyResult<HandleState> {
        self.inner.usable().map_err(simulation_error)?;
        let h = grasp::handle_index(&self.inner.world, handle)?;
        Ok(HandleState::new(py, &self.inner.world, h))
    }

    /// `(force (3,), torque (3,))`: what the object exerts on handle `handle` in the
    /// last step, N and N m, scene frame, the torque about the grasp point (docs/grasp.md,
    /// the convention of `final.handles` in `--stats`); None when the handle holds
    /// nothing or has not stepped since it grasped.
    fn wrench<'py>(&self, py: Python<'py>, handle: &str) -> PyResult<Option<Bound<'py, PyTuple>>> {
        self.inner.usable().map_err(simulation_error)?;
        let h = grasp::handle_index(&self.inner.world, handle)?;
        match self.inner.world.handle_wrench(h) {
            None => Ok(None),
            Some(w) => {
                let (f, t) = grasp::wrench_arrays(py, &w);
                Ok(Some(PyTuple::new(py, [f, t])?))
            }
        }
    }

    /// Back to t = 0. With a `seed`, the scene is built again with that seed (a new
    /// imperfection, new paper singular points, new camera noise); None keeps the
    /// simulation's seed. Clears the command log `save` stores.
    #[pyo3(signature = (seed = None))]
    fn reset(&mut self, py: Python<'_>, seed: Option<u64>) -> PyResult<()> {
        if let Some(seed) = seed.filter(|s| *s != self.inner.pristine.source.seed) {
            self.inner.pristine = self.inner.origin.load_py(py, Some(seed))?;
        }
        self.inner.reset();
        Ok(())
    }

    /// The whole simulation as bytes: the scene (text, overrides, seed) and every step's
    /// targets since t = 0. `Simulation.load(data)` rebuilds it by replaying them, bit
    /// for bit (docs/python.md: why a replay, what it costs).
    fn save<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        self.inner.usable().map_err(simulation_error)?;
        Ok(PyBytes::new(py, &save::encode(&self.inner.saved())))
    }

    /// The simulation `save()` wrote, at the time it was saved. Raises
    /// SimulationError when the bytes are not a save or the replay does not reach the
    /// saved state (another version of the simulator), SceneError when the scene no
    /// longer loads (a mesh file it names is gone).
    #[staticmethod]
    fn load(py: Python<'_>, data: &[u8]) -> PyResult<Simulation> {
        let saved = save::decode(data).map_err(|e| simulation_error(format!("load: {e}")))?;
        let origin = Origin {
            text: saved.text,
            file: saved.file.into(),
            overrides: saved.overrides,
        };
        let scene = origin.load_py(py, Some(saved.seed))?;
        if scene.world.handles().len() != saved.handles {
            return Err(simulation_error(format!(
                "load: saved with {} handles, the scene has {}",
                saved.handles,
                scene.world.handles().len()
            )));
        }
        let mut inner = Inner::new(origin, scene);
        let log = saved.log;
        py.detach(|| log.into_iter().try_for_each(|entry| inner.replay(entry)))
            .map_err(|e| simulation_error(format!("load: {e}")))?;
        if save::fingerprint(&inner.world) != saved.fingerprint {
            return Err(simulation_error(
                "load: the replay did not reach the saved state (saved by another version?)",
            ));
        }
        Ok(Simulation { inner })
    }

    /// An independent copy at the same state (cheap: no replay), e.g. to try actions
    /// from one state.
    fn copy(&self) -> Simulation {
        Simulation {
            inner: self.inner.clone(),
        }
    }
    fn __copy__(&self) -> Simulation {
        self.copy()
    }
    fn __deepcopy__(&self, _memo: &Bound<'_, PyAny>) -> Simulation {
        self.copy()
    }
    /// Pickling goes through `save` / `load` (multiprocessing).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let load = py.get_type::<Simulation>().getattr("load")?;
        let data = slf.borrow().save(py)?;
        PyTuple::new(py, [load.into_any(), PyTuple::new(py, [data])?.into_any()])
    }

    /// Render camera `camera` of the scene at the current state: colour, depth and
    /// points (CameraFrame). `pose`, `(position, quaternion (x, y, z, w))` of the
    /// camera's body frame (REP 103: x forward, y left, z up) in the scene frame,
    /// replaces its mount; a camera on a `tf_frame` needs it. The GIL is released while
    /// it draws.
    #[pyo3(signature = (camera, pose = None))]
    fn render_depth(
        &mut self,
        py: Python<'_>,
        camera: &str,
        pose: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<CameraFrame> {
        self.inner.usable().map_err(simulation_error)?;
        let body = match pose.filter(|p| !p.is_none()) {
            Some(p) => Some(
                targets::pose(p, &developable_sim::geometry::Rotation::identity())
                    .map_err(|e| PyValueError::new_err(format!("pose: {e}")))?,
            ),
            None => None,
        };
        let inner = &mut self.inner;
        let request =
            Cameras::request(&inner.pristine, camera, body).map_err(PyKeyError::new_err)?;
        let (scene, world, cameras) = (&inner.pristine, &inner.world, &mut inner.cameras);
        let (index, frame) = py
            .detach(|| guarded("render", || cameras.render(scene, world, &request)))
            .map_err(simulation_error)?;
        frame_to_py(py, scene, &request, world.time(), index, frame)
    }

    /// Simulation time, s.
    #[getter]
    fn time(&self) -> f64 {
        self.inner.world.time()
    }
    /// Time step, s.
    #[getter]
    fn dt(&self) -> f64 {
        self.inner.world.dt()
    }
    /// Steps taken since t = 0.
    #[getter]
    fn steps(&self) -> u64 {
        self.inner.world.steps_taken()
    }
    /// The seed the scene was built with.
    #[getter]
    fn seed(&self) -> u64 {
        self.inner.pristine.source.seed
    }
    /// The scene's name.
    #[getter]
    fn name(&self) -> &str {
        &self.inner.pristine.name
    }
    /// The scene's `duration:` (what `developable_sim run` simulates), s.
    #[getter]
    fn duration(&self) -> f64 {
        self.inner.pristine.duration
    }
    /// Object names (`state`).
    #[getter]
    fn objects(&self) -> Vec<String> {
        self.inner.world.object_names().to_vec()
    }
    /// Handle names (`step`'s targets).
    #[getter]
    fn handles(&self) -> Vec<String> {
        self.inner
            .world
            .handles()
            .iter()
            .map(|h| h.name.clone())
            .collect()
    }
    /// Camera names (`render_depth`).
    #[getter]
    fn cameras(&self) -> Vec<String> {
        self.inner
            .pristine
            .cameras
            .iter()
            .map(|c| c.name.clone())
            .collect()
    }
    /// Wall time of the last world step alone (without the binding's work), s.
    #[getter]
    fn last_step_time(&self) -> f64 {
        self.inner.last_step_s
    }

    fn __repr__(&self) -> String {
        format!(
            "Simulation(scene={:?}, seed={}, time={}, steps={})",
            self.inner.pristine.name,
            self.inner.pristine.source.seed,
            self.inner.world.time(),
            self.inner.world.steps_taken()
        )
    }
}
