//! The paper simulator (Schreck et al.) on its scenes: near-isometry, singular
//! vertices appearing where the paper has them and persisting, determinism, the effect
//! of epsilon_c, and the stats JSON fields of paper objects.

use developable_sim::paper::PaperSim;
use developable_sim::scene::{self, Scene};
use developable_sim::stats::RunStats;

mod common;
use common::{load, run, scene_path};

fn paper(scene: &Scene) -> &PaperSim {
    scene.world.object_as::<PaperSim>(0).expect("a paper scene")
}

/// Issue 20's targets on a run's S_P edges: at most `share` % of them strained by more
/// than 1 % either way on the final frame (table IV counts compression only: 8 % in
/// fig. 1, 11 % in the crumpling), and no edge strained by more than 10 % in any frame.
fn assert_isometric(name: &str, stats: &RunStats, share: f64) {
    let e = stats.edge_strain.as_ref().expect("paper stats");
    let (last, worst) = (e.final_frame.strained_edges_pct, e.max.strain_max_pct);
    assert!(
        last <= share,
        "{name}: {last} % of the edges over 1 % at the end"
    );
    assert!(worst <= 10.0, "{name}: an edge strained by {worst} %");
}

#[test]
fn cylinder_then_bend_is_nearly_isometric_and_creases_only_in_the_second_bend() {
    let (s, stats) = run("paper_cylinder_then_bend", &[]);
    assert!(stats.finite);
    // the targets of the issue (the paper's fig. 1: 0.89 % and 8 %, table IV)
    let c = stats.compression_mean_pct.expect("paper stats");
    let n = stats.compressed_edges_pct.expect("paper stats");
    assert!(c <= 0.5, "compression_mean_pct {c}");
    assert!(n <= 5.0, "compressed_edges_pct {n}");
    assert_isometric("paper_cylinder_then_bend", &stats, 8.0);
    // the cylinder wrap (0-1.5 s) is smooth; the orthogonal bend creates singular points
    let first = stats
        .first_singular_point
        .as_ref()
        .expect("singular points appear");
    assert!(first.time > 1.5, "first singular point at {} s", first.time);
    assert!(stats.singular_vertices.unwrap() >= 1);
    // a coarse mesh (table V: 87-156 triangles)
    let t = stats.triangles_mean.unwrap();
    assert!((50.0..200.0).contains(&t), "triangles {t}");
    assert!(stats.phase_ms.is_some());
    // singular points reported with their stable ids, on the mesh
    let p = paper(&s);
    assert_eq!(p.singular_points().len(), stats.singular_vertices.unwrap());
    let mut ids: Vec<u64> = p.singular_points().iter().map(|s| s.id).collect();
    ids.dedup();
    assert_eq!(ids.len(), p.singular_points().len(), "ids are unique");
    // a conflict next to an existing d-cone reuses its apex: no two singular points
    // closer than one boundary sample (1/rho_bound, rho_bound = 1.2 /cm)
    let spacing = 1.0 / p.params.boundary_density;
    let pts = p.singular_points();
    for (i, a) in pts.iter().enumerate() {
        for b in &pts[i + 1..] {
            let d = (a.material - b.material).norm();
            assert!(
                d >= spacing,
                "singular points {} and {} are {d} m apart",
                a.id,
                b.id
            );
        }
    }
}

#[test]
fn the_same_seed_gives_a_bit_identical_run_and_another_seed_moves_the_singular_point() {
    let sets = ["duration=1.2", "seed=3"];
    let (a, sa) = run("paper_first_singularity", &sets);
    let (b, sb) = run("paper_first_singularity", &sets);
    let (ma, mb) = (a.world.mesh(0), b.world.mesh(0));
    assert_eq!(ma.vertices, mb.vertices, "bit-identical vertices");
    assert_eq!(ma.triangles, mb.triangles);
    assert_eq!(paper(&a).singular_points(), paper(&b).singular_points());
    let fa = sa
        .first_singular_point
        .expect("a singular point appears after the push");
    let fb = sb.first_singular_point.unwrap();
    assert_eq!(fa.material, fb.material);
    // the position of a new singular vertex is random (sec. 5.2): another seed moves it
    let (_, sc) = run("paper_first_singularity", &["duration=1.2", "seed=4"]);
    let fc = sc.first_singular_point.unwrap();
    assert_ne!(fa.material, fc.material);
    // it appears once the orthogonal push has started (1 s), not before
    assert!(fa.time > 1.0 && fa.time < 1.2, "{}", fa.time);
}

