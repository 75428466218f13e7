//! The node's inputs: handle poses from their topics (transformed into the scene frame
//! through TF when they are stamped in another frame), TF-driven handles' targets, and
//! the external clock under use_sim_time.

use std::time::Instant;

use super::{Lockstep, SimNode, CATCH_UP_BATCH};
use crate::ros::graph::tf_pose;
use crate::session::{Applied, Command};
use crate::wire::msgs::{Header, Pose, PoseStamped, Time};

impl SimNode {
    /// TF and the external clock: take what arrived.
    pub(super) fn drain_graph(&mut self) {
        if let Some(tf) = &mut self.io.tf_in {
            tf.drain();
        }
        if let Some(c) = &mut self.io.clock_in {
            c.drain();
        }
    }

    /// Under use_sim_time: step (at most [`CATCH_UP_BATCH`] times) while the next state's
    /// time is not after the external clock. Returns whether the node is still behind.
    pub(super) fn follow_clock(&mut self) -> bool {
        let Some(clock_ns) = self.io.clock_in.as_ref().and_then(|c| c.now_ns) else {
            return false;
        };
        let world = &self.session.scene.world;
        let (dt, clock) = (world.dt(), clock_ns as f64 * 1e-9);
        let due = |w: &crate::sim::World| w.time() + 0.5 * dt <= clock;
        for _ in 0..CATCH_UP_BATCH {
            if self.session.paused || self.done() || !due(&self.session.scene.world) {
                return false;
            }
            self.tick(Instant::now());
        }
        due(&self.session.scene.world)
    }

    /// The time TF is looked up at for the state a tick computes, ns: the wall clock when
    /// the node owns time (everyone else stamps in wall time), the state's simulated time
    /// under use_sim_time (the graph's clock; see `graph`).
    pub(super) fn lookup_time_ns(&self) -> u64 {
        if self.io.clock_in.is_some() {
            let w = &self.session.scene.world;
            ((w.time() + w.dt()) * 1e9).round().max(0.0) as u64
        } else {
            crate::wire::clock::now_ns()
        }
    }

    /// The targets of TF-driven handles for the coming step: each frame looked up in the
    /// scene frame, offered (and recorded) as a pose of its handle; a failed lookup is
    /// counted and the handle keeps its last target.
    pub(super) fn offer_tf_targets(&mut self) {
        let Some(tf) = &self.io.tf_in else {
            return;
        };
        if self.tf_handles.is_empty() {
            return;
        }
        let at = self.lookup_time_ns();
        let scene_frame = self.session.scene.frame_id.clone();
        let looked_up: Vec<_> = self
            .tf_handles
            .iter()
            .map(|(h, frame)| (*h, tf_pose(tf, &scene_frame, frame, at)))
            .collect();
        for (k, (h, result)) in looked_up.into_iter().enumerate() {
            let frame = &self.tf_handles[k].1;
            match result {
                Ok(msg) => {
                    if self.tf_failing[k] {
                        eprintln!(
                            "[developable_sim] handle {}: TF frame {frame} found again",
                            self.session.scene.world.handles()[h].name
                        );
                        self.tf_failing[k] = false;
                    }
                    let command = Command::Pose {
                        handle: h,
                        pose: msg,
                        arrival_ns: self.arrival_ns(),
                        publish_ns: None,
                    };
                    if let Applied::Input(Err(_)) = self.command(command, None) {
                        self.stats.inputs_rejected += 1;
                    }
                }
                Err(e) => {
                    if !self.tf_failing[k] {
                        eprintln!(
                            "[developable_sim] warning: handle {}: TF frame {frame} in {scene_frame}: {e}; the handle keeps its last target",
                            self.session.scene.world.handles()[h].name
                        );
                        self.tf_failing[k] = true;
                    }
                    let what = PoseStamped {
                        header: Header {
                            stamp: Time::from_nanos(at as i64),
                            frame_id: frame.clone(),
                        },
                        pose: Pose::default(), // identity
                    };
                    let command = Command::TfLookupFailed {
                        handle: h,
                        what,
                        arrival_ns: self.arrival_ns(),
                    };
                    self.command(command, None);
                    self.stats.inputs_rejected += 1;
                }
            }
        }
    }

    pub(super) fn drain_inputs(&mut self) {
        for k in 0..self.io.subs.len() {
            let h = self.io.subs[k].0;
            loop {
                let taken = match self.io.subs[k].1.take() {
                    Ok(Some(x)) => x,
                    Ok(None) => break,
                    Err(e) => {
                        eprintln!(
                            "[developable_sim] warning: {}: {e:?}",
                            self.names.handles[h]
                        );
                        self.stats.inputs_rejected += 1;
                        break;
                    }
                };
                let received = Instant::now();
                let (msg, info) = taken;
                // a pose in another frame of the TF tree, in the scene frame at its stamp
                let msg = match self
                    .io
                    .tf_in
                    .as_ref()
                    .map(|tf| tf.to_scene(&self.session.scene.frame_id, &msg))
                {
                    Some(Ok(Some(transformed))) => transformed,
                    Some(Err(
                        crate::ros::tf::LookupError::TooOld { .. }
                        | crate::ros::tf::LookupError::TooNew { .. },
                    )) => {
                        self.stats.inputs_received += 1;
                        self.stats.inputs_rejected += 1;
                        let command = Command::TfLookupFailed {
                            handle: h,
                            what: msg,
                            arrival_ns: self.arrival_ns(),
                        };
                        self.command(command, None);
                        continue;
                    }
                    // unknown frames are the input filter's to reject
                    _ => msg,
                };
                self.stats.inputs_received += 1;
                self.latency.window_inputs += 1;
                let publish_ns = info
                    .source_timestamp()
                    .map(|t| t.to_nanos())
                    .filter(|t| *t > 0)
                    .map(|t| t as u64);
                let command = Command::Pose {
                    handle: h,
                    pose: msg,
                    arrival_ns: self.arrival_ns(),
                    publish_ns,
                };
                match self.command(command, Some(received)) {
                    Applied::Input(Ok(())) => {
                        self.pending_input[h] = Some(received);
                        if self.lockstep == Lockstep::Handle(h) && !self.session.paused {
                            self.tick(received);
                            if self.done() {
                                return;
                            }
                        }
                    }
                    _ => self.stats.inputs_rejected += 1,
                }
            }
        }
    }

    /// The arrival time of an input: the recorder's (strictly increasing, it is the
    /// input's log time in the bag) when recording, else the wall clock, ns.
    pub(super) fn arrival_ns(&mut self) -> u64 {
        self.recorder
            .as_mut()
            .map_or_else(crate::wire::clock::now_ns, |r| r.arrival_ns())
    }
}
