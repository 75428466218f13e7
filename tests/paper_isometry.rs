//! Issue 20: the paper scenes stay isometric to their pattern, measured on the S_P
//! edges (|l / l_rest - 1|, `--stats` `edge_strain`): every scene's final frame at or
//! below Schreck et al.'s table IV (fig. 1: 0.89 % mean compression and 8 % of edges
//! compressed over 1 %; fig. 22's crumpling: 1.47 % and 11 %), at most 2 % of edges
//! over 1 % |strain| in the gentle scenes, and no edge over 10 % in any frame.

use std::path::PathBuf;

use developable_sim::runner;
use developable_sim::scene;
use developable_sim::stats::{EdgeStrainPct, EdgeStrainStats, RunStats};

fn run(name: &str, sets: &[&str]) -> RunStats {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("config/scenes")
        .join(format!("{name}.yaml"));
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let mut s = scene::load(&path, &sets).unwrap_or_else(|e| panic!("{e}"));
    runner::run(&mut s, &mut (), &|| false).expect("run")
}

/// The bounds a scene's final frame must meet.
#[derive(Clone, Copy, Debug)]
enum Bound {
    /// Table IV: mean compression and share of edges compressed over 1 %, %.
    TableIv { mean_pct: f64, edges_pct: f64 },
    /// Share of edges with |strain| over 1 %, %.
    Gentle { edges_pct: f64 },
}

/// What breaks the bounds (empty when none): the final frame against `bound`, every
/// frame against the 10 % largest |strain|.
fn violations(strain: &EdgeStrainStats, bound: Bound) -> Vec<String> {
    let f: &EdgeStrainPct = &strain.final_frame;
    let mut out = Vec::new();
    match bound {
        Bound::TableIv {
            mean_pct,
            edges_pct,
        } => {
            if f.compression_mean_pct > mean_pct {
                out.push(format!(
                    "final mean compression {:.3} % > {mean_pct} %",
                    f.compression_mean_pct
                ));
            }
            if f.compressed_edges_pct > edges_pct {
                out.push(format!(
                    "final edges compressed over 1 %: {:.2} % > {edges_pct} %",
                    f.compressed_edges_pct
                ));
            }
        }
        Bound::Gentle { edges_pct } => {
            if f.strained_edges_pct > edges_pct {
                out.push(format!(
                    "final edges over 1 % |strain|: {:.2} % > {edges_pct} %",
                    f.strained_edges_pct
                ));
            }
        }
    }
    if strain.max.strain_max_pct > 10.0 {
        out.push(format!(
            "an edge at {:.2} % |strain| in some frame (> 10 %)",
            strain.max.strain_max_pct
        ));
    }
    out
}

fn check(name: &str, sets: &[&str], bound: Bound) -> Result<(), String> {
    let stats = run(name, sets);
    let strain = stats.edge_strain.as_ref().expect("a paper scene");
    let v = violations(strain, bound);
    if v.is_empty() {
        Ok(())
    } else {
        Err(format!("{name} {sets:?}: {}", v.join("; ")))
    }
}

const FIG_1: Bound = Bound::TableIv {
    mean_pct: 0.89,
    edges_pct: 8.0,
};
const FIG_22: Bound = Bound::TableIv {
    mean_pct: 1.47,
    edges_pct: 11.0,
};
const GENTLE: Bound = Bound::Gentle { edges_pct: 2.0 };

#[test]
fn every_paper_scene_ends_isometric_within_table_iv() {
    let scenes = [
        ("paper_cylinder_then_bend", FIG_1),
        ("paper_crumple", FIG_22),
        ("paper_first_singularity", GENTLE),
        ("paper_unload", GENTLE),
        ("paper_mobius_strip", GENTLE),
        ("paper_preset_crease", GENTLE),
    ];
    let failed: Vec<String> = scenes
        .iter()
        .filter_map(|(name, bound)| check(name, &[], *bound).err())
        .collect();
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

fn crumple_seeds(seeds: std::ops::Range<u32>) {
    let failed: Vec<String> = seeds
        .filter_map(|seed| check("paper_crumple", &[&format!("seed={seed}")], FIG_22).err())
        .collect();
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

#[test]
fn the_crumpling_stays_within_table_iv_over_seeds_0_to_4() {
    crumple_seeds(0..5);
}

#[test]
fn the_crumpling_stays_within_table_iv_over_seeds_5_to_9() {
    crumple_seeds(5..10);
}

/// The checker's negative test: each bound broken alone is reported.
#[test]
fn the_bounds_report_what_breaks_them() {
    let ok = EdgeStrainPct {
        compression_mean_pct: 0.1,
        compressed_edges_pct: 1.0,
        strain_mean_pct: 0.1,
        strain_max_pct: 2.0,
        stretch_max_pct: 2.0,
        strained_edges_pct: 1.0,
    };
    let stats = |f: EdgeStrainPct, max: EdgeStrainPct| EdgeStrainStats {
        final_frame: f,
        max,
        time_mean: f,
        frames: Vec::new(),
    };
    assert!(violations(&stats(ok, ok), FIG_1).is_empty());
    assert!(violations(&stats(ok, ok), GENTLE).is_empty());
    let mean = EdgeStrainPct {
        compression_mean_pct: 0.9,
        ..ok
    };
    assert_eq!(violations(&stats(mean, ok), FIG_1).len(), 1);
    let edges = EdgeStrainPct {
        compressed_edges_pct: 8.5,
        ..ok
    };
    assert_eq!(violations(&stats(edges, ok), FIG_1).len(), 1);
    let strained = EdgeStrainPct {
        strained_edges_pct: 2.5,
        ..ok
    };
    assert_eq!(violations(&stats(strained, ok), GENTLE).len(), 1);
    let once = EdgeStrainPct {
        strain_max_pct: 10.5,
        ..ok
    };
    assert_eq!(violations(&stats(ok, once), GENTLE).len(), 1);
}
