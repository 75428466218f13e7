//! The `developable_sim` command line: the ROS 2 node, headless runs, bags and replay.
//! Parsing and dispatch; the logic (the node's settings, the banner, the summaries) is
//! in `developable_sim::cli`, where it is unit-tested.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::{bail, Context};
use clap::{Parser, Subcommand};

use developable_sim::cli::args::{
    NodeArgs, RenderArgs, ReplayArgs, ReportArgs, RunArgs, StressArgs,
};
use developable_sim::cli::stop::{on_stop_signal, stop_message, StopAction, FORCED_EXIT_STATUS};
use developable_sim::cli::{bag_name, banner, node_launch, summary, CheckFailed, CliObserver};
use developable_sim::record::bag::{BagOptions, Compression};
use developable_sim::record::recorder::RunRecorder;
use developable_sim::record::{read, replay};
use developable_sim::ros::node::SimNode;
use developable_sim::session::params;
use developable_sim::sim::ReachWatch;
use developable_sim::{render, runner, scene};

#[derive(Parser)]
#[command(
    name = "developable_sim",
    version,
    about = "Developable ribbons and paper for robot manipulation (Pan et al., Schreck et al.)",
    after_help = "ROS arguments: `node` also accepts `--ros-args --params-file FILE -p NAME:=VALUE \
                  -r __ns:=/NS -r __node:=NAME -r FROM:=TO [--]`, as ROS 2 launch files pass them."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene headless and print a summary.
    Run(RunArgs),
    /// Run a scene headless to a time and render its meshes to a PNG.
    Render(RenderArgs),
    /// Run the ROS 2 node: handle poses in; markers, singular points, status, /clock out.
    Node(NodeArgs),
    /// Re-simulate a bag from its recorded handle poses and compare every output.
    Replay(ReplayArgs),
    /// Bag tools.
    Bag {
        #[command(subcommand)]
        command: BagCommand,
    },
    /// Same as `bag reindex`.
    Reindex { bag: PathBuf },
    /// Error against run time: sweep dt, resolution, tolerance and methods per scene,
    /// compare with a converged reference; writes report.csv, <scene>.png, summary.md.
    Report(ReportArgs),
    /// Stiff and extreme cases over time steps 0.001-0.1 s: a pass/fail table in
    /// OUT/stress.md and OUT/stress.json; exits non-zero if any run fails.
    Stress(StressArgs),
}

