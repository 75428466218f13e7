use developable_sim::geometry::{Point2, Pose, Vector3};
use developable_sim::paper::{PaperParams, PaperSim};
use developable_sim::sim::{HandleSpec, Motion, OrientationMode, Trajectory};

fn main() {
    let squeeze: f64 = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(0.01);
    let tilt: f64 = std::env::args()
        .nth(2)
        .map(|s| s.parse().unwrap())
        .unwrap_or(0.6);
    let steps: usize = std::env::args()
        .nth(3)
        .map(|s| s.parse().unwrap())
        .unwrap_or(15);
    let mk = |name: &str, u: f64, sign: f64| HandleSpec {
        name: name.into(),
        object: 0,
        material_point: Point2::new(u, 0.05),
        position_axes: [true; 3],
        orientation: OrientationMode::Full,
        trajectory: Trajectory {
            initial: Pose::translation(u, 0.05, 0.0),
            motions: vec![Motion {
                start: 0.0,
                end: 1.0,
                translation: Vector3::new(sign * squeeze / 2.0, 0.0, 0.0),
                axis: Vector3::y(),
                angle: -sign * tilt,
            }],
        },
    };
    let handles = vec![mk("left", 0.0, 1.0), mk("right", 0.1, -1.0)];
    let mut sim = PaperSim::new(PaperParams::default(), &handles, 0).unwrap();
    let dt = 1.0 / 30.0;
    for k in 1..=steps {
        let t = k as f64 * dt;
        let targets: Vec<Pose> = handles.iter().map(|h| h.trajectory.pose_at(t)).collect();
        let r = sim.step(dt, t, 0, &handles, &targets);
        let f = sim.frame_stats();
        println!("step {k}: newton {} conv {} viol {:.2e} iso_err {:.3} comp {:.3}% ({:.1}%) tris {} Gflat {} regions {} sing {}",
            r.iterations, r.converged, r.constraint_violation, r.isometry_error, f.compression_mean_pct, f.compressed_edges_pct, f.triangles, f.geometric_triangles, f.curved_regions, r.singular_points);
        for e in &f.crumple_events {
            println!("   event {e:?}");
        }
        println!(
            "   junctions {:?} cones {:?} iso {:?}",
            f.junctions, f.cones, f.isometry
        );
        for reg in &sim.geometric_layer().regions {
            println!(
                "   region {} rulings {:?}",
                reg.id,
                reg.rulings
                    .iter()
                    .map(|r| (
                        sim.geometric_layer().endpoint_material(sim.pattern(), &r.a),
                        sim.geometric_layer().endpoint_material(sim.pattern(), &r.b)
                    ))
                    .map(|(a, b)| format!("({:.3},{:.3})-({:.3},{:.3})", a.x, a.y, b.x, b.y))
                    .collect::<Vec<_>>()
            );
        }
        for c in &sim.geometric_layer().creases {
            println!("   crease {c:?}");
        }
    }
}
