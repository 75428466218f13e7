//! The command line's logic, kept out of `main.rs` so that it is unit-tested: the
//! subcommands' options (`args`, clap), the node's order of precedence for its
//! settings (`node_launch`), its start-up banner (`banner`), the default bag folder
//! name (`bag_name`), and what the commands print when they finish (`summary`).
//! `main.rs` only parses and dispatches.

pub mod args;
pub mod bag_name;
pub mod banner;
pub mod node_launch;
pub mod stop;
pub mod summary;

use crate::record::recorder::RunRecorder;
use crate::record::RecordError;
use crate::runner::StepObserver;
use crate::scene::Scene;
use crate::sim::{ReachWatch, StepReport};

/// A check that ran to the end and found a difference: exit code 1 (an error that
/// stops a command, such as an unreadable bag, is exit code 2).
#[derive(Debug)]
pub struct CheckFailed(pub String);

impl std::fmt::Display for CheckFailed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for CheckFailed {}

/// The `run` command's observer: records when asked, and says on stderr when a handle
/// target goes out of reach and when it is reached again (as the node does).
pub struct CliObserver<'a> {
    pub recorder: Option<&'a mut RunRecorder>,
    pub reach: ReachWatch,
}

impl StepObserver for CliObserver<'_> {
    type Error = RecordError;
    fn after_step(
        &mut self,
        scene: &Scene,
        report: &StepReport,
        step_ms: f64,
    ) -> Result<(), RecordError> {
        let world = &scene.world;
        for m in self
            .reach
            .update(report, world.object_names(), world.handles())
        {
            eprintln!("{m}");
        }
        match self.recorder.as_deref_mut() {
            Some(r) => r.after_step(scene, report, step_ms),
            None => Ok(()),
        }
    }
}
