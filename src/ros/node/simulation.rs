//! The ROS 2 standard `simulation_interfaces` services (release 1.5.1): what a test
//! harness written for Gazebo or Isaac Sim calls. Each becomes the node's own commands
//! (pause, reset, steps), so it is recorded and replayed like `~/set_paused`, `~/reset`
//! and `~/step`.
//!
//! States: PLAYING (running), PAUSED, STOPPED (paused and reset, until played, paused
//! or stepped), QUITTING (the node exits after replying). StepSimulation runs its steps
//! a batch per loop iteration (inputs and services stay served) and replies when done;
//! SimulateSteps goals (`simulate_steps`) share that queue.

use std::time::Instant;

use ros2_client::action::GoalStatusEnum;

use super::sim_state::StepJob;
use super::{Lockstep, SimNode, CATCH_UP_BATCH, CATCH_UP_WALL};
use crate::wire::sim_interfaces::{
    GetSimulationStateResponse, GetSimulatorFeaturesResponse, ResetSimulationRequest as Reset,
    ResultResponse, SimResult, SimulationState as State, SimulatorFeatures as F,
    ALREADY_IN_TARGET_STATE,
};

/// What this node supports, for GetSimulatorFeatures.
fn features() -> GetSimulatorFeaturesResponse {
    GetSimulatorFeaturesResponse {
        features: F {
            features: vec![
                F::SIMULATION_RESET,
                F::SIMULATION_RESET_TIME,
                F::SIMULATION_RESET_STATE,
                F::SIMULATION_STATE_GETTING,
                F::SIMULATION_STATE_SETTING,
                F::SIMULATION_STATE_PAUSE,
                F::STEP_SIMULATION_SINGLE,
                F::STEP_SIMULATION_MULTIPLE,
                F::STEP_SIMULATION_ACTION,
            ],
            spawn_formats: Vec::new(),
            custom_info: format!(
                "developable_sim {}, simulation_interfaces 1.5.1. ResetSimulation resets \
                 time and state together (SCOPE_DEFAULT, SCOPE_ALL, or SCOPE_TIME | \
                 SCOPE_STATE; nothing is ever spawned); under use_sim_time the reset state \
                 is stamped at the /clock's time. A step is the scene's dt. SimulateSteps \
                 (~/simulate_steps): feedback after every step, a canceled goal stops \
                 between steps. No spawning, no worlds (docs/ros2_interop.md).",
                env!("CARGO_PKG_VERSION")
            ),
        },
    }
}

impl SimNode {
    /// Answer the simulation_interfaces services.
    pub(super) fn drain_simulation_services(&mut self, next_tick: &mut Instant) {
        while let Some((id, _)) = self.io.services.simulation.get_features.receive() {
            self.io
                .services
                .simulation
                .get_features
                .reply(id, features());
        }
        while let Some((id, _)) = self.io.services.simulation.get_state.receive() {
            let state = State {
                state: self.simulation_state(),
            };
            let resp = GetSimulationStateResponse {
                state,
                result: SimResult::ok(),
            };
            self.io.services.simulation.get_state.reply(id, resp);
        }
        while let Some((id, req)) = self.io.services.simulation.set_state.receive() {
            let result = self.set_simulation_state(req.state.state, next_tick);
            let resp = ResultResponse { result };
            self.io.services.simulation.set_state.reply(id, resp);
        }
        while let Some((id, req)) = self.io.services.simulation.reset.receive() {
            let result = self.reset_simulation(req.scope, next_tick);
            let resp = ResultResponse { result };
            self.io.services.simulation.reset.reply(id, resp);
        }
        while let Some((id, req)) = self.io.services.simulation.step.receive() {
            if let Err(result) = self.may_step(req.steps) {
                let resp = ResultResponse { result };
                self.io.services.simulation.step.reply(id, resp);
                continue;
            }
            self.sim_if.stopped = false;
            let job = StepJob::Service(id);
            self.sim_if.stepping.push_back((job, req.steps, 0));
        }
        self.drain_simulate_steps();
    }

