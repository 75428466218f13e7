//! A robot's links as kinematic colliders: the world's kinematic bodies (their poses
//! set from outside each step) against the handle-carried colliders they generalize,
//! their refusals, and the session's robot commands (a description that arrives, the
//! links' TF lookups) applied, recorded and replayed bit for bit.

mod common;

use developable_sim::contact::{Collider, ColliderShape};
use developable_sim::geometry::{Pose, Vector3};
use developable_sim::record::bag::BagOptions;
use developable_sim::record::recorder::SessionRecorder;
use developable_sim::record::replay::{replay, ReplayOptions};
use developable_sim::scene::urdf::load_for;
use developable_sim::session::input::InputPolicy;
use developable_sim::session::names::NodeNames;
use developable_sim::session::{Applied, Command, Content, OutputTable, RunOutputs, Session};
use developable_sim::wire::msgs::{Header, Time, Transform, TransformStamped};

fn finger_box() -> Collider {
    Collider {
        shape: ColliderShape::Cuboid {
            half_extents: Vector3::new(0.02, 0.01, 0.03),
        },
        pose: Pose::identity(),
        friction: 0.5,
        attached_to: Some(0),
    }
}

/// The gripper-push scene's finger, once carried by its handle and once as a kinematic
/// body moved along the same poses from outside: the same contact sees the same motion,
/// so the ribbon must come out bit for bit the same (contact and friction included),
/// with either contact method.
#[test]
fn a_kinematic_body_moved_along_a_handles_path_pushes_as_the_handle_carried_collider() {
    for method in ["barrier", "projection"] {
        kinematic_pushes_as_carried(method);
    }
}

fn kinematic_pushes_as_carried(method: &str) {
    let with = format!("contact.method={method}");
    let mut carried = common::load("ribbon_gripper_push", &[&with]);
    let mut kinematic = common::load(
        "ribbon_gripper_push",
        &[
            "colliders=[{name: table, kind: plane, friction: 0.3}]",
            &with,
        ],
    );
    let w = &mut kinematic.world;
    let start = w.scripted_target(0, 0.0);
    w.set_kinematic_colliders(vec![finger_box()], vec![start])
        .unwrap();
    let colliders = |s: &developable_sim::scene::Scene| s.world.colliders().len();
    assert_eq!((colliders(&carried), colliders(&kinematic)), (2, 2));
    let mut contacts = 0;
    for _ in 0..60 {
        let t_next = kinematic.world.time() + kinematic.world.dt();
        let finger = kinematic.world.scripted_target(0, t_next);
        kinematic.world.set_kinematic_pose(0, finger);
        let a = carried.world.step(&[]);
        let b = kinematic.world.step(&[]);
        assert_eq!(a.contact, b.contact, "step {}", a.time);
        contacts += a.contact.unwrap().report.contacts;
        assert_eq!(kinematic.world.kinematic_poses(), [finger]);
        let (ma, mb) = (carried.world.mesh(0), kinematic.world.mesh(0));
        for (p, q) in ma.vertices.iter().zip(&mb.vertices) {
            for k in 0..3 {
                assert_eq!(p[k].to_bits(), q[k].to_bits(), "t = {}", a.time);
            }
        }
    }
    // the finger reaches the ribbon in these 0.6 s: the comparison covers contact
    assert!(contacts > 0, "{method}: no contact in the compared steps");
}

