//! The status producer (`/<object>/status`, developable_sim/msg/SimStatus), and the
//! small global ones: the clock and each object's singular points as data.

use crate::wire::convert::pose;
use crate::wire::msgs::{
    Clock, GraspState, HandleStatus, Header, SimStatus, SingularPoint, SingularPoints, Vector3,
    Wrench, WrenchStamped,
};

use super::produce::{Produce, Scope};

/// `/clock`: the state's simulated time (when the node owns time).
pub fn clock(p: &Produce, _: Scope) -> Option<Clock> {
    Some(Clock { clock: p.stamp() })
}

/// `/<object>/singular_points`: the object's singular points with their ids, world
/// positions (m) and material points (m); none for a mesh that is not finite, and
/// no point with a non-finite coordinate.
pub fn singular_points(p: &Produce, scope: Scope) -> Option<SingularPoints> {
    let Scope::Object(object) = scope else {
        return None;
    };
    let world = &p.scene.world;
    if !world.mesh(object).is_finite() {
        return None;
    }
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    Some(SingularPoints {
        header: p.header(),
        object_name: world.object_names()[object].clone(),
        points: world
            .singular_points(object)
            .iter()
            .filter(|s| {
                finite(s.position.coords.as_slice()) && finite(s.material.coords.as_slice())
            })
            .map(|s| SingularPoint {
                id: s.id,
                position: crate::wire::convert::point(&s.position),
                material: [s.material.x, s.material.y],
            })
            .collect(),
    })
}

/// The status of one object (`/<object>/status`): time, step, solver, energies, errors,
/// strains, counters and its handles.
pub fn status(p: &Produce, scope: Scope) -> Option<SimStatus> {
    let Scope::Object(object) = scope else {
        return None;
    };
    let scene = p.scene;
    let world = &scene.world;
    let c = p.counters;
    let mut s = SimStatus {
        header: p.header(),
        object_name: world.object_names()[object].clone(),
        scene_name: scene.name.clone(),
        sim_time: world.time(),
        step: world.steps_taken(),
        episode: c.episode,
        dt: world.dt(),
        paused: p.paused,
        step_duration: p.step_duration,
        overrun_ticks: c.overrun_ticks,
        dropped_publications: c.dropped_publications,
        camera_frames_skipped: c.camera_frames_skipped,
        unconverged_steps: c.unconverged_steps[object],
        rejected_steps: c.rejected_steps[object],
        real_time_factor: c.real_time_factor,
        clock_resets: c.clock_resets,
        ..SimStatus::default()
    };
    match p.report.and_then(|r| r.objects.get(object)) {
        Some(o) => {
            s.solver_iterations = o.iterations;
            s.outer_iterations = o.outer_iterations;
            s.converged = o.converged;
            s.kept_previous_state = o.kept_previous_state;
            s.kinetic_energy = o.energies.kinetic;
            s.elastic_energy = o.energies.elastic;
            s.gravity_energy = o.energies.gravity;
            s.external_energy = o.energies.external;
            s.total_energy = o.energies.total();
            s.isometry_error = o.isometry_error;
            s.constraint_violation = o.constraint_violation;
            s.singular_point_count = o.singular_points as u32;
        }
        None => {
            // step 0: the initial state
            let e = world.objects()[object].energies();
            s.converged = true;
            s.kinetic_energy = e.kinetic;
            s.elastic_energy = e.elastic;
            s.gravity_energy = e.gravity;
            s.external_energy = e.external;
            s.total_energy = e.total();
            s.isometry_error = world.mesh(object).isometry_error();
            s.singular_point_count = world.singular_points(object).len() as u32;
        }
    }
    let strain = world.mesh(object).edge_strain();
    s.compression_mean_pct = strain.compression_mean_pct;
    s.compressed_edges_pct = strain.compressed_edges_pct;
    s.strain_mean_pct = strain.strain_mean_pct;
    s.strain_max_pct = strain.strain_max_pct;
    s.strained_edges_pct = strain.strained_edges_pct;
    for (h, spec) in world.handles().iter().enumerate() {
        if spec.object != object {
            continue; // (the object it holds, or held last)
        }
        let input = &p.inputs[h];
        let target = input
            .target
            .unwrap_or_else(|| world.scripted_target(h, world.time()));
        let mut hs = HandleStatus {
            name: spec.name.clone(),
            topic: p.handle_topics.get(h).cloned().unwrap_or_default(),
            tf_frame: scene
                .handle_tf_frames
                .get(h)
                .cloned()
                .flatten()
                .unwrap_or_default(),
            target: pose(&target),
            ..HandleStatus::default()
        };
        input.fill_status(&mut hs);
        hs.attached = spec.attached;
        hs.object = world.object_names()[spec.object].clone();
        hs.material_point = [spec.material_point.x, spec.material_point.y];
        hs.grasp_changed = p.grasp_changed[h];
        s.rejected_inputs += input.rejected();
        s.handles.push(hs);
    }
    Some(s)
}

/// `/handles/<handle>/state`: what the handle holds, made when it changed since the
/// last frame and for every initial state.
pub fn grasp_state(p: &Produce, scope: Scope) -> Option<GraspState> {
    let Scope::Handle(h) = scope else {
        return None;
    };
    if !(p.report.is_none() || p.grasp_dirty.get(h).copied().unwrap_or(false)) {
        return None;
    }
    let world = &p.scene.world;
    let spec = world.handles().get(h)?;
    Some(GraspState {
        header: p.header(),
        handle: spec.name.clone(),
        attached: spec.attached,
        object: world.object_names()[spec.object].clone(),
        material_point: [spec.material_point.x, spec.material_point.y],
        changed: p.grasp_changed[h],
    })
}

/// `/<object>/<handle>/wrench`: the force (N) and torque (N m) the object exerts on the
/// gripper, about the grasp point, in the handle's frame `<object>/<handle>` (the frame
/// at the grasp point on `/tf`), while the handle holds the object.
pub fn wrench(p: &Produce, scope: Scope) -> Option<WrenchStamped> {
    let Scope::ObjectHandle(o, h) = scope else {
        return None;
    };
    let world = &p.scene.world;
    let spec = world.handles().get(h)?;
    if !spec.holds(o) {
        return None;
    }
    let w = world.handle_wrench(h)?;
    let world_from_handle = world.mesh(o).frame_at(spec.material_point)?;
    let into = world_from_handle.rotation.inverse();
    let vector = |v: crate::geometry::Vector3| {
        let v = into * v;
        Vector3 {
            x: v.x,
            y: v.y,
            z: v.z,
        }
    };
    Some(WrenchStamped {
        header: Header {
            stamp: p.stamp(),
            frame_id: format!("{}/{}", world.object_names()[o], spec.name),
        },
        wrench: Wrench {
            force: vector(w.force),
            torque: vector(w.torque),
        },
    })
}