    fn simulation_state(&self) -> u8 {
        if self.sim_if.quitting {
            State::QUITTING
        } else if self.sim_if.stopped {
            State::STOPPED
        } else if self.session.paused {
            State::PAUSED
        } else {
            State::PLAYING
        }
    }

    fn set_simulation_state(&mut self, target: u8, next_tick: &mut Instant) -> SimResult {
        let current = self.simulation_state();
        if target == current {
            return SimResult::failed(ALREADY_IN_TARGET_STATE, "already in that state");
        }
        match target {
            State::PLAYING | State::PAUSED => {
                self.sim_if.stopped = false;
                self.set_paused(target == State::PAUSED, next_tick);
            }
            State::STOPPED => {
                // paused first, so the reset state's status says paused
                self.set_paused(true, next_tick);
                self.reset(next_tick);
                self.sim_if.stopped = true;
            }
            State::QUITTING => self.sim_if.quitting = true,
            State::NO_WORLD | State::LOADING_WORLD => {
                return SimResult::failed(
                    SimResult::FEATURE_UNSUPPORTED,
                    "this simulator has one world, its scene: it cannot be unloaded or loaded",
                )
            }
            s => {
                return SimResult::failed(
                    SimResult::OPERATION_FAILED,
                    format!("unknown simulation state {s}"),
                )
            }
        }
        SimResult::ok()
    }

    fn reset_simulation(&mut self, scope: u8, next_tick: &mut Instant) -> SimResult {
        let both = Reset::SCOPE_TIME | Reset::SCOPE_STATE;
        if scope != Reset::SCOPE_DEFAULT && scope & both != both {
            return SimResult::failed(
                SimResult::FEATURE_UNSUPPORTED,
                format!(
                    "scope {scope}: this simulator resets time and state together (use \
                     SCOPE_DEFAULT, SCOPE_ALL or SCOPE_TIME | SCOPE_STATE)"
                ),
            );
        }
        // (SCOPE_SPAWNED: nothing is ever spawned)
        self.reset(next_tick);
        SimResult::ok()
    }

    /// Whether StepSimulation (or a SimulateSteps goal) may run `steps` now.
    pub(super) fn may_step(&self, steps: u64) -> Result<(), SimResult> {
        let failed = |why: &str| Err(SimResult::failed(SimResult::OPERATION_FAILED, why));
        if steps == 0 {
            return failed("steps must be at least 1");
        }
        if !(self.session.paused || self.lockstep == Lockstep::Service) {
            return failed(
                "the simulation is playing: pause it first (SetSimulationState STATE_PAUSED)",
            );
        }
        if self.done() {
            return failed("the node's duration is reached");
        }
        Ok(())
    }

    /// Run the oldest StepSimulation request's or SimulateSteps goal's steps, a batch at
    /// a time (a goal's feedback after each step); reply or end the goal when it is
    /// done, or failed if the simulation was resumed meanwhile.
    pub(super) fn advance_step_requests(&mut self) {
        let Some((job, asked, mut done)) = self.sim_if.stepping.pop_front() else {
            return;
        };
        let start = Instant::now();
        let mut stopped_early = None;
        for _ in 0..CATCH_UP_BATCH {
            if done == asked {
                break;
            }
            if let Err(r) = self.may_step(asked - done) {
                stopped_early = Some(r);
                break;
            }
            self.tick(Instant::now());
            done += 1;
            if let StepJob::Goal(goal) = job {
                self.goal_feedback(goal, done, asked);
            }
            if start.elapsed() >= CATCH_UP_WALL {
                break;
            }
        }
        let (status, result) = match stopped_early {
            Some(mut r) => {
                r.error_message = format!("after {done} of {asked} steps: {}", r.error_message);
                (GoalStatusEnum::Aborted, r)
            }
            None if done == asked => (GoalStatusEnum::Succeeded, SimResult::ok()),
            None => {
                self.sim_if.stepping.push_front((job, asked, done));
                return;
            }
        };
        match job {
            StepJob::Service(id) => {
                let resp = ResultResponse { result };
                self.io.services.simulation.step.reply(id, resp);
            }
            StepJob::Goal(goal) => self.end_goal(goal, status, result),
        }
    }
}
