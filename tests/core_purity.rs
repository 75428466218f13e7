//! The simulation core builds without the edges: `cargo tree -p developable_core`
//! (normal dependencies, every feature the workspace enables) names none of the crates
//! that speak a protocol, write a file format or draw (ARCHITECTURE.md, "Layers"). A
//! library user who wants the simulators builds no DDS, tokio or plotters.

mod purity;

use purity::{cargo_tree, packages};

/// Crates the core must not depend on, directly or through another crate, and why.
const FORBIDDEN: &[(&str, &str)] = &[
    ("ros2-client", "ROS 2"),
    ("rustdds", "DDS"),
    ("mcap", "bags"),
    ("tokio", "an async runtime"),
    ("smol", "an async runtime"),
    ("foxglove", "the live view"),
    (
        "serde",
        "serialization (the edges make serializable counterparts)",
    ),
    ("serde_yaml", "scene files"),
    ("serde_json", "JSON"),
    ("plotters", "plots"),
    ("png", "images on disk"),
    ("clap", "the command line"),
];

/// The forbidden crates found in a dependency tree listing, with the reason.
fn forbidden_in(tree: &str) -> Vec<String> {
    purity::forbidden_in(tree, FORBIDDEN)
}

#[test]
fn the_core_depends_on_no_edge_crate() {
    let tree = cargo_tree("developable_core");
    // the listing is the core's: it starts with the core and holds its math crates
    let found = packages(&tree);
    assert_eq!(found.first(), Some(&"developable_core"), "{tree}");
    for expected in ["nalgebra", "faer", "parry3d-f64", "rayon"] {
        assert!(found.contains(&expected), "{expected} missing from\n{tree}");
    }
    let bad = forbidden_in(&tree);
    assert!(bad.is_empty(), "the core depends on edge crates: {bad:?}");
}

/// The check's negative test: a tree listing with an edge crate deep inside is caught;
/// a crate whose name only starts like a forbidden one is not.
#[test]
fn the_check_finds_an_edge_crate_in_a_tree() {
    let tree = "developable_core v0.1.0 (/x/core)\nnalgebra v0.33.2\n\
                serde_yaml_ng v0.1.0\nmcap v0.26.0\ntokio v1.48.0\n";
    let bad = forbidden_in(tree);
    assert_eq!(bad, vec!["mcap (bags)", "tokio (an async runtime)"]);
    assert!(forbidden_in("developable_core v0.1.0\nserde_yaml_ng v0.1\n").is_empty());
}