#[test]
fn singular_vertices_survive_unloading() {
    let mut s = load("paper_unload", &[]);
    let dt = s.world.dt();
    let release = 1.5;
    // the release acts at the start of the step that ends at 1.5 s: the state before
    // it is the one a step earlier
    let steps_loaded = (release / dt).round() as usize - 1;
    let mut elastic_loaded = 0.0;
    for _ in 0..steps_loaded {
        let r = s.world.step(&[]);
        elastic_loaded = r.objects[0].energies.elastic;
    }
    let before: Vec<_> = paper(&s).singular_points().to_vec();
    assert!(!before.is_empty(), "the push created singular vertices");
    let total = (s.duration / dt).round() as usize;
    let mut elastic_end = 0.0;
    for _ in steps_loaded..total {
        let r = s.world.step(&[]);
        elastic_end = r.objects[0].energies.elastic;
        assert!(s.world.mesh(0).is_finite());
    }
    let after = paper(&s).singular_points();
    // persistence: every singular vertex is still there, same id, same pattern point
    for b in &before {
        let a = after
            .iter()
            .find(|a| a.id == b.id)
            .expect("singular vertex kept");
        assert_eq!(a.material, b.material);
    }
    // the sheet straightens when unloaded (fig. 18): its elastic energy drops
    assert!(
        elastic_end < 0.5 * elastic_loaded,
        "elastic energy {elastic_loaded} J loaded -> {elastic_end} J unloaded"
    );
}

/// Issue 49, where fig. 1's extra singular points come from: step 2's diagnostic
/// (`crumple_attempts`) tells the compression a frame's FEM step makes from the one
/// step 3 hands over. The two points of the bend's first frame (t = 1.533 s, the
/// paper's two) come from triangles next to the held corners that started the frame
/// uncompressed; the next, at t = 1.567 s, from fig. 11's transition triangle beside
/// the first point's cone, cut out of the curved cylinder, which started the frame
/// compressed above epsilon_c (0.18 %, the frame added 0.09 %, below it). Measured
/// 2026-12-07; docs/paper_simulator.md, "Where the extra singular points come from".
/// Not fixed: this pins the measurement, so that a fix shows here.
#[test]
fn fig1_extra_singular_points_start_from_compression_handed_over_by_step_3() {
    let mut s = load("paper_cylinder_then_bend", &["seed=0", "duration=1.6"]);
    let eps = paper(&s).params.compression_threshold;
    let steps = (s.duration / s.world.dt()).round() as usize;
    // (time, attempts that changed S_G) of each frame that made a new singular point
    let mut made = Vec::new();
    for _ in 0..steps {
        let r = s.world.step(&[]);
        let f = paper(&s).frame_stats();
        let new = f.crumple_events.iter().any(|e| {
            matches!(
                e,
                developable_sim::paper::crumpling::CrumpleEvent::NewSingular { .. }
            )
        });
        if new {
            let changed: Vec<_> = f
                .crumple_attempts
                .iter()
                .filter(|a| a.changed)
                .copied()
                .collect();
            made.push((r.time, changed));
        }
    }
    assert!(made.len() >= 2, "{made:?}");
    let (t0, first) = &made[0];
    assert!((t0 - 1.533).abs() < 0.01, "the bend's first frame: {t0}");
    assert_eq!(first.len(), 2, "{first:?}");
    for a in first {
        // the sheet's: below epsilon_c when the frame began, above it after the FEM
        assert!(a.compression_at_start < eps && a.compression > eps, "{a:?}");
        assert!(a.touches_held, "{a:?}");
    }
    let (t1, next) = &made[1];
    assert!((t1 - 1.567).abs() < 0.01, "{t1}");
    let transition = next
        .iter()
        .find(|a| {
            let c = a.corners;
            [(0.0049, 0.0912), (0.0087, 0.0), (0.0113, 0.1)]
                .iter()
                .all(|(u, v)| {
                    c.iter()
                        .any(|p| (p.x - u).abs() < 1e-4 && (p.y - v).abs() < 1e-4)
                })
        })
        .expect("the transition triangle of point 1 starts a strip");
    // handed over: above epsilon_c before the FEM step, which added less than it
    assert!(transition.compression_at_start > eps, "{transition:?}");
    assert!(
        transition.compression - transition.compression_at_start < eps,
        "{transition:?}"
    );
    // its borders are constrained by the paper's test (fig. 6d: a ruling sharper than
    // theta_0), not ours
    let theta0 = paper(&s).params.flat_angle;
    assert!(transition.border_dihedral[0][0] > theta0, "{transition:?}");
}

