//! The node's cameras (issue 48): each camera draws on a thread of its own
//! (`drawing`), beside the simulation loop, so a camera never delays a step.
//!
//! At a state where a camera's tick falls due the loop captures what it sees (a copy of
//! the meshes and collider poses, `Command::Capture`, recorded) and hands it to the
//! camera's thread, which draws it and encodes the five RealSense messages; the loop
//! publishes them when they come back (the thread wakes the poll). A tick that finds
//! the camera still drawing its previous frame is skipped: nothing is captured, and the
//! session counts it (`SimStatus.camera_frames_skipped`). The frames do not depend on
//! the thread count or on timing: a frame's bytes depend on its capture only, which
//! `replay` re-applies.

use super::drawing::Drawn;
use super::SimNode;
use crate::ros::graph::tf_pose;
use crate::scene::CameraMount;
use crate::session::{Applied, Command};

impl SimNode {
    /// Publish the frames the cameras drew since the last call.
    pub(super) fn drain_cameras(&mut self) {
        while let Some(d) = self.cameras.try_take() {
            self.emit_drawn(d);
        }
    }

    /// Publish, send to Foxglove and record a drawn frame; its snapshot goes back to the
    /// session for the next captures.
    fn emit_drawn(&mut self, d: Drawn) {
        self.stats.camera_frames += 1;
        self.camera_draw_ms.push(d.draw_ms);
        if let Some(s) = d.snapshot {
            self.session.cameras.recycle(s);
        }
        match d.frame {
            Ok(frame) => self.emit(&frame, None),
            Err(e) => self.encode_failed(&e),
        }
    }

    /// At a new state: every camera whose tick is due and which is done drawing
    /// captures it (a command, recorded) and hands it to its thread; a camera still
    /// drawing skips the tick (the session counts it). Under use_sim_time nothing is
    /// captured before the first /clock sample: its frame could not be published (no
    /// time yet), and a recorded capture nobody saw would shift `replay`'s frames.
    pub(super) fn capture_cameras(&mut self) {
        self.drain_cameras();
        if self.waiting_for_clock() {
            return;
        }
        for c in 0..self.session.scene.cameras.len() {
            if self.session.cameras.due(c).is_none() || self.cameras.busy(c) {
                continue;
            }
            let Some(world_from_optical) = self.camera_pose(c) else {
                continue;
            };
            let command = Command::Capture {
                camera: c,
                world_from_optical,
            };
            let Applied::Captured { frame: Some(_), .. } = self.command(command, None) else {
                continue;
            };
            if let Some(capture) = self.session.cameras.take(c) {
                self.cameras.send(capture);
            }
        }
    }

    /// `world_from_optical` of camera `c` now: fixed, or its TF frame looked up in the
    /// scene frame (None when the lookup fails: said once, the tick is skipped).
    fn camera_pose(&mut self, c: usize) -> Option<crate::geometry::Pose> {
        let scene = &self.session.scene;
        let cam = &scene.cameras[c];
        let frame = match &cam.mount {
            CameraMount::Fixed(p) => return Some(*p),
            CameraMount::TfFrame(f) => f,
        };
        let at = self.state_lookup_time_ns();
        let looked_up = match &self.io.tf_in {
            Some(tf) => tf_pose(tf, &scene.frame_id, frame, at).map_err(|e| e.to_string()),
            None => Err("no TF input".into()),
        };
        let failing = &mut self.cameras.tf_failing[c];
        match looked_up {
            Ok(msg) => {
                if *failing {
                    eprintln!(
                        "[developable_sim] camera {}: TF frame {frame} found again",
                        cam.name
                    );
                    *failing = false;
                }
                // a looked-up rotation is normalized here; the capture records the
                // pose exactly as drawn
                let (p, o) = (&msg.pose.position, &msg.pose.orientation);
                let world_from_frame = crate::geometry::Pose::from_parts(
                    nalgebra::Translation3::new(p.x, p.y, p.z),
                    nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                        o.w, o.x, o.y, o.z,
                    )),
                );
                Some(world_from_frame * crate::camera::body_from_optical())
            }
            Err(e) => {
                if !*failing {
                    eprintln!(
                        "[developable_sim] warning: camera {}: TF frame {frame} in {}: {e}; its \
                         ticks are skipped until it is found",
                        cam.name, scene.frame_id
                    );
                    *failing = true;
                }
                None
            }
        }
    }

    /// The time TF is looked up at for the current state, ns: the wall clock when the
    /// node owns time, the state's simulated time under use_sim_time (see
    /// `lookup_time_ns`).
    fn state_lookup_time_ns(&self) -> u64 {
        if self.io.clock_in.is_some() {
            (self.session.scene.world.time() * 1e9).round().max(0.0) as u64
        } else {
            crate::wire::clock::now_ns()
        }
    }

    /// Wait for the frames in flight and publish them (the node is stopping; the bag
    /// then holds every frame captured).
    pub(super) fn finish_cameras(&mut self) {
        for d in self.cameras.finish() {
            self.emit_drawn(d);
        }
    }
}
