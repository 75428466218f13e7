//! The node's robot links (`robot_colliders:`): the description taken from its latched
//! topic, and each link's TF frame looked up for every step. Both become commands
//! (recorded, replayed): the description with its shapes loaded here (mesh files read
//! once, shapes that cannot be loaded named on stderr), the lookups' outcomes as
//! transforms.

use super::SimNode;
use crate::session::{Applied, Command};
use crate::wire::msgs::{Header, Time, Transform, TransformStamped};

impl SimNode {
    /// Take the robot descriptions that arrived (the newest wins at the next step).
    pub(super) fn drain_robot_description(&mut self) {
        let Some(sub) = &self.io.robot_description else {
            return;
        };
        let mut arrived = Vec::new();
        loop {
            match sub.take() {
                Ok(Some((msg, _))) => arrived.push(msg.data),
                Ok(None) => break,
                Err(e) => {
                    eprintln!(
                        "[developable_sim] warning: {}: {e:?}",
                        self.names.robot_description
                    );
                    break;
                }
            }
        }
        for urdf in arrived {
            let loaded = crate::scene::urdf::load_for(&self.session.scene, &urdf);
            self.say_description(&loaded);
            self.robot_failing.clear();
            let command = Command::RobotDescription {
                urdf,
                loaded,
                arrival_ns: self.arrival_ns(),
            };
            if let Applied::Robot(Err(e)) = self.command(command, None) {
                eprintln!("[developable_sim] warning: robot_colliders: {e}");
            }
        }
    }

    /// What a description brings (on stderr): its colliding links, what was skipped.
    fn say_description(&self, loaded: &crate::session::robot::LoadedDescription) {
        let topic = &self.names.robot_description;
        match loaded {
            Err(e) => eprintln!(
                "[developable_sim] warning: robot_colliders: the description on {topic} is \
                 ignored ({e}); the robot's colliders stay as they were"
            ),
            Ok(d) => {
                for s in &d.skipped {
                    eprintln!("[developable_sim] warning: robot_colliders: {s}: skipped");
                }
                let names: Vec<&str> = d.links.iter().map(|l| l.name.as_str()).collect();
                eprintln!(
                    "[developable_sim] robot_colliders: robot `{}` from {topic}: {} colliding \
                     links ({}), each following its TF frame",
                    d.robot,
                    names.len(),
                    names.join(", ")
                );
            }
        }
    }

    /// The robot links' poses for the coming step: each link's TF frame looked up in the
    /// scene frame at the tick's lookup time (as TF-driven handles), offered and recorded
    /// as one command. A failed lookup leaves the link where it is and is said once (and
    /// again when the frame is found).
    pub(super) fn offer_link_poses(&mut self) {
        let (Some(tf), Some(d)) = (&self.io.tf_in, self.session.robot().description()) else {
            return;
        };
        let at = self.lookup_time_ns();
        let scene_frame = self.session.scene.frame_id.clone();
        let stamp = Time::from_nanos(at as i64);
        let mut transforms = Vec::with_capacity(d.links.len());
        let mut said = Vec::new();
        for link in &d.links {
            let failing = self.robot_failing.contains(&link.frame);
            let t = match tf.lookup(&scene_frame, &link.frame, at) {
                Ok(pose) => {
                    if failing {
                        said.push((link.frame.clone(), None));
                    }
                    TransformStamped {
                        header: Header {
                            stamp,
                            frame_id: scene_frame.clone(),
                        },
                        child_frame_id: link.frame.clone(),
                        transform: crate::wire::convert::to_transform(&pose),
                    }
                }
                Err(e) => {
                    if !failing {
                        let why = format!(
                            "link `{}`: TF frame {} in {scene_frame}: {e}; its colliders stay \
                             where they were (not in the world before it is found)",
                            link.name, link.frame
                        );
                        said.push((link.frame.clone(), Some(why)));
                    }
                    TransformStamped {
                        header: Header {
                            stamp,
                            frame_id: String::new(),
                        },
                        child_frame_id: link.frame.clone(),
                        transform: Transform::default(),
                    }
                }
            };
            transforms.push(t);
        }
        for (frame, why) in said {
            match why {
                Some(why) => {
                    eprintln!("[developable_sim] warning: robot_colliders: {why}");
                    self.robot_failing.insert(frame);
                }
                None => {
                    eprintln!("[developable_sim] robot_colliders: TF frame {frame} found again");
                    self.robot_failing.remove(&frame);
                }
            }
        }
        let command = Command::LinkPoses {
            transforms,
            arrival_ns: self.arrival_ns(),
        };
        if let Applied::Robot(Err(e)) = self.command(command, None) {
            eprintln!("[developable_sim] warning: robot_colliders: {e}");
        }
    }
}
