use developable_sim::geometry::{Point2, Pose, Vector3};
use developable_sim::paper::{PaperParams, PaperSim};
use developable_sim::sim::{HandleSpec, Motion, OrientationMode, Trajectory};
use std::time::Instant;

fn main() {
    let rho: f64 = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(1666.7);
    let squeeze = 0.0059;
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
    params.interior_density = rho;
    let mut sim = PaperSim::new(params, &handles, 0).unwrap();
    let dt = 1.0 / 30.0;
    let mut times = [0.0f64; 3];
    let n = 30;
    for k in 1..=n {
        let t = k as f64 * dt;
        let targets: Vec<Pose> = handles.iter().map(|h| h.trajectory.pose_at(t)).collect();
        let t0 = Instant::now();
        sim.simulate(dt, t, &handles, &targets);
        let t1 = Instant::now();
        sim.remesh();
        let t2 = Instant::now();
        sim.track();
        let t3 = Instant::now();
        times[0] += (t1 - t0).as_secs_f64() * 1e3;
        times[1] += (t2 - t1).as_secs_f64() * 1e3;
        times[2] += (t3 - t2).as_secs_f64() * 1e3;
    }
    let f = sim.frame_stats();
    println!(
        "rho {rho}: tris {} ms/frame sim {:.2} remesh {:.2} iso {:.2} sing {} comp {:.3}%",
        f.triangles,
        times[0] / n as f64,
        times[1] / n as f64,
        times[2] / n as f64,
        sim.singular_points().len(),
        f.compression_mean_pct
    );
}
