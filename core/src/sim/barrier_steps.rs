//! The contact bodies' steps with contact inside them (`contact.method: barrier`,
//! docs/contact_barrier.md, "Several ribbons"): block Gauss-Seidel over the bodies, with
//! the bodies that cannot meet in this step stepped side by side.
//!
//! Each body minimizes its own objective plus the barrier against the others held where
//! they are. Bodies far enough apart that neither can reach the other within the step
//! form a class and step in parallel, each against the others' meshes as the class
//! found them; the classes run one after the other, each against the meshes the earlier
//! ones left. Whether two bodies of a class did stay apart is checked after the fact on
//! what they really swept (every mesh their line searches passed through, with the
//! paths' curvature margins): a body that came within the barrier's reach of an earlier
//! one of its class is put back and stepped again after the class, against everyone's
//! new meshes — exactly the sequential step. The classes, the checks and the repeats
//! depend only on the state, never on the threads: bit-identical at any thread count.

use rayon::prelude::*;

use super::object::{ObjectSim, ObjectStepReport, PhaseClock, StepContext};
use super::world::{BarrierState, ContactStepReport};
use super::HandleSpec;
use crate::contact::{ContactEnv, ContactReport, OtherMesh};
use crate::geometry::{Point3, Pose, Vector3};

/// Mesh vertices per box of a body's outline (two stations of a ribbon: one element).
const CHUNK: usize = 4;

type Aabb = (Vector3, Vector3);

/// What every body's step of one world step shares.
struct Shared<'a> {
    poses0: &'a [Pose],
    poses1: &'a [Pose],
    targets1: &'a [Pose],
    dt: f64,
    time: f64,
    handles: &'a [HandleSpec],
    clock: &'a dyn PhaseClock,
}

impl BarrierState {
    /// Every object's step (classes forward on even steps, backward on odd), each
    /// contact body with the colliders and the other bodies' current meshes; the
    /// bodies' contact outcomes summed into a [`ContactStepReport`].
    pub(super) fn step(
        &self,
        objects: &mut [Box<dyn ObjectSim>],
        step_index: u64,
        (targets0, targets1): (&[Pose], &[Pose]),
        (dt, time, handles): (f64, f64, &[HandleSpec]),
        clock: &dyn PhaseClock,
    ) -> (Vec<ObjectStepReport>, ContactStepReport) {
        let pose_at = |targets: &[Pose]| -> Vec<Pose> {
            self.colliders
                .iter()
                .map(|c| c.world_pose(targets))
                .collect()
        };
        let (poses0, poses1) = (pose_at(targets0), pose_at(targets1));
        let shared = Shared {
            poses0: &poses0,
            poses1: &poses1,
            // (the carriers' poses: the handles' targets, then the kinematic bodies)
            targets1: &targets1[..handles.len()],
            dt,
            time,
            handles,
            clock,
        };
        let count = objects.len();
        let order: Vec<usize> = if step_index.is_multiple_of(2) {
            (0..count).collect()
        } else {
            (0..count).rev().collect()
        };
        let outlines: Vec<Vec<Aabb>> = objects
            .iter()
            .map(|o| outline(&o.mesh().vertices))
            .collect();
        let motion: Vec<f64> = objects.iter().map(|o| last_motion(o.as_ref())).collect();
        let mut reports = vec![ObjectStepReport::default(); count];
        let (mut side_by_side, mut stepped_again) = (0, 0);
        for class in self.classes(&order, &outlines, &motion) {
            if class.len() > 1 {
                side_by_side += class.len();
            }
            stepped_again += self.step_class(objects, &class, &shared, &mut reports);
        }
        let summary = ContactStepReport {
            report: summary(&reports),
            side_by_side,
            stepped_again,
        };
        (reports, summary)
    }

    /// Classes of bodies that cannot meet in this step, greedily in `order`: a body
    /// joins the first class none of whose members it may reach (outlines within twice
    /// both bodies' last motions plus the barrier's reach). Only a guess (the check
    /// after the class is what holds), from the bodies' own state: a state restored
    /// gives the same classes.
    fn classes(&self, order: &[usize], outlines: &[Vec<Aabb>], motion: &[f64]) -> Vec<Vec<usize>> {
        let reach = self.settings.thickness + self.settings.activation_distance;
        let may_meet = |i: usize, j: usize| {
            self.cells[i].is_some()
                && self.cells[j].is_some()
                && near(
                    &outlines[i],
                    &outlines[j],
                    2.0 * self.guess_scale * (motion[i] + motion[j]) + reach,
                )
        };
        let mut classes: Vec<Vec<usize>> = Vec::new();
        for &i in order {
            match classes
                .iter_mut()
                .find(|class| class.iter().all(|&j| !may_meet(i, j)))
            {
                Some(class) => class.push(i),
                None => classes.push(vec![i]),
            }
        }
        classes
    }

