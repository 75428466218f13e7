//! Handle targets an object cannot reach: an inextensible ribbon pulled past its length,
//! a sheet's handles pulled farther apart than in its pattern ([`crate::paper::reach`]),
//! a grasp point sent farther in one tick than the step can follow. The solver keeps
//! the object as close as it can and reports the distance (`constraint_violation`);
//! [`ReachWatch`] turns that number into a sentence when it starts and when it ends, so
//! that an edge (the node, the CLI) can say what is wrong instead of only counting it.

use super::{HandleSpec, StepReport};

/// A grasp point farther than this from its target is out of reach, m: 1000x the
/// solver's default constraint tolerance (1e-6 m), so no converging step comes near it,
/// and small next to a gripper's own precision (~1 mm).
const OUT_OF_REACH: f64 = 1e-3;

/// Back in reach below half of [`OUT_OF_REACH`] (hysteresis: a violation hovering at
/// the threshold does not repeat the message every tick).
const BACK_IN_REACH: f64 = 0.5 * OUT_OF_REACH;

/// Per object: whether its handles are out of reach now.
#[derive(Clone, Debug, Default)]
pub struct ReachWatch {
    out: Vec<bool>,
}

impl ReachWatch {
    /// The messages this step warrants (one per object whose state changed), in object
    /// order, stamped with the report's simulation time.
    pub fn update(
        &mut self,
        report: &StepReport,
        object_names: &[String],
        handles: &[HandleSpec],
    ) -> Vec<ReachMessage> {
        let time = report.time;
        self.out.resize(report.objects.len(), false);
        let mut messages = Vec::new();
        for (i, o) in report.objects.iter().enumerate() {
            let name = object_names.get(i).map_or("object", String::as_str);
            let v = o.constraint_violation;
            if !v.is_finite() {
                continue;
            }
            if !self.out[i] && v > OUT_OF_REACH {
                self.out[i] = true;
                let what = match o.violation_handle.and_then(|h| handles.get(h)) {
                    Some(h) => format!(
                        "handle '{}' cannot reach its target: its grasp point is {v:.4} m \
                         from it",
                        h.name
                    ),
                    None => format!("a constraint is violated by {v:.4} m"),
                };
                messages.push(ReachMessage {
                    object: i,
                    out_of_reach: true,
                    text: format!(
                        "{name}: {what} at t = {time:.3} s; the object is kept as close \
                         as it allows (reported as constraint_violation in its status)"
                    ),
                });
            } else if self.out[i] && v < BACK_IN_REACH {
                self.out[i] = false;
                messages.push(ReachMessage {
                    object: i,
                    out_of_reach: false,
                    text: format!(
                        "{name}: back within {BACK_IN_REACH} m of every handle target at \
                         t = {time:.3} s"
                    ),
                });
            }
        }
        messages.extend(scripted_failures(report, handles));
        messages
    }

    /// Forget every state (after a reset).
    pub fn clear(&mut self) {
        self.out.clear();
    }
}

/// A scripted grasp (`grasp_at`) that found nothing to close on, said as a warning: the
/// gripper stays open, and a scene author wants to know why.
fn scripted_failures<'a>(
    report: &'a StepReport,
    handles: &'a [HandleSpec],
) -> impl Iterator<Item = ReachMessage> + 'a {
    report.scripted.iter().filter_map(move |c| {
        let e = c.result.as_ref().err()?;
        let name = handles.get(c.handle).map_or("handle", |h| h.name.as_str());
        let what = if c.grasp { "grasp_at" } else { "release_at" };
        Some(ReachMessage {
            object: handles.get(c.handle).map_or(0, |h| h.object),
            out_of_reach: true,
            text: format!(
                "handle '{name}': its scripted {what} at t = {:.3} s did nothing: {e}",
                report.time
            ),
        })
    })
}

/// One change of an object's reach.
#[derive(Clone, Debug, PartialEq)]
pub struct ReachMessage {
    pub object: usize,
    /// True: it went out of reach; false: it came back.
    pub out_of_reach: bool,
    pub text: String,
}

impl std::fmt::Display for ReachMessage {
    /// The log line: `warning: ` before an object going out of reach.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.out_of_reach {
            f.write_str("warning: ")?;
        }
        f.write_str(&self.text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point2;
    use crate::sim::{GraspError, ObjectStepReport, ScriptedChange, Trajectory};

    fn report(violation: f64, handle: Option<usize>, time: f64) -> StepReport {
        StepReport {
            time,
            objects: vec![ObjectStepReport {
                constraint_violation: violation,
                violation_handle: handle,
                ..Default::default()
            }],
            ..Default::default()
        }
    }

    fn gripper() -> HandleSpec {
        HandleSpec::new(
            "right",
            0,
            Point2::new(1.0, 0.0),
            Trajectory::fixed(crate::geometry::Pose::identity()),
        )
    }

    #[test]
    fn says_once_when_a_handle_goes_out_of_reach_and_once_when_it_is_back() {
        let names = vec!["ribbon".to_string()];
        let handles = vec![gripper()];
        let mut watch = ReachWatch::default();
        // within tolerance: nothing
        assert!(watch
            .update(&report(1e-6, Some(0), 0.1), &names, &handles)
            .is_empty());
        // out of reach: one message naming object, handle and distance
        let m = watch.update(&report(0.25, Some(0), 0.2), &names, &handles);
        assert_eq!(m.len(), 1);
        assert!(m[0].out_of_reach);
        assert!(
            m[0].text
                .starts_with("ribbon: handle 'right' cannot reach its target")
                && m[0].text.contains("0.2500 m")
                && m[0].text.contains("t = 0.200 s"),
            "{}",
            m[0].text
        );
        // still out, or hovering between the two thresholds: no repetition
        assert!(watch
            .update(&report(0.25, Some(0), 0.3), &names, &handles)
            .is_empty());
        assert!(watch
            .update(&report(0.8e-3, Some(0), 0.4), &names, &handles)
            .is_empty());
        // back: one message
        let m = watch.update(&report(1e-6, Some(0), 0.5), &names, &handles);
        assert_eq!(m.len(), 1);
        assert!(
            !m[0].out_of_reach && m[0].text.starts_with("ribbon: back"),
            "{}",
            m[0].text
        );
        // a loop closure (no handle) is named as a constraint
        let m = watch.update(&report(2e-3, None, 0.6), &names, &handles);
        assert!(
            m[0].text.contains("a constraint is violated by 0.0020 m"),
            "{}",
            m[0].text
        );
    }

    #[test]
    fn a_scripted_grasp_that_finds_nothing_is_a_warning_and_a_success_is_silent() {
        let names = vec!["ribbon".to_string()];
        let handles = vec![gripper()];
        let mut r = report(0.0, None, 1.0);
        let far = GraspError::TooFar {
            distance: 0.3,
            max: 0.02,
        };
        r.scripted = vec![
            ScriptedChange {
                handle: 0,
                grasp: true,
                result: Err(far),
            },
            ScriptedChange {
                handle: 0,
                grasp: false,
                result: Ok(true),
            },
        ];
        let m = ReachWatch::default().update(&r, &names, &handles);
        assert_eq!(m.len(), 1, "{m:?}");
        assert!(
            m[0].to_string()
                == "warning: handle 'right': its scripted grasp_at at t = 1.000 s did \
                    nothing: the nearest graspable point is 0.3000 m away, farther than \
                    0.0200 m",
            "{}",
            m[0]
        );
    }
}
