use developable_sim::geometry::{Point2, Pose, Vector3};
use developable_sim::paper::compression::triangle_strain;
use developable_sim::paper::geometric::{GVertexKind, GeometricMesh};
use developable_sim::paper::physical::Interpolator;
use developable_sim::paper::{PaperParams, PaperSim};
use developable_sim::sim::{HandleSpec, Motion, OrientationMode, Trajectory};

fn main() {
    let squeeze: f64 = std::env::var("SQUEEZE")
        .map(|v| v.parse().unwrap())
        .unwrap_or(0.0059);
    let tilt = 0.6;
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
    let mut params = PaperParams::default();
    if let Ok(v) = std::env::var("RHO_INT") {
        params.interior_density = v.parse().unwrap();
    }
    let squeeze: f64 = std::env::var("SQUEEZE")
        .map(|v| v.parse().unwrap())
        .unwrap_or(0.0059);
    let _ = squeeze;
    let mut sim = PaperSim::new(params, &handles, 0).unwrap();
    let dt = 1.0 / 30.0;
    let t = dt;
    let targets: Vec<Pose> = handles.iter().map(|h| h.trajectory.pose_at(t)).collect();
    let r = sim.simulate(dt, t, &handles, &targets);
    println!("{r:?}");
    let sp = sim.physical_mesh();
    for (i, (m, p)) in sp.material.iter().zip(&sp.position).enumerate() {
        if (m.x - 0.05).abs() < 0.02 || i < 6 {
            println!(
                "v{i} m=({:.4},{:.4}) p=({:.5},{:.5},{:.5})",
                m.x, m.y, p.x, p.y, p.z
            );
        }
    }
    let pattern = sim.pattern().clone();
    let interp = Interpolator::new(sp, &pattern);
    let pos = |_: &GVertexKind, m: &Point2| interp.position(m);
    let g = GeometricMesh::build(sim.geometric_layer(), &pattern, &pos).unwrap();
    for f in 0..g.faces.len() {
        println!(
            "face {:?} strain {:?}",
            g.faces[f].vertices,
            triangle_strain(&g, f)
        );
    }
}