    /// One class: its members side by side against the meshes as the class found them,
    /// then, one after the other, those that came within reach of an earlier member;
    /// returns how many were stepped again.
    fn step_class(
        &self,
        objects: &mut [Box<dyn ObjectSim>],
        class: &[usize],
        shared: &Shared,
        reports: &mut [ObjectStepReport],
    ) -> usize {
        if class.len() == 1 {
            reports[class[0]] = self.step_in_turn(objects, class[0], shared);
            return 0;
        }
        let before: Vec<Vec<Point3>> = objects.iter().map(|o| o.mesh().vertices.clone()).collect();
        let mut members: Vec<(usize, &mut Box<dyn ObjectSim>)> = objects
            .iter_mut()
            .enumerate()
            .filter(|(i, _)| class.contains(i))
            .collect();
        // each member's backup (for a step again) taken on its own thread: a ribbon's
        // clone is half the time a class spends outside the steps (double chain)
        let stepped: Vec<(usize, ObjectStepReport, Box<dyn ObjectSim>)> = members
            .par_iter_mut()
            .map(|(i, object)| {
                let backup = object.clone_box();
                let others = self.others(*i, |j| &before[j]);
                let report = self.step_body(object.as_mut(), *i, &others, shared);
                (*i, report, backup)
            })
            .collect();
        let mut kept = Vec::with_capacity(stepped.len());
        for (i, report, backup) in stepped {
            reports[i] = report;
            kept.push((i, backup));
        }
        let reach = self.settings.thickness + self.settings.activation_distance;
        let swept: Vec<Vec<Aabb>> = class
            .iter()
            .map(|&i| swept_outline(objects[i].as_ref(), &before[i]))
            .collect();
        let mut again = Vec::new();
        for b in 1..class.len() {
            if self.check_classes
                && self.cells[class[b]].is_some()
                && (0..b)
                    .any(|a| self.cells[class[a]].is_some() && near(&swept[a], &swept[b], reach))
            {
                again.push(class[b]);
            }
        }
        for &i in &again {
            let k = kept.iter().position(|(j, _)| *j == i).expect("a member");
            objects[i] = kept.swap_remove(k).1;
            reports[i] = self.step_in_turn(objects, i, shared);
        }
        again.len()
    }

    /// Body `index` stepped against the other bodies as they are now.
    fn step_in_turn(
        &self,
        objects: &mut [Box<dyn ObjectSim>],
        index: usize,
        shared: &Shared,
    ) -> ObjectStepReport {
        let (before, rest) = objects.split_at_mut(index);
        let (object, after) = rest.split_first_mut().expect("index < count");
        let mesh = |j: usize| -> &[Point3] {
            if j < index {
                &before[j].mesh().vertices
            } else {
                &after[j - index - 1].mesh().vertices
            }
        };
        let others = self.others(index, mesh);
        self.step_body(object.as_mut(), index, &others, shared)
    }

    /// The contact bodies other than `index`, in index order, with their vertices.
    fn others<'m>(
        &'m self,
        index: usize,
        vertices: impl Fn(usize) -> &'m [Point3],
    ) -> Vec<OtherMesh<'m>> {
        (0..self.cells.len())
            .filter(|&j| j != index)
            .filter_map(|j| {
                self.cells[j].as_ref().map(|cells| OtherMesh {
                    vertices: vertices(j),
                    cells,
                })
            })
            .collect()
    }

    /// One object's step with `others` as the other bodies.
    fn step_body(
        &self,
        object: &mut dyn ObjectSim,
        index: usize,
        others: &[OtherMesh],
        shared: &Shared,
    ) -> ObjectStepReport {
        let env = ContactEnv {
            settings: self.settings,
            colliders: &self.colliders,
            poses0: shared.poses0,
            poses1: shared.poses1,
            others,
        };
        object.step(&StepContext {
            dt: shared.dt,
            time: shared.time,
            index,
            handles: shared.handles,
            targets: shared.targets1,
            clock: shared.clock,
            contact: self.cells[index].as_ref().map(|_| &env),
        })
    }
}

/// The most any vertex of a contact body moved in its last step, m (0 for others).
fn last_motion(object: &dyn ObjectSim) -> f64 {
    let Some(body) = object.contact_body() else {
        return 0.0;
    };
    let mut previous = Vec::new();
    body.previous_mesh_vertices(&mut previous);
    object
        .mesh()
        .vertices
        .iter()
        .zip(&previous)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max)
}

/// The bodies' contact outcomes summed.
fn summary(reports: &[ObjectStepReport]) -> ContactReport {
    let mut report = ContactReport {
        resolved: true,
        ..Default::default()
    };
    for outcome in reports.iter().filter_map(|r| r.contact) {
        report.contacts += outcome.active;
        report.constraints += outcome.active;
        report.iterations = report.iterations.max(outcome.rounds);
        report.resolved &= outcome.resolved;
        // the smallest gap left, as an overlap when it is negative (never, by
        // construction: every iterate is feasible)
        report.penetration_max = report.penetration_max.max(-outcome.min_gap);
    }
    report
}

/// Boxes of runs of [`CHUNK`] vertices, m.
fn outline(x: &[Point3]) -> Vec<Aabb> {
    x.chunks(CHUNK)
        .map(|c| {
            c.iter().fold(
                (
                    Vector3::repeat(f64::INFINITY),
                    Vector3::repeat(f64::NEG_INFINITY),
                ),
                |(lo, hi), p| (lo.inf(&p.coords), hi.sup(&p.coords)),
            )
        })
        .collect()
}

/// Where a body went in its last step: its start and end outlines and the boxes its
/// step recorded (the line searches' paths). A body that records none is taken to
/// have been everywhere (an infinite box).
fn swept_outline(object: &dyn ObjectSim, start: &[Point3]) -> Vec<Aabb> {
    let recorded = object
        .contact_body()
        .map(|b| b.swept_boxes())
        .unwrap_or(&[]);
    if recorded.is_empty() {
        return vec![(
            Vector3::repeat(f64::NEG_INFINITY),
            Vector3::repeat(f64::INFINITY),
        )];
    }
    let mut boxes = outline(start);
    boxes.extend(outline(&object.mesh().vertices));
    boxes.extend_from_slice(recorded);
    boxes
}

/// Whether any box of `a` comes within `margin` of any box of `b` on every axis.
fn near(a: &[Aabb], b: &[Aabb], margin: f64) -> bool {
    a.iter().any(|x| {
        b.iter()
            .any(|y| (0..3).all(|d| x.0[d] - y.1[d] <= margin && y.0[d] - x.1[d] <= margin))
    })
}
