//! The Python wheel builds without the node: `cargo tree -p developable_sim_py` (what
//! maturin builds: the library with `default-features = false`) names none of the
//! crates that speak ROS or DDS, run an async runtime, write bags, serve Foxglove, plot
//! or parse a command line (Cargo.toml, `[features]`: `node` and `tools`). A Python
//! user installs the simulator, not a ROS stack.

mod purity;

use purity::{cargo_tree, forbidden_in, packages};

/// Crates the wheel must not contain, directly or through another crate, and why.
const FORBIDDEN: &[(&str, &str)] = &[
    ("ros2-client", "ROS 2"),
    ("rustdds", "DDS"),
    ("cdr-encoding", "the DDS wire format"),
    ("mcap", "bags"),
    ("tokio", "an async runtime"),
    ("smol", "an async runtime"),
    ("mio", "an event loop"),
    ("foxglove", "the live view"),
    ("transforms", "the TF buffer"),
    ("ctrlc", "signal handling"),
    ("clap", "the command line"),
    ("plotters", "the report's plots"),
    ("indicatif", "progress bars"),
];

#[test]
fn the_wheel_depends_on_no_node_crate() {
    let tree = cargo_tree("developable_sim_py");
    // the listing is the wheel's: the bindings, the library and the core are in it
    let found = packages(&tree);
    assert_eq!(found.first(), Some(&"developable_sim_py"), "{tree}");
    for expected in ["developable_sim", "developable_core", "pyo3", "numpy"] {
        assert!(found.contains(&expected), "{expected} missing from\n{tree}");
    }
    let bad = forbidden_in(&tree, FORBIDDEN);
    assert!(bad.is_empty(), "the wheel depends on node crates: {bad:?}");
}

/// The check's negative test: the library with its default features (the node) is
/// caught, with the crates a wheel would then carry; a synthetic listing with a
/// forbidden crate deep inside is caught, a look-alike name is not.
#[test]
fn the_check_finds_the_node_in_the_default_library() {
    let bad = forbidden_in(&cargo_tree("developable_sim"), FORBIDDEN);
    for expected in [
        "ros2-client (ROS 2)",
        "rustdds (DDS)",
        "mcap (bags)",
        "tokio (an async runtime)",
        "foxglove (the live view)",
        "plotters (the report's plots)",
    ] {
        assert!(
            bad.iter().any(|b| b == expected),
            "{expected} not found: {bad:?}"
        );
    }
    let tree = "developable_sim_py v0.1.0 (/x/python)\npyo3 v0.30.1\nmio-extras v1\nsmol v2.0.2\n";
    assert_eq!(
        forbidden_in(tree, FORBIDDEN),
        vec!["smol (an async runtime)"]
    );
}
