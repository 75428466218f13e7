//! The stress cases: the repository's scenes (`config/scenes`, `config/stress`) plus
//! `--set` overrides, each with its time steps, lengths, expectation and allowance.

use super::{
    Allowance, Expectation, StressCase, DEFAULT_ALLOWANCE, ENERGY_RELATIVE_TOLERANCE,
    PAPER_ENERGY_RELATIVE_TOLERANCE, TIME_STEPS,
};

fn none(_: f64, _: f64) -> Vec<String> {
    Vec::new()
}

/// The suite (issue 6): bending stiffness x1e4 and x1e-4 of the default (0.1 J),
/// an 8 pi twist, extreme drag, a 0.5 m handle jump in one tick, two handles pulled
/// apart beyond the ribbon's length, a 500-element ribbon, heavy paper crumpling and
/// 50 % paper compression; and contact (issue 46): a fine falling ribbon, a stiff one,
/// a fast push, the double chain's impact.
pub fn cases() -> Vec<StressCase> {
    let mut cases = bending_cases();
    cases.extend(loading_cases());
    cases.push(resolution_case());
    cases.extend(paper_cases());
    cases.extend(contact_cases());
    cases
}

/// Contact inside the step (`contact.method: barrier`, docs/contact_barrier.md) where
/// it is hard: every published frame exactly isometric and nothing overlapping, on top
/// of the suite's energy bound (which counts the work of moving colliders).
fn contact_cases() -> Vec<StressCase> {
    let contact = |name, description, scene, overrides, duration, quick_duration| StressCase {
        name,
        description,
        scene,
        overrides,
        duration,
        quick_duration,
        max_steps: 300,
        quick_max_steps: 80,
        quick_dts: &[0.01, 0.1],
        expectation: Expectation::ExactContact,
        energy_tolerance: ENERGY_RELATIVE_TOLERANCE,
        allowance: DEFAULT_ALLOWANCE,
    };
    vec![
        contact(
            "contact_falling_n600",
            "falling ribbon, 600 elements: folds finer than the thickness allows",
            "scenes/ribbon_falling.yaml",
            |_, _| vec!["ribbon.segments=600".into()],
            1.5,
            0.8,
        ),
        contact(
            "contact_falling_stiff",
            "falling ribbon, bending stiffness 1e3 x the scene's (2 J): it lands end first and bounces",
            "scenes/ribbon_falling.yaml",
            |_, _| vec!["ribbon.bending_stiffness=2.0".into()],
            1.5,
            0.8,
        ),
        contact(
            "contact_fast_push",
            "gripper finger sweeping a ribbon at 2.5 m/s (10 x the scene's)",
            "scenes/ribbon_gripper_push.yaml",
            |_, _| vec!["handles.0.trajectory.motions.1.end=0.3".into()],
            0.6,
            0.4,
        ),
        contact(
            "contact_chain_impact",
            "two chains of 9 loops flying into each other",
            "scenes/ribbon_double_chain.yaml",
            none,
            0.6,
            0.3,
        ),
    ]
}

/// Every time step of a full run (the quick runs of most cases use them all).
const ALL: &[f64] = &TIME_STEPS;

/// Ribbon bending stiffness alpha far from the default 0.1 J: x1e4 and x1e-4.
fn bending_cases() -> Vec<StressCase> {
    vec![
        StressCase {
            name: "bending_x1e4",
            description: "two grippers, bending stiffness 1e4 x default (1000 J)",
            scene: "scenes/ribbon_two_grippers.yaml",
            overrides: |_, _| vec!["ribbon.bending_stiffness=1000.0".into()],
            duration: 2.0,
            quick_duration: 0.5,
            max_steps: 1000,
            quick_max_steps: 60,
            quick_dts: ALL,
            expectation: Expectation::Stable,
            energy_tolerance: ENERGY_RELATIVE_TOLERANCE,
            allowance: DEFAULT_ALLOWANCE,
        },
        StressCase {
            name: "bending_x1e-4",
            description: "two grippers, bending stiffness 1e-4 x default (1e-5 J)",
            scene: "scenes/ribbon_two_grippers.yaml",
            overrides: |_, _| vec!["ribbon.bending_stiffness=1.0e-5".into()],
            duration: 2.0,
            quick_duration: 0.5,
            max_steps: 1000,
            quick_max_steps: 60,
            quick_dts: ALL,
            expectation: Expectation::Stable,
            energy_tolerance: ENERGY_RELATIVE_TOLERANCE,
            allowance: DEFAULT_ALLOWANCE,
        },
    ]
}