/// With contact inside the step a link cannot arrive through the ribbon (the barrier
/// cannot start from an overlap): refused, the world unchanged; the projection takes it
/// (it pushes the ribbon out after the next step).
#[test]
fn a_kinematic_collider_through_the_ribbon_is_refused_by_the_barrier() {
    let inside = Pose::translation(0.1, 0.0, 0.0);
    let mut barrier = common::load("ribbon_gripper_push", &["contact.method=barrier"]);
    let e = barrier
        .world
        .set_kinematic_colliders(vec![finger_box()], vec![inside])
        .unwrap_err();
    assert!(
        e.to_string().contains("cannot start from an overlap"),
        "{e}"
    );
    assert_eq!(barrier.world.colliders().len(), 2);
    assert!(barrier.world.kinematic_poses().is_empty());
    barrier.world.step(&[]);
    let mut projection = common::load("ribbon_gripper_push", &["contact.method=projection"]);
    projection
        .world
        .set_kinematic_colliders(vec![finger_box()], vec![inside])
        .unwrap();
    assert_eq!(projection.world.colliders().len(), 3);
}

#[test]
fn kinematic_colliders_refuse_what_they_cannot_place() {
    let mut no_stage = common::load("ribbon_extreme_torsion", &[]);
    let e = no_stage
        .world
        .set_kinematic_colliders(vec![finger_box()], vec![Pose::identity()])
        .unwrap_err();
    assert!(e.to_string().contains("need a contact stage"), "{e}");
    let mut s = common::load("ribbon_gripper_push", &[]);
    let w = &mut s.world;
    let mut on_nothing = finger_box();
    on_nothing.attached_to = None;
    for (c, poses) in [
        (on_nothing, vec![Pose::identity()]),
        (finger_box(), vec![]),
        (finger_box(), vec![Pose::translation(f64::NAN, 0.0, 0.0)]),
    ] {
        assert!(w.set_kinematic_colliders(vec![c], poses).is_err());
    }
    // refused: the world is as it was
    assert_eq!(w.colliders().len(), 2);
    assert!(w.kinematic_poses().is_empty());
    // a body's next pose that is not finite is ignored: it stays; a reset keeps it
    let at = Pose::translation(0.3, 0.2, 0.5);
    w.set_kinematic_colliders(vec![finger_box()], vec![at])
        .unwrap();
    w.set_kinematic_pose(0, Pose::translation(f64::INFINITY, 0.0, 0.0));
    w.set_kinematic_pose(7, Pose::identity()); // no such body: nothing happens
    w.step(&[]);
    assert_eq!(w.kinematic_poses(), [at]);
    let handles = w.handles().len();
    assert_eq!(w.current_targets()[handles], at);
    w.reset();
    assert_eq!(w.kinematic_poses(), [at]);
    assert_eq!(w.colliders().len(), 3);
}

/// A one-link robot: a 0.3 x 0.04 x 0.04 m box centred 0.15 m along the link's x.
const ARM: &str = r#"<robot name="stick">
  <link name="base"/>
  <link name="stick">
    <collision><origin xyz="0.15 0 0"/><geometry><box size="0.3 0.04 0.04"/></geometry></collision>
  </link>
</robot>"#;

/// A lookup that found `frame` at (x, y, z), m, turned by 90 degrees about z (its x
/// axis along the world's y).
fn found(frame: &str, x: f64, y: f64, z: f64, at_ns: i64) -> TransformStamped {
    let h = std::f64::consts::FRAC_PI_4;
    TransformStamped {
        header: Header {
            stamp: Time::from_nanos(at_ns),
            frame_id: "world".into(),
        },
        child_frame_id: frame.into(),
        transform: Transform {
            translation: developable_sim::wire::msgs::Vector3 { x, y, z },
            rotation: developable_sim::wire::msgs::Quaternion {
                z: h.sin(),
                w: h.cos(),
                ..Default::default()
            },
        },
    }
}

fn failed(frame: &str, at_ns: i64) -> TransformStamped {
    let mut t = found(frame, 0.0, 0.0, 0.0, at_ns);
    t.header.frame_id.clear();
    t
}

