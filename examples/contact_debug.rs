use developable_sim::scene;
use std::path::Path;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut sc = scene::load(Path::new(&args[1]), &args[2..]).unwrap();
    let steps = (sc.duration / sc.world.dt()).round() as usize;
    for s in 0..steps {
        let t = std::time::Instant::now();
        let r = sc.world.step(&[]);
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let c = r.contact.unwrap_or_default();
        let iso: f64 = r
            .objects
            .iter()
            .map(|o| o.isometry_error)
            .fold(0.0, f64::max);
        let zmin = (0..sc.world.objects().len())
            .flat_map(|o| {
                sc.world
                    .mesh(o)
                    .vertices
                    .iter()
                    .map(|v| v.z)
                    .collect::<Vec<_>>()
            })
            .fold(f64::INFINITY, f64::min);
        println!("step {s}: {ms:.1} ms (contact {:.1}) its {} iso {iso:.2e} zmin {zmin:.4} | contacts {} cons {} rounds {} qp {} pen {:.1e} pred {:.1e} corr {:.1e} res {}",
          0.0, r.objects.iter().map(|o| o.iterations).sum::<u32>(), c.report.contacts, c.report.constraints, c.report.iterations, c.report.qp_iterations, c.report.penetration_max, c.report.predicted_penetration_max, c.report.correction_max, c.report.resolved);
    }
}
