//! The node's services: reset, step and set_paused (std_srvs), the rcl_interfaces
//! parameter services with the run-time parameters taking effect, and the held replies.

use crate::session::Command;
use std::time::{Duration, Instant};

use super::{Lockstep, Pacing, SimNode};
use crate::ros::reply::Flushed;
use crate::session::params::ParamValue;
use crate::wire::msgs::{SetBoolResponse, TriggerResponse};
use crate::wire::param_msgs::{
    DescribeParametersResponse, GetParameterTypesResponse, GetParametersResponse,
    ListParametersResponse, SetParametersResponse, SetParametersResult,
};

impl SimNode {
    pub(super) fn drain_services(&mut self, next_tick: &mut Instant) {
        while let Some((id, _req)) = self.io.services.reset.receive() {
            self.reach.clear();
            self.last_markers = None;
            for p in &mut self.pending_input {
                *p = None;
            }
            self.command(Command::Reset, None);
            *next_tick = Instant::now() + self.period();
            let resp = TriggerResponse {
                success: true,
                message: format!(
                    "reset to t = 0 s (episode {})",
                    self.session.counters.episode
                ),
            };
            self.io.services.reset.reply(id, resp);
        }
        while let Some((id, req)) = self.io.services.set_paused.receive() {
            self.set_paused(req.data, next_tick);
            let t = self.session.scene.world.time();
            let resp = SetBoolResponse {
                success: true,
                message: if req.data {
                    format!("paused at t = {t:.6} s")
                } else {
                    format!("running from t = {t:.6} s")
                },
            };
            self.io.services.set_paused.reply(id, resp);
        }
        while let Some((id, _req)) = self.io.services.step.receive() {
            let resp = if self.lockstep == Lockstep::Service || self.session.paused {
                self.tick(Instant::now());
                TriggerResponse {
                    success: true,
                    message: format!(
                        "stepped to t = {:.6} s (step {})",
                        self.session.scene.world.time(),
                        self.session.scene.world.steps_taken()
                    ),
                }
            } else {
                TriggerResponse {
                    success: false,
                    message: "the simulation is running: pause it first (~/set_paused true) \
                              or start the node with --lockstep service"
                        .into(),
                }
            };
            self.io.services.step.reply(id, resp);
        }
        self.drain_parameter_services(next_tick);
        self.drain_grasp_services();
        self.flush_replies();
    }

    pub(super) fn replies_waiting(&self) -> bool {
        self.io.services.waiting()
    }

    /// Pause or resume; a change sends a fresh status so subscribers see `paused`.
    pub(super) fn set_paused(&mut self, paused: bool, next_tick: &mut Instant) {
        let was = self.session.paused;
        self.params.store("paused", ParamValue::Bool(paused));
        if was && !paused {
            *next_tick = Instant::now() + self.period();
        }
        self.command(Command::SetPaused(paused), None);
    }

    /// Answer the rcl_interfaces parameter services; apply what `set_parameters` changed.
    pub(super) fn drain_parameter_services(&mut self, next_tick: &mut Instant) {
        let s = &mut self.io.services;
        while let Some((id, req)) = s.list_parameters.receive() {
            let result = self.params.list(&req);
            s.list_parameters
                .reply(id, ListParametersResponse { result });
        }
        while let Some((id, req)) = s.get_parameters.receive() {
            let values = self.params.values(&req.names);
            s.get_parameters.reply(id, GetParametersResponse { values });
        }
        while let Some((id, req)) = s.describe_parameters.receive() {
            let descriptors = self.params.describe(&req.names);
            s.describe_parameters
                .reply(id, DescribeParametersResponse { descriptors });
        }
        while let Some((id, req)) = s.get_parameter_types.receive() {
            let types = self.params.types(&req.names);
            s.get_parameter_types
                .reply(id, GetParameterTypesResponse { types });
        }
        while let Some((id, req)) = self.io.services.set_parameters.receive() {
            let results = req
                .parameters
                .iter()
                .map(|p| match self.params.check(p) {
                    Ok(v) => {
                        self.apply_parameter(&p.name, &v, next_tick);
                        self.params.store(&p.name, v);
                        SetParametersResult {
                            successful: true,
                            reason: String::new(),
                        }
                    }
                    Err(reason) => SetParametersResult {
                        successful: false,
                        reason,
                    },
                })
                .collect();
            self.io
                .services
                .set_parameters
                .reply(id, SetParametersResponse { results });
        }
    }

    /// Make a checked run-time parameter take effect (see `param_server::RUNTIME`):
    /// `paused` as a pause command, every other one as a parameter command (the
    /// session takes the ones that change the simulation's inputs or outputs), then
    /// what concerns the node itself (its pacing, TF buffer, markers' rate).
    pub(super) fn apply_parameter(&mut self, name: &str, v: &ParamValue, next_tick: &mut Instant) {
        let x = match v {
            ParamValue::Double(x) => *x,
            _ => 0.0,
        };
        if let ("paused", ParamValue::Bool(b)) = (name, v) {
            self.set_paused(*b, next_tick);
            return;
        }
        let command = Command::SetParameter {
            name: name.to_string(),
            value: v.clone(),
        };
        self.command(command, None);
        match name {
            "markers_rate" => self.markers_period = (x > 0.0).then(|| 1.0 / x),
            "tf_max_lag" => {
                if let Some(tf) = &mut self.io.tf_in {
                    tf.max_lag = Duration::from_secs_f64(x);
                }
            }
            "real_time_factor" => {
                if let Pacing::RealTime { factor } = &mut self.pacing {
                    *factor = x;
                    *next_tick = Instant::now() + self.period();
                }
            }
            _ => {}
        }
    }

    /// Send the held replies whose clients can receive them (see `reply`).
    pub(super) fn flush_replies(&mut self) {
        let Flushed {
            sent,
            sent_unseen,
            failed,
        } = self.io.flush_replies(Instant::now());
        self.stats.service_replies += sent + sent_unseen;
        self.stats.service_replies_unseen += sent_unseen + failed;
        if sent_unseen + failed > 0 {
            eprintln!(
                "[developable_sim] warning: {} service repl{} sent although the \
                 client's reply reader was not matched within {} s, {failed} failed \
                 (is the client on the Cyclone DDS service mapping?)",
                sent_unseen,
                if sent_unseen == 1 { "y" } else { "ies" },
                crate::ros::reply::GIVE_UP.as_secs()
            );
        }
    }
}