/// A session of the hanging-ribbon scene, recording into `bag`.
fn recorded_session(bag: &std::path::Path) -> (Session, SessionRecorder) {
    let scene = common::load("ribbon_robot_arm", &[]);
    let names = NodeNames::resolve(&scene, "developable_sim", "/", &[]).unwrap();
    assert_eq!(names.robot_description, "/robot_description");
    let run = RunOutputs {
        own_clock: true,
        recording: true,
        record_cameras: false,
    };
    let table = OutputTable::for_scene(&scene, &names, run).unwrap();
    assert!(table.rows.iter().any(|r| r.kind.name == "colliders"));
    let policy = InputPolicy {
        frame_id: "world".into(),
        accept_empty_frame_id: false,
        max_stamp_lead: 10.0,
    };
    let mut session = Session::new(scene, policy, names.handles.clone(), table);
    let mut recorder =
        SessionRecorder::create(bag, BagOptions::default(), &session, &names).unwrap();
    recorder
        .record_frame(&session.frame(Content::All).unwrap())
        .unwrap();
    (session, recorder)
}

/// Record, apply and record the frame of one command, as the node does.
fn run(session: &mut Session, recorder: &mut SessionRecorder, command: Command) -> Applied {
    recorder.record_command(&command, session.stamp()).unwrap();
    let applied = session.apply(&command);
    if let Some(frame) = session.frame_after(&applied) {
        recorder.record_frame(&frame.unwrap()).unwrap();
    }
    applied
}

fn description(session: &Session, recorder: &mut SessionRecorder, urdf: &str) -> Command {
    Command::RobotDescription {
        urdf: urdf.into(),
        loaded: load_for(&session.scene, urdf),
        arrival_ns: recorder.arrival_ns(),
    }
}

#[test]
fn robot_commands_move_links_through_the_ribbon_and_replay_bit_for_bit() {
    let bag = common::scratch("robot").join("bag");
    let (mut s, mut rec) = recorded_session(&bag);
    let colliders = |s: &Session| s.scene.world.colliders().len();
    assert_eq!(colliders(&s), 0);
    let d = description(&s, &mut rec, ARM);
    assert_eq!(run(&mut s, &mut rec, d), Applied::Robot(Ok(())));
    assert_eq!(s.robot().description().unwrap().links.len(), 1);
    // the link's frame is not in TF yet: not in the world
    let lookups = |rec: &mut SessionRecorder, t: TransformStamped| Command::LinkPoses {
        transforms: vec![t],
        arrival_ns: rec.arrival_ns(),
    };
    for k in 0..3 {
        let c = lookups(&mut rec, failed("stick", k));
        assert_eq!(run(&mut s, &mut rec, c), Applied::Robot(Ok(())));
        run(&mut s, &mut rec, Command::Step);
    }
    assert_eq!(colliders(&s), 0);
    // the stick, along y from y0 (its box across the ribbon's width, y in [-0.15,
    // 0.15]), sweeps along -x through the ribbon's plane x = 0, 0.25 m below the clamp
    let (y0, z) = (-0.15, 0.75);
    let mut pushed: f64 = 0.0;
    for k in 0..120 {
        let x = 0.1 - 0.002 * f64::from(k);
        let t = if k == 40 {
            failed("stick", 0) // one failed lookup: the stick stays for a step
        } else {
            found("stick", x, y0, z, 0)
        };
        let c = lookups(&mut rec, t);
        run(&mut s, &mut rec, c);
        run(&mut s, &mut rec, Command::Step);
        let stick = s.scene.world.kinematic_poses()[0];
        if k != 40 {
            assert_eq!(stick.translation.vector, Vector3::new(x, y0, z));
        } else {
            assert_eq!(stick.translation.vector.x, 0.1 - 0.002 * 39.0);
        }
        let at = stick.translation.vector.x;
        let mesh = s.scene.world.mesh(0);
        for v in &mesh.vertices {
            pushed = pushed.max(-v.x);
            // the box spans x in [at - 0.02, at + 0.02] at the ribbon (|y| <= 0.02):
            // no vertex of the ribbon between its faces at its height
            let inside = (v.x - at).abs() < 0.02 && (v.z - z).abs() < 0.02 && v.y.abs() < 0.15;
            assert!(
                !inside,
                "step {k}: ribbon vertex {v} inside the stick at x = {at}"
            );
        }
    }
    assert_eq!(colliders(&s), 1);
    assert!(pushed > 0.1, "the ribbon was pushed {pushed} m in -x only");
    // a new description: the same link keeps its place, a new one waits for TF
    let two = ARM.replace(
        "</robot>",
        r#"<link name="ball"><collision><geometry><sphere radius="0.02"/></geometry></collision></link></robot>"#,
    );
    let before = s.scene.world.kinematic_poses()[0];
    let d = description(&s, &mut rec, &two);
    run(&mut s, &mut rec, d);
    assert_eq!(s.robot().links_in_world(), ["stick"]);
    assert_eq!(s.scene.world.kinematic_poses(), [before]);
    let c = Command::LinkPoses {
        transforms: vec![failed("stick", 0), found("ball", 0.5, 0.5, 0.5, 0)],
        arrival_ns: rec.arrival_ns(),
    };
    run(&mut s, &mut rec, c);
    assert_eq!(s.robot().links_in_world(), ["stick", "ball"]);
    assert_eq!(colliders(&s), 2);
    run(&mut s, &mut rec, Command::Step);
    // not a URDF: refused, the robot stays; a robot without the stick: it leaves
    let d = description(&s, &mut rec, "<robot name='x'>");
    assert!(matches!(run(&mut s, &mut rec, d), Applied::Robot(Err(_))));
    assert_eq!(colliders(&s), 2);
    let ball_only = two.replace(
        r#"<link name="stick">
    <collision><origin xyz="0.15 0 0"/><geometry><box size="0.3 0.04 0.04"/></geometry></collision>
  </link>"#,
        "",
    );
    let d = description(&s, &mut rec, &ball_only);
    run(&mut s, &mut rec, d);
    assert_eq!(s.robot().links_in_world(), ["ball"]);
    run(&mut s, &mut rec, Command::Step);
    rec.close().unwrap();

    let r = replay(&bag, &ReplayOptions::default()).unwrap();
    assert!(r.identical, "{r:#?}");
    assert_eq!(r.steps, 3 + 120 + 2);
    let colliders_topic = r.topics.iter().find(|t| t.topic == "/colliders").unwrap();
    assert_eq!(colliders_topic.compared, 1 + 125);
}

