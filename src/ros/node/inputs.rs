//! The node's inputs: handle poses from their topics (transformed into the scene frame
//! through TF when they are stamped in another frame), TF-driven handles' targets, and
//! the external clock under use_sim_time.

use std::time::Instant;

use super::{Lockstep, SimNode, CATCH_UP_BATCH, CATCH_UP_WALL};
use crate::ros::graph::tf_pose;
use crate::session::sim_clock::ClockEvent;
use crate::session::{Applied, Command};
use crate::wire::msgs::{Header, Pose, PoseStamped, Time};

impl SimNode {
    /// TF and the external clock: take what arrived; the clock's first sample and its
    /// jumps become commands.
    pub(super) fn drain_graph(&mut self) {
        if let Some(tf) = &mut self.io.tf_in {
            tf.drain();
        }
        let Some(c) = &mut self.io.clock_in else {
            return;
        };
        let events = c.drain();
        if let Some(now) = c.now_ns() {
            self.realtime.clock(Instant::now(), now as f64 * 1e-9);
        }
        for e in events {
            self.clock_event(e);
        }
    }

    /// The first `/clock` sample starts simulated time; a jump backwards resets there;
    /// a jump forward beyond `max_clock_jump` moves the time origin (see
    /// `session::sim_clock`). Each is said once on stderr.
    fn clock_event(&mut self, event: ClockEvent) {
        let s = |ns: i64| ns as f64 * 1e-9;
        let command = match event {
            ClockEvent::Start { at_ns } => {
                eprintln!(
                    "[developable_sim] /clock: simulated time starts at {:.9} s (the first \
                     clock sample)",
                    s(at_ns)
                );
                Command::SetTimeOrigin { origin_ns: at_ns }
            }
            ClockEvent::Backwards { from_ns, to_ns } => {
                eprintln!(
                    "[developable_sim] /clock jumped back from {:.9} s to {:.9} s: the \
                     simulation is reset there (clock reset {})",
                    s(from_ns),
                    s(to_ns),
                    self.session.counters.clock_resets + 1
                );
                self.forget_episode();
                Command::ResetAt {
                    origin_ns: to_ns,
                    clock_jump: true,
                }
            }
            ClockEvent::Forward { from_ns, to_ns } => {
                let max = self
                    .io
                    .clock_in
                    .as_ref()
                    .map_or(0, |c| c.follower.max_jump_ns);
                eprintln!(
                    "[developable_sim] /clock jumped ahead from {:.9} s to {:.9} s (more \
                     than max_clock_jump = {} s beyond the wall time between the samples): \
                     the {:.3} s gap is not simulated, the time origin moves by it",
                    s(from_ns),
                    s(to_ns),
                    s(max),
                    s(to_ns - from_ns)
                );
                Command::SetTimeOrigin {
                    origin_ns: self.session.origin_ns + (to_ns - from_ns),
                }
            }
        };
        self.command(command, None);
        self.realtime.restart(Instant::now());
    }

    /// What belongs to an episode of the node (reach messages, the markers' throttle,
    /// inputs waiting for their markers): forgotten at a reset.
    pub(super) fn forget_episode(&mut self) {
        self.reach.clear();
        self.last_markers = None;
        for p in &mut self.pending_input {
            *p = None;
        }
    }

    /// Under use_sim_time: step (at most [`CATCH_UP_BATCH`] times, and for at most
    /// [`CATCH_UP_WALL`] of wall time, so inputs, services and the clock stay served)
    /// while the next state's stamp is not after the external clock. Returns whether
    /// the node is still behind.
    pub(super) fn follow_clock(&mut self) -> bool {
        let Some(clock_ns) = self.io.clock_in.as_ref().and_then(|c| c.now_ns()) else {
            return false;
        };
        // the clock relative to the origin: small numbers, exact in f64 at any epoch
        let clock = (clock_ns - self.session.origin_ns) as f64 * 1e-9;
        let dt = self.session.scene.world.dt();
        let due = |w: &crate::sim::World| w.time() + 0.5 * dt <= clock;
        let start = Instant::now();
        for _ in 0..CATCH_UP_BATCH {
            if self.session.paused || self.done() || !due(&self.session.scene.world) {
                return false;
            }
            self.tick(Instant::now());
            if start.elapsed() >= CATCH_UP_WALL {
                break;
            }
        }
        due(&self.session.scene.world)
    }

    /// The time TF is looked up at for the state a tick computes, ns: the wall clock when
    /// the node owns time (everyone else stamps in wall time), the state's simulated time
    /// under use_sim_time (the graph's clock; see `graph`).
    pub(super) fn lookup_time_ns(&self) -> u64 {
        if self.io.clock_in.is_some() {
            let w = &self.session.scene.world;
            let next = crate::session::produce::stamp_at(self.session.origin_ns, w.time() + w.dt());
            next.nanos().max(0) as u64
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