/// Ribbons loaded hard by their handles or a force: an 8 pi twist, a drag of 400 x the
/// loop's weight, a 0.5 m handle jump within one tick, handles pulled apart beyond the
/// ribbon's length.
fn loading_cases() -> Vec<StressCase> {
    vec![
        StressCase {
            name: "twist_8pi",
            description: "one end twisted by 8 pi over the run",
            scene: "scenes/ribbon_extreme_torsion.yaml",
            overrides: |d, _| {
                vec![
                    format!("handles.0.trajectory.motions.0.end={d}"),
                    format!(
                        "handles.0.trajectory.motions.0.angle={}",
                        8.0 * std::f64::consts::PI
                    ),
                ]
            },
            duration: 2.0,
            quick_duration: 1.0,
            max_steps: 1000,
            quick_max_steps: 100,
            quick_dts: ALL,
            expectation: Expectation::Stable,
            energy_tolerance: ENERGY_RELATIVE_TOLERANCE,
            allowance: DEFAULT_ALLOWANCE,
        },
        StressCase {
            name: "extreme_drag",
            description: "looped ribbon dragged by 10 x the paper's force (400 x its weight)",
            scene: "scenes/ribbon_extreme_dragging.yaml",
            overrides: |_, _| vec!["forces.0.force=[20.0, 0.0, -10.0]".into()],
            duration: 1.0,
            quick_duration: 0.3,
            max_steps: 1000,
            quick_max_steps: 40,
            quick_dts: ALL,
            expectation: Expectation::Stable,
            energy_tolerance: ENERGY_RELATIVE_TOLERANCE,
            allowance: Allowance {
                unconverged_fraction: 0.1,
                rejected_steps: 0,
                reason:
                    "at dt 0.001 s the 20 N drag on the closed loop leaves 3 of 40 quick steps \
                         (10, 18, 19; 2026-12-02) with one augmented-Lagrangian round on the \
                         200-iteration inner limit short of the 1e-6 gradient reduction, the loop \
                         closed to 1e-6 m and the energy bound met",
            },
        },
        StressCase {
            name: "handle_jump",
            description: "gripper target jumps 0.5 m within one tick",
            scene: "stress/ribbon_handle_jump.yaml",
            overrides: |d, dt| {
                // half a step after the step nearest a third of the run: the jump
                // falls inside one step, clear of the step boundaries
                let start = ((d / 3.0 / dt).round() + 0.5) * dt;
                vec![
                    format!("handles.0.trajectory.motions.0.start={start}"),
                    format!("handles.0.trajectory.motions.0.end={}", start + 1e-9),
                ]
            },
            duration: 1.0,
            quick_duration: 0.4,
            max_steps: 1000,
            quick_max_steps: 60,
            quick_dts: ALL,
            expectation: Expectation::Stable,
            energy_tolerance: ENERGY_RELATIVE_TOLERANCE,
            allowance: DEFAULT_ALLOWANCE,
        },
        StressCase {
            name: "over_stretch",
            description: "two handles pulled to 1.5 m apart on a 1 m inextensible ribbon",
            scene: "stress/ribbon_over_stretch.yaml",
            overrides: |d, _| {
                vec![
                    format!("handles.0.trajectory.motions.0.end={}", d / 2.0),
                    format!("handles.1.trajectory.motions.0.end={}", d / 2.0),
                ]
            },
            duration: 1.0,
            quick_duration: 0.4,
            max_steps: 1000,
            quick_max_steps: 60,
            quick_dts: ALL,
            // grasp points at most l = 1 m apart, targets 1.5 m: the larger of the two
            // violations is at least (1.5 - 1) / 2 m (less a round-off margin)
            expectation: Expectation::ViolationAtLeast(0.25 - 1e-6),
            energy_tolerance: ENERGY_RELATIVE_TOLERANCE,
            allowance: DEFAULT_ALLOWANCE,
        },
    ]
}

/// A fine ribbon: 500 elements.
fn resolution_case() -> StressCase {
    StressCase {
        name: "segments_500",
        description: "two grippers, 500 elements",
        scene: "scenes/ribbon_two_grippers.yaml",
        overrides: |_, _| vec!["ribbon.segments=500".into()],
        duration: 1.0,
        quick_duration: 0.3,
        max_steps: 200,
        // about 1 s per step at dt 0.1 (dense Newton on 1000 unknowns)
        quick_max_steps: 3,
        quick_dts: &[0.001, 0.1],
        expectation: Expectation::Stable,
        energy_tolerance: ENERGY_RELATIVE_TOLERANCE,
        allowance: DEFAULT_ALLOWANCE,
    }
}

/// Paper: heavy crumpling and 50 % compression.
fn paper_cases() -> Vec<StressCase> {
    vec![
        StressCase {
            name: "paper_crumple",
            description: "paper, heavy crumpling (Schreck et al. fig. 22)",
            scene: "scenes/paper_crumple.yaml",
            overrides: none,
            duration: 3.0,
            quick_duration: 1.0,
            max_steps: 1000,
            quick_max_steps: 30,
            quick_dts: ALL,
            expectation: Expectation::Stable,
            energy_tolerance: PAPER_ENERGY_RELATIVE_TOLERANCE,
            // the suite's default: with the strain-limited length restoration the FEM
            // of step 1 starts each frame from an isometric sheet and converges at dt
            // 0.1 s too (the paper's restoration needed 20 % in 2026-12-02's runs)
            allowance: DEFAULT_ALLOWANCE,
        },
        StressCase {
            name: "paper_compression_50",
            description: "paper, compressed to 50 % of its width",
            scene: "stress/paper_compression.yaml",
            overrides: |d, _| {
                vec![
                    format!("handles.0.trajectory.motions.0.end={d}"),
                    format!("handles.1.trajectory.motions.0.end={d}"),
                ]
            },
            duration: 1.0,
            quick_duration: 1.0,
            max_steps: 1000,
            quick_max_steps: 30,
            quick_dts: ALL,
            expectation: Expectation::Stable,
            energy_tolerance: PAPER_ENERGY_RELATIVE_TOLERANCE,
            allowance: DEFAULT_ALLOWANCE,
        },
    ]
}