#[test]
fn a_bad_robot_colliders_section_names_its_key() {
    let load = |name: &str, set: &str| {
        developable_sim::scene::load(&common::scene_path(name), &[set.to_string()])
            .unwrap_err()
            .to_string()
    };
    for (set, says) in [
        (
            "robot_colliders.thickness=-0.001",
            "`robot_colliders.thickness`: must be >= 0",
        ),
        (
            "robot_colliders.friction=.nan",
            "`robot_colliders.friction`: must be a finite number",
        ),
        (
            "robot_colliders.links=[]",
            "`robot_colliders.links`: an empty list takes no link",
        ),
        (
            "robot_colliders.topic=' '",
            "`robot_colliders.topic`: must not be empty",
        ),
        ("robot_colliders.frames=x", "unknown field `frames`"),
    ] {
        let e = load("ribbon_robot_arm", set);
        assert!(e.contains(says), "{set}: {e}");
    }
    let e = load("paper_crumple", "robot_colliders={}");
    assert!(
        e.contains("`robot_colliders`: a robot's links collide with ribbons"),
        "{e}"
    );
    // the defaults
    let s = common::load("ribbon_robot_arm", &["robot_colliders={}"]);
    let r = s.robot.unwrap();
    assert_eq!(
        (
            r.topic.as_str(),
            r.links,
            r.thickness,
            r.friction,
            r.frame_prefix.as_str()
        ),
        ("/robot_description", None, 0.0, 0.5, "")
    );
}
