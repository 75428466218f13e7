//! The contact bodies' steps with contact inside them (`contact.method: barrier`,
//! docs/contact_barrier.md, "Several ribbons"): block Gauss-Seidel over the bodies, with
//! the bodies that cannot meet in this step stepped side by side.
//!
//! Each body minimizes its own objective plus the barrier against the others held where
//! they are. Bodies far enough apart that neither can reach the other within the step
//! form a class; the classes, one after the other, give the bodies a sequence. A body
//! waits only for the earlier bodies of the sequence it may reach, and steps against
//! their new meshes and every other body's mesh at the start of the step: a thread that
//! finishes one body takes the next whose waits are over, with no barrier between
//! classes. Whether two bodies that did not wait for each other stayed apart is checked
//! after the fact on what they really swept (every mesh their line searches passed
//! through, with the paths' curvature margins): a body that came within the barrier's
//! reach of an earlier one it did not wait for is put back and stepped again after all
//! the others, against everyone's new meshes, and so is every body that waited for
//! one put back. Then, back over the sequence, a body held back by where a later one
//! that waited for it started, now moved off, steps again against everyone's new
//! meshes. The sequence, the waits, the checks and the repeats depend only on the
//! state, never on the threads: bit-identical at any thread count.

use std::sync::OnceLock;

use super::dependency_order::run_in_dependency_order;
use super::object::{ObjectSim, ObjectStepReport, PhaseClock, StepContext};
use super::world::{BarrierState, ContactStepReport};
use super::HandleSpec;
use crate::contact::{ContactEnv, ContactReport, OtherMesh};
use crate::geometry::{Point3, Pose, Vector3};

/// Mesh vertices per box of a body's outline (two stations of a ribbon: one element).
const CHUNK: usize = 4;

type Aabb = (Vector3, Vector3);

/// A body's copy from before its step, if it may step again.
type Backup = Option<Box<dyn ObjectSim>>;

/// One body's first step: its report, its backup (if it may step again) and its mesh
/// after the step (if a later body waits for it).
struct Stepped {
    report: ObjectStepReport,
    backup: Backup,
    end: Vec<Point3>,
}

