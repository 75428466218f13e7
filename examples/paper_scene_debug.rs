use developable_sim::paper::PaperSim;
use developable_sim::scene;
use std::path::Path;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let sets: Vec<String> = args[2..].to_vec();
    let mut sc = scene::load(Path::new(&args[1]), &sets).unwrap();
    let steps = (sc.duration / sc.world.dt()).round() as usize;
    for k in 1..=steps {
        if std::env::var("DUMP").is_ok() && k % 10 == 1 {
            final_dump(&sc);
        }
        let r = sc.world.step(&[]);
        let p = sc.world.object_as::<PaperSim>(0).expect("a paper scene");
        let f = p.frame_stats();
        let m = p.mesh();
        let mut worst = (0.0, 0u32, 0u32);
        for [a, b] in m.edges() {
            let rest = (m.material[a as usize] - m.material[b as usize]).norm();
            let len = (m.vertices[a as usize] - m.vertices[b as usize]).norm();
            let e = (len - rest).abs() / rest;
            if e > worst.0 {
                worst = (e, a, b);
            }
        }
        let o = &r.objects[0];
        println!("step {k} t={:.3}: energy {:.4e} (kinetic {:.2e}) work {:.3e} newton {} conv {} iso_err {:.3} (edge {}-{} m {:?}-{:?} rest {:.4}) comp {:.3}% ({:.1}%) tris {} regions {} sing {} events {} junc {:?} cones {:?} iso_it {} lenerr {:.2e}->{:.2e}",
            r.time, o.energies.total(), o.energies.kinetic, o.work_bound, o.iterations, o.converged, o.isometry_error, worst.1, worst.2, m.material[worst.1 as usize], m.material[worst.2 as usize],
            (m.material[worst.1 as usize]-m.material[worst.2 as usize]).norm(),
            f.edges.compression_mean_pct, f.edges.compressed_edges_pct, f.triangles, f.curved_regions, o.singular_points, f.crumple_events.len(), f.junctions, f.cones, f.isometry.iterations, f.isometry.length_error_before, f.isometry.length_error_after);
        for a in &f.crumple_attempts {
            println!(
                "    attempt comp {:.4} (start {:.4}, membrane {:.4}) at ({:.3},{:.3}) dir ({:.2},{:.2}) changed {} ({:?}) held {} corners {:?} borders {:?} dihedral {:?}",
                a.compression,
                a.compression_at_start,
                a.membrane,
                a.centroid.x,
                a.centroid.y,
                a.ruling_direction.x,
                a.ruling_direction.y,
                a.changed,
                a.unchanged,
                a.touches_held,
                a.corners.map(|c| [(c.x * 1e4).round() / 1e4, (c.y * 1e4).round() / 1e4]),
                a.borders,
                a.border_dihedral
            );
        }
        for e in &f.crumple_events {
            println!("    {e:?}");
        }
    }
}

#[allow(dead_code)]
fn final_dump(sc: &developable_sim::scene::Scene) {
    let p = sc.world.object_as::<PaperSim>(0).expect("a paper scene");
    println!("creases {:?}", p.geometric_layer().creases);
    let layer = p.geometric_layer();
    for r in &layer.regions {
        let rs: Vec<String> = r
            .rulings
            .iter()
            .map(|ru| {
                let a = layer.endpoint_material(p.pattern(), &ru.a);
                let b = layer.endpoint_material(p.pattern(), &ru.b);
                format!("({:.4},{:.4})-({:.4},{:.4})", a.x, a.y, b.x, b.y)
            })
            .collect();
        println!("region {}: {}", r.id, rs.join(" "));
    }
    let sp = p.physical_mesh();
    for h in &sp.hinges {
        let (a, b) = (sp.material[h.v[0] as usize], sp.material[h.v[1] as usize]);
        if (a.x - 0.05).abs() < 1e-3 && (b.x - 0.05).abs() < 1e-3 {
            println!("hinge {:?} {:?} rest {}", a, b, h.rest_angle);
        }
    }
}