/// Issue 49, the attempts that change nothing: in fig. 1 (seed 0) step 2 finds a
/// compressed flat triangle 350 times and changes S_G 16 times. Of the 334 others, 254
/// end with both borders on singular vertices that existed already and are joined by a
/// crease (`Unchanged::CreaseExists`: our reuse rules, where the paper's fig. 6c, d
/// would add a new point), and 12 have a free border (fig. 7, 8: the only strips
/// whose rulings may reach the free boundary). Measured 2026-12-08 on 0ab3a4b; docs/
/// paper_simulator.md, "The attempts that change nothing". Pins the measurement.
#[test]
fn fig1_attempts_that_change_nothing_end_on_existing_singular_vertices() {
    use developable_sim::paper::crumpling::{Border, Unchanged};
    let mut s = load("paper_cylinder_then_bend", &["seed=0"]);
    let steps = (s.duration / s.world.dt()).round() as usize;
    let mut attempts = Vec::new();
    for _ in 0..steps {
        s.world.step(&[]);
        attempts.extend(paper(&s).frame_stats().crumple_attempts.iter().copied());
    }
    // every attempt that changes nothing says why, and only those
    for a in &attempts {
        assert_eq!(a.changed, a.unchanged.is_none(), "{a:?}");
    }
    let unchanged: Vec<_> = attempts.iter().filter(|a| !a.changed).collect();
    assert!(unchanged.len() > 300, "{} attempts", unchanged.len());
    let crease = unchanged
        .iter()
        .filter(|a| matches!(a.unchanged, Some(Unchanged::CreaseExists(_))))
        .count();
    // 254 of 334 measured: more than two thirds
    assert!(
        3 * crease > 2 * unchanged.len(),
        "{crease} of {}",
        unchanged.len()
    );
    let free = unchanged
        .iter()
        .filter(|a| a.borders.is_some_and(|b| b.contains(&Border::Boundary)))
        .count();
    // 12 of 334 measured: under a twentieth
    assert!(20 * free < unchanged.len(), "{free} of {}", unchanged.len());
}

/// Mean singular vertices of fig. 1's scenario over seeds 0-3 at each epsilon_c of
/// fig. 21 (1 %, 0.5 %, 0.2 %), with `extra` overrides.
fn singular_by_epsilon_c(extra: &[&str]) -> Vec<(&'static str, f64)> {
    let seeds = ["seed=0", "seed=1", "seed=2", "seed=3"];
    ["0.01", "0.005", "0.002"]
        .into_iter()
        .map(|eps| {
            let set = format!("paper.compression_threshold={eps}");
            let n: usize = seeds
                .iter()
                .map(|seed| {
                    let mut sets = vec![*seed, set.as_str()];
                    sets.extend_from_slice(extra);
                    let (_, st) = run("paper_cylinder_then_bend", &sets);
                    st.singular_vertices.unwrap()
                })
                .sum();
            (eps, n as f64 / seeds.len() as f64)
        })
        .collect()
}