/// What every body's step of one world step shares.
struct Shared<'a> {
    /// Every object's mesh at the start of the step, and its outline.
    before: &'a [Vec<Point3>],
    outlines: &'a [Vec<Aabb>],
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
        &mut self,
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
        let before: Vec<Vec<Point3>> = objects.iter().map(|o| o.mesh().vertices.clone()).collect();
        let outlines: Vec<Vec<Aabb>> = before.iter().map(|v| outline(v)).collect();
        let shared = Shared {
            before: &before,
            outlines: &outlines,
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
        let motion: Vec<f64> = objects.iter().map(|o| last_motion(o.as_ref())).collect();
        let classes = self.classes(&order, &outlines, &motion);
        let side_by_side = classes.iter().filter(|c| c.len() > 1).map(Vec::len).sum();
        let sequence: Vec<usize> = classes.concat();
        // a body waits for the earlier ones it may reach (earlier classes only: a class's
        // members cannot reach each other)
        let deps: Vec<Vec<usize>> = (0..count)
            .map(|b| {
                (0..b)
                    .filter(|&a| self.may_meet(sequence[a], sequence[b], &outlines, &motion))
                    .collect()
            })
            .collect();
        // a free thread takes the ready body that the longest chain of waiting work
        // still hangs on, each body's work guessed from its last step's iterations
        let mut priority = vec![0.0; count];
        for b in (0..count).rev() {
            let cost = self
                .last_iterations
                .get(sequence[b])
                .map_or(1, |&n| n.max(1));
            let after = (b + 1..count)
                .filter(|&k| deps[k].contains(&b))
                .fold(0.0, |m: f64, k| m.max(priority[k]));
            priority[b] = cost as f64 + after;
        }
        let mut reports = vec![ObjectStepReport::default(); count];
        let stepped_again = self.step_in_dependency_order(
            objects,
            (&sequence, &deps, &priority),
            &shared,
            &mut reports,
        );
        self.last_iterations = reports.iter().map(|r| r.iterations as usize).collect();
        let summary = ContactStepReport {
            report: summary(&reports),
            side_by_side,
            stepped_again,
        };
        (reports, summary)
    }

    /// Whether bodies `i` and `j` may reach each other in this step (the guess): both
    /// contact bodies, their outlines within twice both last motions plus the barrier's
    /// reach.
    fn may_meet(&self, i: usize, j: usize, outlines: &[Vec<Aabb>], motion: &[f64]) -> bool {
        let reach = self.settings.thickness + self.settings.activation_distance;
        self.cells[i].is_some()
            && self.cells[j].is_some()
            && near(
                &outlines[i],
                &outlines[j],
                2.0 * self.guess_scale * (motion[i] + motion[j]) + reach,
            )
    }

    /// Classes of bodies that cannot meet in this step, greedily in `order`: a body
    /// joins the first class none of whose members it may reach. Only a guess (the check
    /// after the steps is what holds), from the bodies' own state: a state restored
    /// gives the same classes.
    fn classes(&self, order: &[usize], outlines: &[Vec<Aabb>], motion: &[f64]) -> Vec<Vec<usize>> {
        let mut classes: Vec<Vec<usize>> = Vec::new();
        for &i in order {
            match classes.iter_mut().find(|class| {
                class
                    .iter()
                    .all(|&j| !self.may_meet(i, j, outlines, motion))
            }) {
                Some(class) => class.push(i),
                None => classes.push(vec![i]),
            }
        }
        classes
    }

    /// Every body in the classes' sequence, each as soon as the earlier bodies it may
    /// reach (`deps`, positions in `sequence`) have stepped, against their new meshes
    /// and every other body's mesh at the start of the step; then, one after the other,
    /// those that came within reach of an earlier body they did not wait for, and those
    /// that waited for a body stepped again. Returns how many were stepped again.
    fn step_in_dependency_order(
        &self,
        objects: &mut [Box<dyn ObjectSim>],
        (sequence, deps, priority): (&[usize], &[Vec<usize>], &[f64]),
        shared: &Shared,
        reports: &mut [ObjectStepReport],
    ) -> usize {
        let count = sequence.len();
        let before = shared.before;
        let mut position = vec![0; count];
        for (b, &i) in sequence.iter().enumerate() {
            position[i] = b;
        }
        // a body can be stepped again only if an earlier one did not wait for it...
        let unwaited = |b: usize| {
            self.cells[sequence[b]].is_some()
                && (0..b).any(|a| self.cells[sequence[a]].is_some() && !deps[b].contains(&a))
        };
        // ... or it waited for one that can; one that a later body waited for may be
        // held back by where that body started
        let waited_for: Vec<bool> = (0..count)
            .map(|b| deps.iter().any(|d| d.contains(&b)))
            .collect();
        let mut backed_up = vec![false; count];
        for b in 0..count {
            backed_up[b] = (self.check_classes
                && (unwaited(b) || deps[b].iter().any(|&a| backed_up[a])))
                || (self.repeat_held_back && waited_for[b]);
        }
        let mut slots: Vec<Option<&mut Box<dyn ObjectSim>>> =
            objects.iter_mut().map(Some).collect();
        let items: Vec<&mut Box<dyn ObjectSim>> = sequence
            .iter()
            .map(|&i| slots[i].take().expect("each body once"))
            .collect();
        let stepped = run_in_dependency_order(
            items,
            (deps, priority),
            |b, object, done: &[OnceLock<Stepped>]| {
                let i = sequence[b];
                // each body's backup (for a step again) taken on its own thread: a ribbon's
                // clone is half the time spent outside the steps (double chain)
                let backup = backed_up[b].then(|| object.clone_box());
                let mesh = |j: usize| -> &[Point3] {
                    let p = position[j];
                    match deps[b].contains(&p) {
                        true => &done[p].get().expect("a dependency stepped first").end,
                        false => &before[j],
                    }
                };
                let others = self.others(i, (mesh, before));
                let report = self.step_body(object.as_mut(), i, &others, shared);
                let end = match waited_for[b] {
                    true => object.mesh().vertices.clone(),
                    false => Vec::new(),
                };
                Stepped {
                    report,
                    backup,
                    end,
                }
            },
        );
        drop(slots);
        let mut backups: Vec<Backup> = Vec::with_capacity(count);
        for (b, s) in stepped.into_iter().enumerate() {
            reports[sequence[b]] = s.report;
            backups.push(s.backup);
        }
        let again = self.stepped_apart_check(objects, (sequence, deps), before);
        // every body that steps again back at its start first: a later one's first
        // step may have moved into where an earlier one started (it waited for it)
        let redo: Vec<(usize, usize)> = sequence
            .iter()
            .copied()
            .enumerate()
            .filter(|(b, _)| again[*b])
            .collect();
        for &(b, i) in &redo {
            objects[i] = backups[b]
                .take()
                .expect("a body that may step again is backed up");
        }
        for &(_, i) in &redo {
            reports[i] = self.step_in_turn(objects, i, shared);
        }
        let held_back = self.step_held_back_again(
            objects,
            (sequence, deps, &again),
            &mut backups,
            shared,
            reports,
        );
        again.iter().filter(|&&a| a).count() + held_back
    }

    /// Back over the sequence, every body held back by where a later body started: it
    /// stepped against that body's start (the later one waited for it), part of it
    /// ended within the barrier's reach of it, and that part is now out of reach of
    /// where the later body went (a stack lifted from its top, taken bottom first). It
    /// steps again from its start against everyone's meshes now; later bodies first, so
    /// a stack moving off in a chain follows in one pass. A step again that is rejected
    /// (its start within reach of where another went) keeps the first step, which the
    /// later bodies stepped against. Returns how many stepped again.
    fn step_held_back_again(
        &self,
        objects: &mut [Box<dyn ObjectSim>],
        (sequence, deps, again): (&[usize], &[Vec<usize>], &[bool]),
        backups: &mut [Backup],
        shared: &Shared,
        reports: &mut [ObjectStepReport],
    ) -> usize {
        if !self.repeat_held_back {
            return 0;
        }
        let reach = self.settings.thickness + self.settings.activation_distance;
        let mut stepped = 0;
        for a in (0..sequence.len()).rev() {
            let i = sequence[a];
            if again[a] || self.cells[i].is_none() {
                continue;
            }
            let mine = outline(&objects[i].mesh().vertices);
            let held = (a + 1..sequence.len())
                .filter(|&b| deps[b].contains(&a))
                .any(|b| {
                    let j = sequence[b];
                    let (then, now) = (&shared.outlines[j], outline(&objects[j].mesh().vertices));
                    mine.iter()
                        .any(|x| near(&[*x], then, reach) && !near(&[*x], &now, reach))
                });
            let Some(start) = backups[a].take().filter(|_| held) else {
                continue;
            };
            let first = std::mem::replace(&mut objects[i], start);
            let report = self.step_in_turn(objects, i, shared);
            if report.kept_previous_state {
                objects[i] = first;
            } else {
                reports[i] = report;
                stepped += 1;
            }
        }
        stepped
    }

    /// Per position in `sequence`: whether that body steps again, because what it swept
    /// came within the barrier's reach of what an earlier body it did not wait for swept
    /// (paths' boxes with their curvature margins), or it waited for one that steps
    /// again.
    fn stepped_apart_check(
        &self,
        objects: &[Box<dyn ObjectSim>],
        (sequence, deps): (&[usize], &[Vec<usize>]),
        before: &[Vec<Point3>],
    ) -> Vec<bool> {
        let count = sequence.len();
        let mut again = vec![false; count];
        if !self.check_classes {
            return again;
        }
        let reach = self.settings.thickness + self.settings.activation_distance;
        // each body's swept boxes with their hull: most pairs of bodies are far apart
        let swept: Vec<Option<(Aabb, Vec<Aabb>)>> = sequence
            .iter()
            .map(|&i| {
                self.cells[i].as_ref().map(|_| {
                    let boxes = swept_outline(objects[i].as_ref(), &before[i]);
                    (hull(&boxes), boxes)
                })
            })
            .collect();
        for b in 0..count {
            let Some(mine) = &swept[b] else { continue };
            let met = (0..b).any(|a| {
                !deps[b].contains(&a)
                    && swept[a].as_ref().is_some_and(|(hull, theirs)| {
                        near(&[*hull], &[mine.0], reach) && near(theirs, &mine.1, reach)
                    })
            });
            again[b] = met || (self.repeat_dependents && deps[b].iter().any(|&a| again[a]));
        }
        again
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
        let others = self.others(index, (mesh, shared.before));
        self.step_body(object.as_mut(), index, &others, shared)
    }

    /// The contact bodies other than `index`, in index order, with their vertices.
    fn others<'m>(
        &'m self,
        index: usize,
        (vertices, start): (impl Fn(usize) -> &'m [Point3], &'m [Vec<Point3>]),
    ) -> Vec<OtherMesh<'m>> {
        (0..self.cells.len())
            .filter(|&j| j != index)
            .filter_map(|j| {
                self.cells[j].as_ref().map(|cells| OtherMesh {
                    vertices: vertices(j),
                    start: &start[j],
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

/// The box holding `boxes` (f64::min and max skip a NaN corner, which no box comes
/// near in [`near`] either).
fn hull(boxes: &[Aabb]) -> Aabb {
    let inf = Vector3::repeat(f64::INFINITY);
    boxes.iter().fold((inf, -inf), |(lo, hi), (a, b)| {
        (lo.zip_map(a, f64::min), hi.zip_map(b, f64::max))
    })
}

/// Whether any box of `a` comes within `margin` of any box of `b` on every axis.
fn near(a: &[Aabb], b: &[Aabb], margin: f64) -> bool {
    a.iter().any(|x| {
        b.iter()
            .any(|y| (0..3).all(|d| x.0[d] - y.1[d] <= margin && y.0[d] - x.1[d] <= margin))
    })
}
