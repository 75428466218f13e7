//! The `ribbons:`, `colliders:` and `contact:` scene sections: what gets built, the
//! stats keys, mesh colliders read from files, and errors that name the key.

use std::path::{Path, PathBuf};

use developable_sim::runner;
use developable_sim::scene;

mod common;
use common::{lowest_z, scratch};

const ONE: &str = "duration: 0.05\ndt: 0.01\nribbon:\n  segments: 10\n  base: {mode: floating, position: [0, 0, 0.2]}\n";

fn load_err(text: &str) -> String {
    match scene::load_str(text, &PathBuf::from("bad.yaml"), &[]) {
        Ok(_) => panic!("scene accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

fn check(text: &str, expected: &[&str]) {
    let msg = load_err(text);
    for e in expected {
        assert!(msg.contains(e), "message `{msg}` lacks `{e}`");
    }
}

#[test]
fn no_colliders_builds_no_contact_stage_and_reports_zero() {
    let mut s = scene::load_str(ONE, Path::new("one.yaml"), &[]).unwrap();
    assert!(s.world.contact_stage().is_none());
    let r = s.world.step(&[]);
    assert!(r.contact.is_none());
    let stats = runner::run(&mut s, &mut (), &|| false).unwrap();
    assert_eq!(stats.contact_ms.median, 0.0);
    assert_eq!(stats.penetration_max, 0.0);
    let json = serde_json::to_value(&stats).unwrap();
    assert!(
        json.get("contact").is_none(),
        "no contact details without a stage"
    );
    assert!(json["contact_ms"]["median"].is_number());
    assert!(json["penetration_max"].is_number());
}

#[test]
fn stats_carry_contact_time_and_penetration() {
    let text = format!("{ONE}colliders:\n  - {{kind: plane}}\ncontact: {{method: projection}}\n")
        .replace("duration: 0.05", "duration: 0.4");
    let mut s = scene::load_str(&text, Path::new("drop.yaml"), &[]).unwrap();
    let stats = runner::run(&mut s, &mut (), &|| false).unwrap();
    assert!(stats.contact_ms.median > 0.0);
    assert!(stats.penetration_max <= 1e-6, "{}", stats.penetration_max);
    let c = stats.contact.as_ref().expect("contact details");
    assert!(c.contacts_max > 0, "the ribbon landed: {c:?}");
    assert!(c.predicted_penetration_max > 1e-3, "{c:?}");
    assert_eq!(c.unresolved_steps, 0);
    let json = serde_json::to_value(&stats).unwrap();
    assert!(json["contact"]["correction_max"].as_f64().unwrap() > 0.0);
}

#[test]
fn a_contact_section_alone_builds_ribbon_ribbon_contact() {
    let text = "duration: 0.02\ndt: 0.01\ngravity: [0, 0, 0]\nribbons:\n  - {name: a, segments: 10, base: {mode: floating}}\n  - {name: b, segments: 10, base: {mode: floating, position: [0, 0, 0.1]}}\ncontact: {}\n";
    let mut s = scene::load_str(text, Path::new("two.yaml"), &[]).unwrap();
    assert_eq!(s.world.object_names(), ["a", "b"]);
    // the default method: the barrier inside the steps, no stage after them
    assert!(s.world.contact_stage().is_none());
    let (settings, colliders) = s.world.barrier_contact().expect("barrier contact");
    assert_eq!(settings.thickness, 1e-3);
    assert_eq!(settings.activation_distance, 1e-4);
    assert!(colliders.is_empty());
    assert!(s.world.step(&[]).contact.is_some());
    // the baseline on request
    let projection = text.replace("contact: {}", "contact: {method: projection}");
    let s = scene::load_str(&projection, Path::new("two.yaml"), &[]).unwrap();
    assert!(s.world.contact_stage().is_some());
    assert!(s.world.barrier_contact().is_none());
    assert_eq!(s.world.contact_stage().unwrap().settings().thickness, 1e-3);
}

#[test]
fn a_ribbon_lands_on_a_mesh_collider_read_from_an_obj_file() {
    let dir = scratch("mesh");
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    // a 2 m x 2 m square at z = 0.05 as two triangles
    std::fs::write(
        dir.join("meshes/table.obj"),
        "v -1 -1 0.05\nv 1 -1 0.05\nv 1 1 0.05\nv -1 1 0.05\nf 1 2 3 4\n",
    )
    .unwrap();
    let text = "duration: 0.5\ndt: 0.01\nribbon:\n  segments: 10\n  base: {mode: floating, position: [-0.5, 0, 0.3]}\ncolliders:\n  - {name: table, kind: mesh, file: meshes/table.obj, friction: 0.5}\ncontact: {thickness: 0.002}\n";
    let path = dir.join("scene.yaml");
    std::fs::write(&path, text).unwrap();
    let mut s = scene::load(&path, &[]).unwrap();
    let steps = (s.duration / s.world.dt()).round() as usize;
    for _ in 0..steps {
        let r = s.world.step(&[]);
        assert!(r.contact.unwrap().report.resolved);
    }
    // resting on the mesh: between h/2 and h/2 + ŝ (the barrier's reach, h/10) above
    // its surface, not fallen through
    let zmin = lowest_z(s.world.mesh(0));
    assert!(
        zmin > 0.051 && zmin < 0.051 + 0.0002,
        "lowest vertex at {zmin} m, the mesh is at 0.05 m"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn collider_and_contact_errors_name_the_key() {
    check(
        &format!("{ONE}colliders:\n  - {{kind: cone}}\n"),
        &["`colliders.0.kind`", "plane, box, sphere, capsule, mesh"],
    );
    check(
        &format!("{ONE}colliders:\n  - {{kind: box}}\n"),
        &["`colliders.0.size`", "required"],
    );
    check(
        &format!("{ONE}colliders:\n  - {{kind: box, size: [1, 0, 1]}}\n"),
        &["`colliders.0.size.1`", "> 0"],
    );
    check(
        &format!("{ONE}colliders:\n  - {{kind: sphere, radius: 0.1, size: [1, 1, 1]}}\n"),
        &["`colliders.0.size`", "not used"],
    );
    check(
        &format!("{ONE}colliders:\n  - {{kind: capsule, radius: 0.1}}\n"),
        &["`colliders.0.length`", "required"],
    );
    check(
        &format!("{ONE}colliders:\n  - {{kind: plane, friction: -1}}\n"),
        &["`colliders.0.friction`", ">= 0"],
    );
    check(
        &format!("{ONE}colliders:\n  - {{kind: plane, handle: nobody}}\n"),
        &["`colliders.0.handle`", "no handle named `nobody`"],
    );
    check(
        &format!("{ONE}colliders:\n  - {{kind: mesh, file: missing.obj}}\n"),
        &["`colliders.0.file`", "missing.obj"],
    );
    check(
        &format!("{ONE}colliders:\n  - {{kind: plane, colour: red}}\n"),
        &["unknown field `colour`"],
    );
    check(
        &format!("{ONE}colliders:\n  - {{name: g, kind: plane}}\n  - {{name: g, kind: plane}}\n"),
        &["`colliders.1.name`", "duplicate"],
    );
    check(
        &format!("{ONE}contact: {{thickness: 0}}\n"),
        &["`contact.thickness`", "> 0"],
    );
    check(
        &format!("{ONE}contact: {{closeness: soft}}\n"),
        &["`contact.closeness`", "stiff, plain"],
    );
    check(
        &format!("{ONE}contact: {{max_iterations: 0}}\n"),
        &["`contact.max_iterations`", "at least 1"],
    );
    check(
        &format!("{ONE}contact: {{method: penalty}}\n"),
        &["`contact.method`", "barrier, projection"],
    );
    check(
        &format!("{ONE}contact: {{thickness: 0.002, activation_distance: 0.002}}\n"),
        &["`contact.activation_distance`", "pi/2 - 1"],
    );
    check(
        &format!("{ONE}contact: {{barrier_pressure: 0}}\n"),
        &["`contact.barrier_pressure`", "> 0"],
    );
    check(
        &format!("{ONE}contact: {{friction_velocity: -1}}\n"),
        &["`contact.friction_velocity`", "> 0"],
    );
    check(
        &format!("{ONE}contact: {{ribbon_friction: -0.1}}\n"),
        &["`contact.ribbon_friction`", ">= 0"],
    );
    check(
        &format!("{ONE}contact: {{method: projection, ribbon_friction: 0.3}}\n"),
        &["`contact.ribbon_friction`", "barrier"],
    );
    check(
        &format!("{ONE}solver: {{kind: lbfgsb}}\ncontact: {{}}\n"),
        &["`solver.kind`", "Newton solver", "projection"],
    );
    // a ribbon starting inside a solid
    check(
        &format!("{ONE}colliders:\n  - {{kind: sphere, radius: 0.1, position: [0.5, 0, 0.2]}}\n"),
        &["`colliders.0`", "starts inside"],
    );
}

#[test]
fn ribbons_list_errors_name_the_key() {
    let two = "duration: 0.05\ndt: 0.01\nribbons:\n  - {name: a, segments: 10}\n  - {name: b, segments: 10, base: {position: [0, 0.5, 0]}}\n";
    assert!(scene::load_str(two, Path::new("two.yaml"), &[]).is_ok());
    check(
        &format!("{ONE}ribbons:\n  - {{name: a}}\n"),
        &["`ribbons`", "not both"],
    );
    check(
        "duration: 0.05\ndt: 0.01\nribbons:\n  - {segments: 10}\n",
        &["`ribbons.0.name`", "needs a name"],
    );
    check(
        "duration: 0.05\ndt: 0.01\nribbons:\n  - {name: a}\n  - {name: a, base: {position: [0, 1, 0]}}\n",
        &["`ribbons.1.name`", "duplicate"],
    );
    check(
        "duration: 0.05\ndt: 0.01\nribbon:\n  name: tape\n",
        &["`ribbon.name`"],
    );
    check(
        &format!("{two}handles:\n  - {{name: h, point: [0.5, 0]}}\n"),
        &["`handles.0.object`", "several objects"],
    );
    check(
        &format!("{two}handles:\n  - {{name: h, object: c, point: [0.5, 0]}}\n"),
        &["`handles.0.object`", "no object named `c`"],
    );
    check(
        "duration: 0.05\ndt: 0.01\nribbons:\n  - {name: a, segments: 10, width: 2}\n",
        &["`ribbons.0.width`"],
    );
    // ribbons starting on top of each other
    check(
        "duration: 0.05\ndt: 0.01\nribbons:\n  - {name: a, segments: 10}\n  - {name: b, segments: 10}\ncontact: {}\n",
        &["`contact`", "overlapping", "ribbon `a`", "ribbon `b`"],
    );
    check(
        "duration: 0.05\ndt: 0.01\nribbon:\n  segments: 4\n  initial_shape: {kind: explicit, crease_directions: [0, 0], bending_angles: [0, 0, 0]}\n",
        &["`ribbon.initial_shape.crease_directions`", "expected n - 1 = 3"],
    );
    check(
        "duration: 0.05\ndt: 0.01\nribbon:\n  segments: 4\n  initial_shape: {kind: helix, bending_angles: [0, 0, 0]}\n",
        &["`ribbon.initial_shape.bending_angles`", "only used with kind: explicit"],
    );
}