#[test]
fn fewer_singular_points_as_epsilon_c_grows() {
    // fig. 21: the fig. 1 scenario with epsilon_c = 1 %, 0.5 %, 0.2 %: a stiffer paper
    // (larger epsilon_c) gets fewer singular points; averaged over seeds since the
    // placement of each one is random (sec. 5.2). The paper's own restoration shows
    // the whole trend.
    let paper = singular_by_epsilon_c(&["paper.length_restoration=paper"]);
    for w in paper.windows(2) {
        assert!(
            w[1].1 > w[0].1,
            "paper restoration, mean singular points by epsilon_c: {paper:?}"
        );
    }
    // The strain limit (the default) shows it from 0.5 % to 0.2 % only: a sheet that
    // cannot stretch creases as often at 1 % as at 0.5 % (12.3 and 11.5 singular
    // vertices over seeds 0-9, 2026-12-05; docs/paper_simulator.md, known gaps)
    let limit = singular_by_epsilon_c(&[]);
    assert!(
        limit[2].1 > limit[0].1 && limit[2].1 > limit[1].1,
        "strain limit, mean singular points by epsilon_c: {limit:?}"
    );
}

#[test]
fn heavy_crumpling_over_seeds_stays_isometric_and_creases() {
    // fig. 22, second row. The placement of each singular vertex is random (sec. 5.2)
    // and the count follows it, so over seeds 0-9: the paper's text has "more than
    // twenty singular vertices ... progressively created", its table V at most 15
    // interior ones.
    let mut counts = Vec::new();
    for seed in 0..10 {
        let name = format!("paper_crumple seed {seed}");
        let (_, stats) = run("paper_crumple", &[&format!("seed={seed}")]);
        assert!(stats.finite, "{name}");
        assert_isometric(&name, &stats, 11.0);
        counts.push(stats.singular_vertices.unwrap());
    }
    let mean = counts.iter().sum::<usize>() as f64 / counts.len() as f64;
    assert!(mean >= 15.0, "singular vertices by seed {counts:?}");
    assert!(
        counts.iter().any(|&n| n > 20),
        "singular vertices by seed {counts:?}"
    );
}

#[test]
fn the_pushed_and_unloaded_sheets_stay_isometric() {
    for name in ["paper_first_singularity", "paper_unload"] {
        let (_, stats) = run(name, &[]);
        assert!(stats.finite, "{name}");
        assert_isometric(name, &stats, 2.0);
    }
}

#[test]
fn the_mobius_strip_and_the_preset_crease_stay_finite_and_nearly_isometric() {
    for name in ["paper_mobius_strip", "paper_preset_crease"] {
        let (_, stats) = run(name, &[]);
        assert!(stats.finite, "{name}");
        let c = stats.compression_mean_pct.unwrap();
        assert!(c <= 0.5, "{name}: compression_mean_pct {c}");
        assert_isometric(name, &stats, 2.0);
    }
}

