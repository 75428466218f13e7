//! What the commands print when they finish: the run summary, the replay's comparison,
//! a bag's topics, a reindex, the node's last line. Each returns its lines; the caller
//! prints them (stdout, or stderr for the node).

use std::path::Path;

use crate::record::read::{ReindexReport, Scan};
use crate::record::replay::ReplayReport;
use crate::ros::node_stats::NodeStats;
use crate::stats::RunStats;

/// `run`: one line for every run, one for paper objects, one with a contact stage.
pub fn run_summary(s: &RunStats) -> Vec<String> {
    let mut lines = vec![format!(
        "{}: {} steps of {} s, median step {:.3} ms (p95 {:.3}), solver {} median {} iterations, {} unconverged, isometry error max {:.2e}, constraint violation max {:.2e} m, singular points max {}, finite: {}",
        s.scene,
        s.steps,
        s.dt,
        s.step_ms.median,
        s.step_ms.p95,
        s.solver.kind,
        s.solver.iterations_median,
        s.solver.unconverged_steps,
        s.isometry_error_max,
        s.constraint_violation_max,
        s.singular_points_max,
        s.finite
    )];
    if let (Some(c), Some(n), Some(t), Some(sv)) = (
        s.compression_mean_pct,
        s.compressed_edges_pct,
        s.triangles_mean,
        s.singular_vertices,
    ) {
        let phases = s
            .phase_ms
            .as_ref()
            .map(|p| {
                format!(
                    ", phases (median ms) simulation {:.3} remesh {:.3} isometry {:.3}",
                    p.simulation, p.remesh, p.isometry
                )
            })
            .unwrap_or_default();
        lines.push(format!(
            "paper: compression mean {c:.3} %, edges compressed > 1 %: {n:.2} %, triangles mean {t:.1}, singular vertices {sv}{phases}"
        ));
        if let Some(e) = &s.edge_strain {
            let (f, m) = (&e.final_frame, &e.max);
            lines.push(format!(
                "paper final frame: compression mean {:.3} %, edges compressed > 1 %: {:.2} %, |strain| mean {:.3} % max {:.2} %, edges |strain| > 1 %: {:.2} %; over frames max |strain| {:.2} %, edges |strain| > 1 % max {:.2} %",
                f.compression_mean_pct,
                f.compressed_edges_pct,
                f.strain_mean_pct,
                f.strain_max_pct,
                f.strained_edges_pct,
                m.strain_max_pct,
                m.strained_edges_pct
            ));
        }
    }
    if let Some(c) = &s.contact {
        lines.push(format!(
            "contact: median {:.3} ms per step, penetration max {:.2e} m, contacts max {}, rounds max {}, {} unresolved steps, developability error (|X - X~|) max {:.2e} m, flipped/degenerate triangles {}/{}",
            s.contact_ms.median,
            s.penetration_max,
            c.contacts_max,
            c.iterations_max,
            c.unresolved_steps,
            c.correction_max,
            c.flipped_triangles,
            c.degenerate_triangles
        ));
    }
    lines
}

/// `replay`: the totals, one line per topic, the verdict.
pub fn replay_summary(r: &ReplayReport) -> Vec<String> {
    let mut lines = vec![format!(
        "replayed {}: scene {}, {} steps, {} resets, {} handle poses fed, {:.2} s",
        r.bag, r.scene, r.steps, r.resets, r.inputs, r.wall_s
    )];
    for t in &r.topics {
        let at = if t.max_at.is_empty() {
            String::new()
        } else {
            format!(" at {}", t.max_at)
        };
        let structure = t
            .structural
            .as_ref()
            .map(|s| format!("; structure: {s}"))
            .unwrap_or_default();
        let first = if t.first_difference.is_empty() {
            String::new()
        } else {
            format!("; first: {}", t.first_difference)
        };
        lines.push(format!(
            "  {:<32} {:>7} compared  {:>6} differ  {:>4} missing  max |diff| {:.3e}{at}{structure}{first}",
            t.topic, t.compared, t.differing, t.missing, t.max_abs_difference,
        ));
    }
    if let Some(t) = &r.truncated {
        lines.push(format!(
            "  note: the bag ends early ({t}); compared up to there"
        ));
    }
    lines.push(if r.identical {
        "identical: every recorded output reproduced bit for bit".to_string()
    } else if r.topics.iter().all(|t| t.compared == 0) {
        "NOTHING COMPARED: the bag holds no recorded output this build can read".to_string()
    } else {
        format!("DIFFERENT: largest difference {:.3e}", r.max_abs_difference)
    });
    lines
}

