//! The `developable_sim` command line: run scenes headless (more subcommands join as
//! the node, recording and reports land).

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::Context;
use clap::{Parser, Subcommand};

use developable_sim::{runner, scene};

#[derive(Parser)]
#[command(
    name = "developable_sim",
    version,
    about = "Developable ribbons and paper for robot manipulation (Pan et al., Schreck et al.)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene headless and print a summary.
    Run {
        /// Scene file (YAML), e.g. config/scenes/ribbon_extreme_torsion.yaml.
        scene: PathBuf,
        /// Simulated duration, s (overrides the scene's `duration`).
        #[arg(long)]
        duration: Option<f64>,
        /// Time step, s (overrides the scene's `dt`).
        #[arg(long)]
        dt: Option<f64>,
        /// Override a scene key: --set ribbon.segments=200 (value parsed as YAML).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// Write run statistics as JSON.
        #[arg(long, value_name = "OUT.json")]
        stats: Option<PathBuf>,
    },
    /// Run a scene headless to a time and render its meshes to a PNG.
    Render {
        /// Scene file (YAML).
        scene: PathBuf,
        /// Output PNG.
        #[arg(long, value_name = "OUT.png")]
        out: PathBuf,
        /// Simulated time of the picture, s (default: the scene's duration).
        #[arg(long)]
        time: Option<f64>,
        /// Override a scene key (as for `run`).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// View direction (world, towards the scene).
        #[arg(long, value_delimiter = ',', default_value = "-1,-2,-1.2")]
        view: Vec<f64>,
        /// Picture size in pixels, WIDTHxHEIGHT.
        #[arg(long, default_value = "960x540")]
        size: String,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match real_main(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

fn real_main(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Run {
            scene,
            duration,
            dt,
            sets,
            stats,
        } => {
            let mut overrides = Vec::new();
            if let Some(d) = duration {
                overrides.push(format!("duration={d}"));
            }
            if let Some(d) = dt {
                overrides.push(format!("dt={d}"));
            }
            overrides.extend(sets);
            let mut loaded = scene::load(&scene, &overrides)?;
            let stop = Arc::new(AtomicBool::new(false));
            let run_stats = runner::run(&mut loaded, &mut (), &|| stop.load(Ordering::Relaxed))?;
            println!(
                "{}: {} steps of {} s, median step {:.3} ms (p95 {:.3}), solver {} median {} iterations, {} unconverged, isometry error max {:.2e}, constraint violation max {:.2e} m, singular points max {}, finite: {}",
                run_stats.scene,
                run_stats.steps,
                run_stats.dt,
                run_stats.step_ms.median,
                run_stats.step_ms.p95,
                run_stats.solver.kind,
                run_stats.solver.iterations_median,
                run_stats.solver.unconverged_steps,
                run_stats.isometry_error_max,
                run_stats.constraint_violation_max,
                run_stats.singular_points_max,
                run_stats.finite
            );
            if let Some(c) = &run_stats.contact {
                println!(
                    "contact: median {:.3} ms per step, penetration max {:.2e} m, contacts max {}, rounds max {}, {} unresolved steps, developability error (|X - X~|) max {:.2e} m",
                    run_stats.contact_ms.median,
                    run_stats.penetration_max,
                    c.contacts_max,
                    c.iterations_max,
                    c.unresolved_steps,
                    c.correction_max
                );
            }
            if let Some(path) = stats {
                let json = serde_json::to_string_pretty(&run_stats)?;
                std::fs::write(&path, json)
                    .with_context(|| format!("writing stats to {}", path.display()))?;
            }
            Ok(())
        }
        Command::Render {
            scene,
            out,
            time,
            sets,
            view,
            size,
        } => {
            let mut overrides = sets;
            if let Some(t) = time {
                overrides.push(format!("duration={t}"));
            }
            let mut loaded = scene::load(&scene, &overrides)?;
            runner::run(&mut loaded, &mut (), &|| false)?;
            let (w, h) = size
                .split_once('x')
                .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)))
                .ok_or_else(|| anyhow::anyhow!("--size must be WIDTHxHEIGHT, got `{size}`"))?;
            anyhow::ensure!(
                view.len() == 3 && view.iter().all(|v| v.is_finite()),
                "--view takes three numbers x,y,z"
            );
            let meshes: Vec<_> = (0..loaded.world.object_names().len())
                .map(|i| loaded.world.mesh(i))
                .collect();
            let dir = nalgebra::Vector3::new(view[0], view[1], view[2]);
            anyhow::ensure!(dir.norm() > 0.0, "--view must not be zero");
            let up = if dir.normalize().z.abs() > 0.99 {
                nalgebra::Vector3::y()
            } else {
                nalgebra::Vector3::z()
            };
            developable_sim::render::render_png(&meshes, &out, w, h, dir, up)?;
            println!("wrote {}", out.display());
            Ok(())
        }
    }
}