#[test]
fn the_preset_crease_folds_the_sheet() {
    let (s, _) = run("paper_preset_crease", &[]);
    let p = paper(&s);
    let sp = p.physical_mesh();
    // the hinges along the crease (u = 0.05) are folded towards their rest angle
    // and they are a straight chain of S_P edges covering the whole crease, each with
    // the preset rest angle (a curved face of S_G must not swallow the crease)
    let mut folded = Vec::new();
    let mut covered = 0.0;
    for h in &sp.hinges {
        let (a, b) = (sp.material[h.v[0] as usize], sp.material[h.v[1] as usize]);
        if (a.x - 0.05).abs() < 1e-9 && (b.x - 0.05).abs() < 1e-9 {
            assert_eq!(h.rest_angle, 1.2, "hinge {a:?}-{b:?}");
            covered += (a - b).norm();
            let x = h.v.map(|i| sp.position[i as usize].coords);
            folded.push(developable_sim::paper::physical::signed_dihedral(&x).abs());
        }
    }
    assert!(
        (covered - 0.1).abs() < 1e-9,
        "crease hinges cover {covered} m of 0.1 m"
    );
    // no ruling crosses the crease nor ends on its interior
    let layer = p.geometric_layer();
    for r in layer.regions.iter().flat_map(|r| &r.rulings) {
        let a = layer.endpoint_material(p.pattern(), &r.a);
        let b = layer.endpoint_material(p.pattern(), &r.b);
        let side = |m: &developable_sim::geometry::Point2| {
            if (m.x - 0.05).abs() < 1e-9 {
                0.0
            } else {
                (m.x - 0.05).signum()
            }
        };
        assert!(
            side(&a) * side(&b) >= 0.0,
            "ruling {a:?}-{b:?} crosses the crease"
        );
        for m in [a, b] {
            assert!(
                side(&m) != 0.0 || m.y.abs() < 1e-9 || (m.y - 0.1).abs() < 1e-9,
                "ruling ends on the crease at {m:?}"
            );
        }
    }
    let mean = folded.iter().sum::<f64>() / folded.len() as f64;
    assert!(
        mean > 0.3,
        "mean fold along the crease {mean} rad (rest 1.2)"
    );
}

#[test]
fn paper_stats_fields_only_for_paper_scenes() {
    let (_, stats) = run("paper_preset_crease", &["duration=0.2"]);
    let json = serde_json::to_value(&stats).unwrap();
    for key in [
        "compression_mean_pct",
        "compressed_edges_pct",
        "triangles_mean",
        "singular_vertices",
        "phase_ms",
    ] {
        assert!(json.get(key).is_some(), "{key} missing");
    }
    for key in ["simulation", "remesh", "isometry"] {
        assert!(json["phase_ms"][key].as_f64().unwrap() >= 0.0);
    }
    // edge strains per frame, on the final frame, as the max and the mean over frames
    let strain = &json["edge_strain"];
    let frames = strain["frames"].as_array().expect("edge_strain.frames");
    assert_eq!(frames.len(), stats.steps);
    let fields = [
        "compression_mean_pct",
        "compressed_edges_pct",
        "strain_mean_pct",
        "strain_max_pct",
        "stretch_max_pct",
        "strained_edges_pct",
    ];
    for key in fields {
        let of = |f: &serde_json::Value| f[key].as_f64().unwrap_or_else(|| panic!("{key}"));
        let series: Vec<f64> = frames.iter().map(of).collect();
        assert_eq!(of(&strain["final"]), *series.last().unwrap(), "{key}");
        let max = series.iter().cloned().fold(f64::MIN, f64::max);
        assert_eq!(of(&strain["max"]), max, "{key}");
        let mean = series.iter().sum::<f64>() / series.len() as f64;
        assert!((of(&strain["time_mean"]) - mean).abs() <= 1e-12 * mean.abs().max(1.0));
    }
    assert_eq!(
        json["compression_mean_pct"].as_f64(),
        strain["time_mean"]["compression_mean_pct"].as_f64()
    );
    // the crease folds the sheet: stretch or compression is measured, not all zero
    assert!(strain["max"]["strain_max_pct"].as_f64().unwrap() > 0.0);
    let (_, ribbon) = run("ribbon_extreme_torsion", &["duration=0.05"]);
    let json = serde_json::to_value(&ribbon).unwrap();
    assert!(json.get("compression_mean_pct").is_none());
    assert!(json.get("edge_strain").is_none());
    assert!(json.get("phase_ms").is_none());
}

