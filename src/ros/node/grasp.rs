//! The grasp services: `~/grasp`, `~/release` and each handle's `handles/<h>/grasp`
//! open / close shortcut. A request is resolved by the session (names, the nearest
//! point, refusals), then applied as a command, recorded like every other.

use super::SimNode;
use crate::session::grasping::{resolve_close, resolve_grasp, Resolved};
use crate::session::{Applied, Command};
use crate::sim::Grasped;
use crate::wire::msgs::{GraspResponse, ReleaseResponse, SetBoolResponse};

impl SimNode {
    pub(super) fn drain_grasp_services(&mut self) {
        while let Some((id, req)) = self.io.services.grasp.receive() {
            let resolved = resolve_grasp(&self.session.scene.world, &req);
            let resp = self.grasp(resolved);
            self.io.services.grasp.reply(id, resp);
        }
        while let Some((id, req)) = self.io.services.release.receive() {
            let world = &self.session.scene.world;
            let resp = match crate::session::grasping::handle_index(world, &req.handle) {
                Ok(handle) => self.release(handle),
                Err(message) => ReleaseResponse {
                    success: false,
                    message,
                },
            };
            self.io.services.release.reply(id, resp);
        }
        for h in 0..self.io.services.handle_grasp.len() {
            while let Some((id, req)) = self.io.services.handle_grasp[h].receive() {
                let resp = if req.data {
                    let r = self.grasp(resolve_close(&self.session.scene.world, h));
                    SetBoolResponse {
                        success: r.success,
                        message: r.message,
                    }
                } else {
                    self.release(h)
                };
                self.io.services.handle_grasp[h].reply(id, resp);
            }
        }
    }

    /// Apply a resolved grasp (or answer its refusal).
    fn grasp(&mut self, resolved: Result<Resolved, String>) -> GraspResponse {
        let refused = |message: String| GraspResponse {
            success: false,
            message,
            ..GraspResponse::default()
        };
        let Resolved { command, distance } = match resolved {
            Ok(r) => r,
            Err(message) => return refused(message),
        };
        match self.command(command, None) {
            Applied::Grasp(Ok(Grasped {
                object,
                material_point,
                changed,
                ..
            })) => {
                let world = &self.session.scene.world;
                let what = format!(
                    "`{}` at [{:.6}, {:.6}] m, {:.4} m from the point asked for",
                    world.object_names()[object],
                    material_point.x,
                    material_point.y,
                    distance
                );
                GraspResponse {
                    success: true,
                    message: if changed {
                        format!("grasped {what}")
                    } else {
                        format!("already holding {what}: nothing changed")
                    },
                    material_point: [material_point.x, material_point.y],
                    distance,
                }
            }
            Applied::Grasp(Err(e)) => refused(e.to_string()),
            other => refused(format!("unexpected outcome {other:?}")),
        }
    }

    /// Apply a release of `handle`.
    fn release(&mut self, handle: usize) -> ReleaseResponse {
        let name = self.session.scene.world.handles()[handle].name.clone();
        match self.command(Command::Release { handle }, None) {
            Applied::Release(Ok(true)) => ReleaseResponse {
                success: true,
                message: format!("handle `{name}` released"),
            },
            Applied::Release(Ok(false)) => ReleaseResponse {
                success: true,
                message: format!("handle `{name}` was open: nothing changed"),
            },
            Applied::Release(Err(e)) => ReleaseResponse {
                success: false,
                message: e.to_string(),
            },
            other => ReleaseResponse {
                success: false,
                message: format!("unexpected outcome {other:?}"),
            },
        }
    }
}