/// `bag info`: one MCAP file's message count (and whether it is complete), its topics.
pub fn scan_summary(file: &Path, s: &Scan) -> Vec<String> {
    let state = match (&s.truncated, s.complete) {
        (_, true) => String::new(),
        (Some(t), false) => {
            format!(" (incomplete file: {t}; run `developable_sim bag reindex`)")
        }
        (None, false) => " (incomplete file: no footer; run `developable_sim bag reindex`)".into(),
    };
    let mut lines = vec![format!(
        "{}: {} messages{state}",
        file.display(),
        s.message_count()
    )];
    for t in s.topics() {
        lines.push(format!("  {:<36} {:<40} {}", t.name, t.type_name, t.count));
    }
    lines
}

/// `bag reindex`: the files repaired, the metadata rebuilt.
pub fn reindex_summary(bag: &Path, r: &ReindexReport) -> Vec<String> {
    let mut lines: Vec<String> = r
        .repaired
        .iter()
        .zip(&r.truncation)
        .map(|((file, kept), why)| {
            format!(
                "{}: was incomplete ({why}); rewritten with every readable message, original kept as {}",
                file.display(),
                kept.display()
            )
        })
        .collect();
    let info = &r.metadata.rosbag2_bagfile_information;
    lines.push(format!(
        "{}: metadata.yaml rebuilt: {} messages on {} topics",
        bag.display(),
        info.message_count,
        info.topics_with_message_count.len()
    ));
    lines
}

/// `report`: the README's table of errors against the exact solutions, then a PASS or
/// FAIL line per check (nothing when the report ran no exact-solution scene).
pub fn exact_summary(exact: &[crate::report::exact_run::ExactSceneReport]) -> Vec<String> {
    if exact.is_empty() {
        return Vec::new();
    }
    let mut lines = vec![crate::report::exact_output::readme_table(exact)];
    for c in exact.iter().flat_map(|s| &s.checks) {
        lines.push(format!(
            "{} {}: {}: measured {}",
            if c.pass { "PASS" } else { "FAIL" },
            c.scene,
            c.what,
            c.measured.map_or("n/a".into(), |m| format!("{m:.4}"))
        ));
    }
    lines
}

/// The node's last line on stderr.
pub fn node_stopped(s: &NodeStats) -> String {
    format!(
        "[developable_sim] stopped at t = {:.3} s after {} steps ({} poses received, {} rejected); \
         tick -> markers median {:.3} ms, p99 {:.3} ms",
        s.sim_time,
        s.steps,
        s.inputs_received,
        s.inputs_rejected,
        s.tick_to_markers.median_ms,
        s.tick_to_markers.p99_ms
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::replay::TopicReport;
    use crate::stats::{ContactStats, PhaseMs};

    #[test]
    fn run_summary_has_a_paper_line_and_a_contact_line_only_when_they_apply() {
        let mut s = RunStats {
            scene: "torsion".into(),
            steps: 10,
            dt: 0.01,
            finite: true,
            ..RunStats::default()
        };
        let lines = run_summary(&s);
        assert_eq!(lines.len(), 1);
        assert!(
            lines[0].starts_with("torsion: 10 steps of 0.01 s,"),
            "{}",
            lines[0]
        );
        assert!(lines[0].ends_with("finite: true"));
        s.compression_mean_pct = Some(0.5);
        s.compressed_edges_pct = Some(2.0);
        s.triangles_mean = Some(100.0);
        s.singular_vertices = Some(3);
        s.phase_ms = Some(PhaseMs {
            simulation: 1.0,
            remesh: 2.0,
            isometry: 3.0,
        });
        s.contact = Some(ContactStats {
            contacts_max: 7,
            ..ContactStats::default()
        });
        let lines = run_summary(&s);
        assert_eq!(lines.len(), 3);
        assert_eq!(
            lines[1],
            "paper: compression mean 0.500 %, edges compressed > 1 %: 2.00 %, triangles mean 100.0, \
             singular vertices 3, phases (median ms) simulation 1.000 remesh 2.000 isometry 3.000"
        );
        assert!(lines[2].contains("contacts max 7,"), "{}", lines[2]);
    }

    #[test]
    fn replay_summary_names_the_largest_difference_and_where() {
        let mut r = ReplayReport {
            bag: "b".into(),
            scene: "s".into(),
            steps: 3,
            identical: true,
            topics: vec![TopicReport {
                topic: "/clock".into(),
                compared: 3,
                ..TopicReport::default()
            }],
            ..ReplayReport::default()
        };
        let lines = replay_summary(&r);
        assert_eq!(lines.len(), 3);
        assert_eq!(
            lines[2],
            "identical: every recorded output reproduced bit for bit"
        );
        r.identical = false;
        r.max_abs_difference = 0.25;
        r.topics[0].differing = 1;
        r.topics[0].max_at = "step 2: clock.sec".into();
        r.truncated = Some("no footer".into());
        let lines = replay_summary(&r);
        assert!(lines[1].ends_with(" at step 2: clock.sec"), "{}", lines[1]);
        assert_eq!(
            lines[2],
            "  note: the bag ends early (no footer); compared up to there"
        );
        assert_eq!(lines[3], "DIFFERENT: largest difference 2.500e-1");
    }
}