#[test]
fn bad_paper_scenes_name_the_key() {
    let path = scene_path("paper_preset_crease");
    let cases: [(&[&str], &str); 8] = [
        (&["handles.0.point=[0.02, 0.05]"], "handles.0.point"),
        (
            &["paper.compression_threshold=1.5"],
            "paper.compression_threshold",
        ),
        (&["paper.size=[0.1, -0.1]"], "paper.size.1"),
        (&["paper.creases.0.to=[0.05, 0.05]"], "paper.creases.0.to"),
        (
            &["paper.colliders=[{kind: cube}]"],
            "paper.colliders.0.kind",
        ),
        (&["paper.strain_limit=0.7"], "paper.strain_limit"),
        (
            &["paper.strain_limit_stiffness=-1"],
            "paper.strain_limit_stiffness",
        ),
        (
            &["paper.length_restoration=exact"],
            "paper.length_restoration",
        ),
    ];
    for (sets, key) in cases {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        let err = scene::load(&path, &sets).expect_err(key).to_string();
        assert!(err.contains(key), "`{err}` should name `{key}`");
    }
    let sets = vec!["paper.stiffness=3".to_string()];
    let err = scene::load(&path, &sets)
        .expect_err("unknown key")
        .to_string();
    assert!(err.contains("stiffness"), "{err}");
}

/// Two corners of a 0.1 m sheet pulled 20 mm farther apart than the sheet is wide, then
/// brought back to the sheet's width (issue 20): the sheet is not stretched, the handle is
/// named once when it goes out of reach and once when it is back, and the status
/// reports how far its target is from where the sheet can be.
const PULLED_APART: &str = "\
name: paper_pulled_apart
duration: 1.0
dt: 0.0333333333333
frame_id: world
seed: 0
gravity: [0.0, 0.0, 0.0]
paper:
  size: [0.1, 0.1]
handles:
  - name: left
    point: [0.0, 0.0]
    orientation: full
    trajectory:
      motions:
        - {start: 0.0, end: 0.5, translation: [-0.01, 0.0, 0.0]}
        - {start: 0.5, end: 0.9, translation: [0.01, 0.0, 0.0]}
  - name: right
    point: [0.1, 0.0]
    orientation: full
    trajectory:
      motions:
        - {start: 0.0, end: 0.5, translation: [0.01, 0.0, 0.0]}
        - {start: 0.5, end: 0.9, translation: [-0.01, 0.0, 0.0]}
";

#[test]
fn handles_pulled_beyond_the_sheet_are_named_and_the_sheet_is_not_stretched() {
    use developable_sim::sim::ReachWatch;
    let dir = common::scratch("pulled_apart");
    let path = dir.join("paper_pulled_apart.yaml");
    std::fs::write(&path, PULLED_APART).unwrap();
    let mut s = scene::load(&path, &[]).expect("the scene loads");
    let mut watch = ReachWatch::default();
    let mut messages = Vec::new();
    let mut violation_at_half = f64::NAN;
    let mut strain_max: f64 = 0.0;
    let steps = (s.duration / s.world.dt()).round() as usize;
    for _ in 0..steps {
        let r = s.world.step(&[]);
        messages.extend(
            watch
                .update(&r, s.world.object_names(), s.world.handles())
                .into_iter()
                .map(|m| m.to_string()),
        );
        if (r.time - 0.5).abs() < 1e-6 {
            violation_at_half = r.objects[0].constraint_violation;
        }
        strain_max = strain_max.max(s.world.mesh(0).edge_strain().strain_max_pct);
    }
    // at 0.5 s the targets are 0.12 m apart, 0.02 m beyond the sheet: each is 0.01 m
    // from the taut sheet's corner
    assert!(
        (violation_at_half - 0.01).abs() < 1e-9,
        "constraint_violation at 0.5 s: {violation_at_half} m"
    );
    // held taut, not stretched (without the reach projection: 47 % on one edge,
    // 2026-12-03)
    assert!(
        strain_max < 0.5,
        "largest edge strain {strain_max} % over the run"
    );
    assert_eq!(messages.len(), 2, "{messages:?}");
    assert!(
        messages[0].starts_with("warning: paper: handle 'left' cannot reach its target")
            || messages[0].starts_with("warning: paper: handle 'right' cannot reach its target"),
        "{messages:?}"
    );
    assert!(messages[1].contains("back within"), "{messages:?}");
}