#[derive(Subcommand)]
enum BagCommand {
    /// Rebuild metadata.yaml from the MCAP file(s), repairing a file cut short by a
    /// crash (the original is kept as <file>.incomplete).
    Reindex { bag: PathBuf },
    /// Print topics and message counts (streaming; works on a truncated file).
    Info { bag: PathBuf },
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    let (own, ros) = match params::split_ros_args(&args[1..]) {
        Ok(x) => x,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let cli = Cli::parse_from(std::iter::once(args[0].clone()).chain(own));
    match real_main(cli, ros) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.downcast_ref::<CheckFailed>().is_some() => {
            eprintln!("{e}");
            ExitCode::from(1)
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

fn print(lines: Vec<String>) {
    for l in lines {
        println!("{l}");
    }
}

fn write_json(path: &Path, value: &impl serde::Serialize, what: &str) -> anyhow::Result<()> {
    std::fs::write(path, serde_json::to_string_pretty(value)?)
        .with_context(|| format!("writing {what}{}", path.display()))
}

fn real_main(cli: Cli, ros: params::RosArgs) -> anyhow::Result<()> {
    let non_node = !matches!(cli.command, Command::Node(_));
    if non_node && ros != params::RosArgs::default() {
        bail!("--ros-args only apply to `developable_sim node`");
    }
    match cli.command {
        Command::Run(a) => run_command(a),
        Command::Node(a) => node_command(a, ros),
        Command::Render(a) => render_command(a),
        Command::Replay(a) => {
            let options = replay::ReplayOptions { scene: a.scene };
            let report = replay::replay(&a.bag, &options)?;
            print(summary::replay_summary(&report));
            if let Some(path) = a.stats {
                write_json(&path, &report, "")?;
            }
            if !report.identical {
                let why = if report.topics.iter().all(|t| t.compared == 0) {
                    "no recorded output could be compared"
                } else {
                    "the outputs differ from the recording"
                };
                return Err(CheckFailed(format!("replay of {}: {why}", report.bag)).into());
            }
            Ok(())
        }
        Command::Bag {
            command: BagCommand::Reindex { bag },
        }
        | Command::Reindex { bag } => {
            print(summary::reindex_summary(&bag, &read::reindex(&bag)?));
            Ok(())
        }
        Command::Bag {
            command: BagCommand::Info { bag },
        } => {
            for file in read::mcap_files(&bag)? {
                print(summary::scan_summary(&file, &read::scan(&file)?));
            }
            Ok(())
        }
        Command::Report(a) => report_command(a),
        Command::Stress(a) => {
            let options = (&a).into();
            let report = developable_sim::stress::run_suite(&a.config, &a.out, &options)?;
            println!(
                "{} of {} runs passed in {:.1} s; table in {}",
                report.passed,
                report.results.len(),
                report.wall_s,
                a.out.join("stress.md").display()
            );
            if report.failed > 0 {
                bail!("{} stress run(s) failed", report.failed);
            }
            Ok(())
        }
    }
}

fn render_command(a: RenderArgs) -> anyhow::Result<()> {
    let mut loaded = scene::load(&a.scene, &a.scene_overrides())?;
    runner::run(&mut loaded, &mut (), &|| false)?;
    if let Some(name) = &a.camera {
        let frame = render::camera_frame(&loaded, name)?;
        render::write_png(&render::color_image(&frame), &a.out)?;
        let depth_out = render::depth_path(&a.out);
        let (depth, range) = render::depth_image(&frame);
        render::write_png(&depth, &depth_out)?;
        let range = match range {
            Some([lo, hi]) => format!("depth {lo:.3} .. {hi:.3} m"),
            None => "no depth".into(),
        };
        println!(
            "wrote {} and {} ({range})",
            a.out.display(),
            depth_out.display()
        );
        return Ok(());
    }
    let (width, height) = render::parse_size(&a.size)?;
    anyhow::ensure!(a.view.len() == 3, "--view takes three numbers x,y,z");
    let meshes: Vec<_> = (0..loaded.world.object_names().len())
        .map(|i| loaded.world.mesh(i))
        .collect();
    let options = render::RenderOptions {
        width,
        height,
        view_dir: nalgebra::Vector3::new(a.view[0], a.view[1], a.view[2]),
    };
    render::render_png(&meshes, &a.out, &options)?;
    println!("wrote {}", a.out.display());
    Ok(())
}

/// A flag set by the first Ctrl-C or SIGTERM (and `wake` called, for the node's poll
/// loop); a second one exits at once (`cli::stop`).
fn stop_flag(wake: impl Fn() + Send + 'static) -> anyhow::Result<Arc<AtomicBool>> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    ctrlc::set_handler(move || {
        let action = on_stop_signal(&flag);
        eprintln!("{}", stop_message(action));
        match action {
            StopAction::Stop => wake(),
            StopAction::ExitNow => std::process::exit(FORCED_EXIT_STATUS),
        }
    })
    .context("installing the Ctrl-C / SIGTERM handler")?;
    Ok(stop)
}

fn run_command(a: RunArgs) -> anyhow::Result<()> {
    let mut loaded = scene::load(&a.scene, &a.scene_overrides())?;
    let record = a.record.clone().map(bag_name::bag_folder);
    let stop = stop_flag(|| {})?;
    let mut recorder = match &record {
        Some(dir) => {
            let compression: Compression = a
                .record_compression
                .parse()
                .map_err(|e: String| anyhow::anyhow!("--record-compression: {e}"))?;
            let options = BagOptions {
                compression,
                record_cameras: a.record_cameras,
                ..BagOptions::default()
            };
            Some(RunRecorder::create(&loaded, dir, options)?)
        }
        None => None,
    };
    let mut observer = CliObserver {
        recorder: recorder.as_mut(),
        reach: ReachWatch::default(),
    };
    let result = runner::run(&mut loaded, &mut observer, &|| stop.load(Ordering::Relaxed));
    // close the bag whatever happened
    let closed = recorder.map(|r| r.close()).transpose();
    let run_stats = result?;
    if let (Some(n), Some(dir)) = (closed?, &record) {
        println!("recorded {n} messages into {}", dir.display());
    }
    print(summary::run_summary(&run_stats));
    match &a.stats {
        Some(path) => write_json(path, &run_stats, "stats to "),
        None => Ok(()),
    }
}

fn node_command(a: NodeArgs, ros: params::RosArgs) -> anyhow::Result<()> {
    let env_domain = std::env::var("ROS_DOMAIN_ID").ok();
    let config = node_launch::resolve(&a, &ros, env_domain.as_deref(), &mut |l| eprintln!("{l}"))?;
    for l in banner::banner(&config) {
        eprintln!("{l}");
    }
    let node = SimNode::new(config)?;
    let waker = node.waker();
    let stop = stop_flag(move || {
        let _ = waker.wake();
    })?;
    eprintln!("[developable_sim] ready");
    let stats = node.run(&stop)?;
    eprintln!("{}", summary::node_stopped(&stats));
    if let Some(path) = &a.stats {
        write_json(path, &stats, "")?;
    }
    if let Some(e) = &stats.record_error {
        bail!("recording failed: {e}");
    }
    Ok(())
}

fn report_command(a: ReportArgs) -> anyhow::Result<()> {
    use std::io::IsTerminal;
    let options = developable_sim::report::ReportOptions {
        scene_dir: a.scene_dir,
        scenes: a.scenes,
        quick: a.quick,
        out: a.out.clone(),
        progress: std::io::stderr().is_terminal(),
    };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let command = format!("developable_sim {}", args.join(" "));
    let report = developable_sim::report::run_report(&options, &command)?;
    print(summary::exact_summary(&report.exact));
    println!("wrote {}", a.out.join("summary.md").display());
    let failed = report.failed_checks();
    if !failed.is_empty() {
        let which: Vec<String> = failed
            .iter()
            .map(|c| format!("{}: {}", c.scene, c.what))
            .collect();
        bail!(
            "accuracy against the exact solutions regressed: {} check(s) failed ({})",
            failed.len(),
            which.join("; ")
        );
    }
    Ok(())
}
