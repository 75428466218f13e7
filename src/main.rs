//! The `developable_sim` command line: the ROS 2 node, headless runs, bags and replay.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::{bail, Context};
use clap::{Parser, Subcommand};

use developable_sim::record::bag::{BagOptions, Compression};
use developable_sim::record::recorder::RunRecorder;
use developable_sim::record::{read, replay};
use developable_sim::ros::foxglove::FoxgloveConfig;
use developable_sim::ros::input::InputPolicy;
use developable_sim::ros::names::NodeNames;
use developable_sim::ros::node::{Lockstep, NodeConfig, Pacing, SimNode};
use developable_sim::ros::params::{self, ParamValue, Params};
use developable_sim::ros::session::MarkerStyle;
use developable_sim::runner::StepObserver;
use developable_sim::scene::Scene;
use developable_sim::sim::{ReachWatch, StepReport};
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
        /// Record every step into this rosbag2 folder (as the node would publish it);
        /// without a value: rosbag2_YYYY_MM_DD-HH_MM_SS (UTC), as `ros2 bag record` names it.
        #[arg(long, value_name = "BAG_DIR")]
        record: Option<Option<PathBuf>>,
        /// MCAP chunk compression of the bag: none or lz4.
        #[arg(long, default_value = "none")]
        record_compression: String,
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
    /// Run the ROS 2 node: handle poses in; markers, singular points, status, /clock out.
    Node {
        /// Scene file (YAML). May instead come from the `scene` parameter.
        scene: Option<PathBuf>,
        /// Record inputs and outputs into this rosbag2 folder (must not exist yet);
        /// without a value: rosbag2_YYYY_MM_DD-HH_MM_SS (UTC), as `ros2 bag record` names it.
        #[arg(long, value_name = "BAG_DIR")]
        record: Option<Option<PathBuf>>,
        /// ROS 2 params file (`node_name:` or `/**:` then `ros__parameters:`); repeatable.
        #[arg(long = "params", value_name = "PARAMS.yaml")]
        params: Vec<PathBuf>,
        /// DDS domain id (default: $ROS_DOMAIN_ID, else 0).
        #[arg(long)]
        domain_id: Option<u16>,
        /// Node namespace, e.g. /robot1 (default /, or `-r __ns:=`).
        #[arg(long)]
        namespace: Option<String>,
        /// Node name (default developable_sim, or `-r __node:=`).
        #[arg(long)]
        node_name: Option<String>,
        /// Step as fast as possible instead of in real time.
        #[arg(long)]
        as_fast_as_possible: bool,
        /// Lock-step: `service` (one step per ~/step call) or a handle name (one step per
        /// pose accepted on its topic).
        #[arg(long, value_name = "HANDLE|service")]
        lockstep: Option<String>,
        /// Exit after this much simulated time, s (default: run until stopped).
        #[arg(long)]
        duration: Option<f64>,
        /// Simulated seconds per wall-clock second in real-time mode.
        #[arg(long)]
        real_time_factor: Option<f64>,
        /// Start paused.
        #[arg(long)]
        paused: bool,
        /// Override a scene key: --set ribbon.segments=200 (value parsed as YAML).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// Write latency and run statistics as JSON at exit.
        #[arg(long, value_name = "OUT.json")]
        stats: Option<PathBuf>,
        /// Serve a live Foxglove view on this TCP port (foxglove.sdk.v1; connect
        /// Foxglove to ws://localhost:PORT); 0: off (default, or the `foxglove_port` parameter).
        #[arg(long, value_name = "PORT")]
        foxglove: Option<u16>,
        /// IP address of the Foxglove server (default 127.0.0.1: this machine only;
        /// 0.0.0.0: every interface, no authentication).
        #[arg(long, value_name = "ADDR")]
        foxglove_bind: Option<String>,
    },
    /// Re-simulate a bag from its recorded handle poses and compare every output.
    Replay {
        /// Bag folder recorded by `node --record` or `run --record`.
        bag: PathBuf,
        /// Simulate this scene instead of the one stored in the bag.
        #[arg(long)]
        scene: Option<PathBuf>,
        /// Write the comparison as JSON.
        #[arg(long, value_name = "OUT.json")]
        stats: Option<PathBuf>,
    },
    /// Bag tools.
    Bag {
        #[command(subcommand)]
        command: BagCommand,
    },
    /// Same as `bag reindex`.
    Reindex { bag: PathBuf },
    /// Error against run time: sweep dt, resolution, tolerance and methods per scene,
    /// compare with a converged reference; writes report.csv, <scene>.png, summary.md.
    Report {
        /// Scene file-name glob in --scene-dir (`*`, `?`); default: extreme torsion,
        /// helix unrolling, paper cylinder then bend.
        #[arg(long, value_name = "GLOB")]
        scenes: Option<String>,
        /// Short durations, 3 time steps, a small reference (CI; under 2 minutes).
        #[arg(long)]
        quick: bool,
        /// Output directory.
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        #[arg(long, value_name = "DIR", default_value = "config/scenes")]
        scene_dir: PathBuf,
    },
    /// Stiff and extreme cases over time steps 0.001-0.1 s: a pass/fail table in
    /// OUT/stress.md and OUT/stress.json; exits non-zero if any run fails.
    Stress {
        /// Output folder.
        #[arg(long, value_name = "DIR", default_value = "target/stress")]
        out: PathBuf,
        /// Shorter runs and fewer time steps (CI).
        #[arg(long)]
        quick: bool,
        /// Only the cases whose name contains this.
        #[arg(long)]
        only: Option<String>,
        /// Only this time step, s.
        #[arg(long)]
        dt: Option<f64>,
        /// Replace every case's limit on the number of steps.
        #[arg(long)]
        max_steps: Option<usize>,
        /// The repository's config folder (scenes/ and stress/).
        #[arg(long, value_name = "DIR", default_value = "config")]
        config: PathBuf,
    },
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

/// A check that ran to the end and found a difference: exit code 1 (an error that
/// stops a command, such as an unreadable bag, is exit code 2).
#[derive(Debug)]
struct CheckFailed(String);

impl std::fmt::Display for CheckFailed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for CheckFailed {}

fn real_main(cli: Cli, ros: params::RosArgs) -> anyhow::Result<()> {
    let non_node = !matches!(cli.command, Command::Node { .. });
    if non_node && ros != params::RosArgs::default() {
        bail!("--ros-args only apply to `developable_sim node`");
    }
    match cli.command {
        Command::Run {
            scene,
            duration,
            dt,
            sets,
            stats,
            record,
            record_compression,
        } => run_command(
            scene,
            duration,
            dt,
            sets,
            stats,
            record,
            &record_compression,
        ),
        Command::Node {
            scene,
            record,
            params,
            domain_id,
            namespace,
            node_name,
            as_fast_as_possible,
            lockstep,
            duration,
            real_time_factor,
            paused,
            sets,
            stats,
            foxglove,
            foxglove_bind,
        } => node_command(NodeArgs {
            scene,
            record,
            params,
            domain_id,
            namespace,
            node_name,
            as_fast_as_possible,
            lockstep,
            duration,
            real_time_factor,
            paused,
            sets,
            stats,
            foxglove,
            foxglove_bind,
            ros,
        }),
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
            let (width, height) = render::parse_size(&size)?;
            anyhow::ensure!(view.len() == 3, "--view takes three numbers x,y,z");
            let meshes: Vec<_> = (0..loaded.world.object_names().len())
                .map(|i| loaded.world.mesh(i))
                .collect();
            let view_dir = nalgebra::Vector3::new(view[0], view[1], view[2]);
            let options = render::RenderOptions {
                width,
                height,
                view_dir,
            };
            render::render_png(&meshes, &out, &options)?;
            println!("wrote {}", out.display());
            Ok(())
        }
        Command::Replay { bag, scene, stats } => {
            let report = replay::replay(&bag, &replay::ReplayOptions { scene })?;
            println!(
                "replayed {}: scene {}, {} steps, {} resets, {} handle poses fed, {:.2} s",
                report.bag, report.scene, report.steps, report.resets, report.inputs, report.wall_s
            );
            for t in &report.topics {
                println!(
                    "  {:<32} {:>7} compared  {:>6} differ  {:>4} missing  max |diff| {:.3e}{}{}{}",
                    t.topic,
                    t.compared,
                    t.differing,
                    t.missing,
                    t.max_abs_difference,
                    if t.max_at.is_empty() {
                        String::new()
                    } else {
                        format!(" at {}", t.max_at)
                    },
                    t.structural
                        .as_ref()
                        .map(|s| format!("; structure: {s}"))
                        .unwrap_or_default(),
                    if t.first_difference.is_empty() {
                        String::new()
                    } else {
                        format!("; first: {}", t.first_difference)
                    }
                );
            }
            if let Some(t) = &report.truncated {
                println!("  note: the bag ends early ({t}); compared up to there");
            }
            println!(
                "{}",
                if report.identical {
                    "identical: every recorded output reproduced bit for bit".to_string()
                } else {
                    format!(
                        "DIFFERENT: largest difference {:.3e}",
                        report.max_abs_difference
                    )
                }
            );
            if let Some(path) = stats {
                std::fs::write(&path, serde_json::to_string_pretty(&report)?)
                    .with_context(|| format!("writing {}", path.display()))?;
            }
            if !report.identical {
                return Err(CheckFailed(format!(
                    "replay of {}: the outputs differ from the recording",
                    report.bag
                ))
                .into());
            }
            Ok(())
        }
        Command::Bag {
            command: BagCommand::Reindex { bag },
        }
        | Command::Reindex { bag } => reindex_command(&bag),
        Command::Report {
            scenes,
            quick,
            out,
            scene_dir,
        } => report_command(scenes, quick, out, scene_dir),
        Command::Stress {
            out,
            quick,
            only,
            dt,
            max_steps,
            config,
        } => {
            let options = developable_sim::stress::SuiteOptions {
                quick,
                only,
                dt,
                max_steps,
            };
            let report = developable_sim::stress::run_suite(&config, &out, &options)?;
            println!(
                "{} of {} runs passed in {:.1} s; table in {}",
                report.passed,
                report.results.len(),
                report.wall_s,
                out.join("stress.md").display()
            );
            if report.failed > 0 {
                bail!("{} stress run(s) failed", report.failed);
            }
            Ok(())
        }
        Command::Bag {
            command: BagCommand::Info { bag },
        } => {
            for file in read::mcap_files(&bag)? {
                let s = read::scan(&file)?;
                println!(
                    "{}: {} messages{}",
                    file.display(),
                    s.message_count(),
                    match (&s.truncated, s.complete) {
                        (_, true) => String::new(),
                        (Some(t), false) =>
                            format!(" (incomplete file: {t}; run `developable_sim bag reindex`)"),
                        (None, false) =>
                            " (incomplete file: no footer; run `developable_sim bag reindex`)"
                                .into(),
                    }
                );
                for t in s.topics() {
                    println!("  {:<36} {:<40} {}", t.name, t.type_name, t.count);
                }
            }
            Ok(())
        }
    }
}

/// `--record` without a value: a new folder named as `ros2 bag record` names it.
fn bag_folder(given: Option<PathBuf>) -> PathBuf {
    if let Some(given) = given {
        return given;
    }
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as i64)
        .unwrap_or(0);
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    // civil date from days since 1970-01-01 (H. Hinnant's algorithm)
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + (month <= 2) as i64;
    PathBuf::from(format!(
        "rosbag2_{year:04}_{month:02}_{day:02}-{:02}_{:02}_{:02}",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    ))
}

fn reindex_command(bag: &Path) -> anyhow::Result<()> {
    let r = read::reindex(bag)?;
    for ((file, kept), why) in r.repaired.iter().zip(&r.truncation) {
        println!(
            "{}: was incomplete ({why}); rewritten with every readable message, original kept as {}",
            file.display(),
            kept.display()
        );
    }
    let info = &r.metadata.rosbag2_bagfile_information;
    println!(
        "{}: metadata.yaml rebuilt: {} messages on {} topics",
        bag.display(),
        info.message_count,
        info.topics_with_message_count.len()
    );
    Ok(())
}

fn run_command(
    scene_path: PathBuf,
    duration: Option<f64>,
    dt: Option<f64>,
    sets: Vec<String>,
    stats: Option<PathBuf>,
    record: Option<Option<PathBuf>>,
    record_compression: &str,
) -> anyhow::Result<()> {
    let mut overrides = Vec::new();
    if let Some(d) = duration {
        overrides.push(format!("duration={d}"));
    }
    if let Some(d) = dt {
        overrides.push(format!("dt={d}"));
    }
    overrides.extend(sets);
    let mut loaded = scene::load(&scene_path, &overrides)?;
    let record = record.map(bag_folder);
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = Arc::clone(&stop);
        ctrlc::set_handler(move || stop.store(true, Ordering::SeqCst))
            .context("installing the Ctrl-C handler")?;
    }
    let mut recorder = match &record {
        Some(dir) => {
            let compression: Compression = record_compression
                .parse()
                .map_err(|e: String| anyhow::anyhow!("--record-compression: {e}"))?;
            Some(RunRecorder::create(
                &loaded,
                dir,
                BagOptions {
                    compression,
                    ..BagOptions::default()
                },
            )?)
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
    if let (Some(c), Some(n), Some(t), Some(sv)) = (
        run_stats.compression_mean_pct,
        run_stats.compressed_edges_pct,
        run_stats.triangles_mean,
        run_stats.singular_vertices,
    ) {
        let phases = run_stats
            .phase_ms
            .as_ref()
            .map(|p| {
                format!(
                    ", phases (median ms) simulation {:.3} remesh {:.3} isometry {:.3}",
                    p.simulation, p.remesh, p.isometry
                )
            })
            .unwrap_or_default();
        println!(
            "paper: compression mean {c:.3} %, edges compressed > 1 %: {n:.2} %, triangles mean {t:.1}, singular vertices {sv}{phases}"
        );
    }
    if let Some(c) = &run_stats.contact {
        println!(
            "contact: median {:.3} ms per step, penetration max {:.2e} m, contacts max {}, rounds max {}, {} unresolved steps, developability error (|X - X~|) max {:.2e} m, flipped/degenerate triangles {}/{}",
            run_stats.contact_ms.median,
            run_stats.penetration_max,
            c.contacts_max,
            c.iterations_max,
            c.unresolved_steps,
            c.correction_max,
            c.flipped_triangles,
            c.degenerate_triangles
        );
    }
    if let Some(path) = stats {
        let json = serde_json::to_string_pretty(&run_stats)?;
        std::fs::write(&path, json)
            .with_context(|| format!("writing stats to {}", path.display()))?;
    }
    Ok(())
}

struct NodeArgs {
    scene: Option<PathBuf>,
    record: Option<Option<PathBuf>>,
    params: Vec<PathBuf>,
    domain_id: Option<u16>,
    namespace: Option<String>,
    node_name: Option<String>,
    as_fast_as_possible: bool,
    lockstep: Option<String>,
    duration: Option<f64>,
    real_time_factor: Option<f64>,
    paused: bool,
    sets: Vec<String>,
    stats: Option<PathBuf>,
    foxglove: Option<u16>,
    foxglove_bind: Option<String>,
    ros: params::RosArgs,
}

fn domain_id(cli: Option<u16>) -> anyhow::Result<u16> {
    let id = match cli {
        Some(id) => id,
        None => match std::env::var("ROS_DOMAIN_ID") {
            Ok(v) if !v.trim().is_empty() => v.trim().parse::<u16>().with_context(|| {
                format!("ROS_DOMAIN_ID={v:?} is not a domain id (an integer 0..=232)")
            })?,
            _ => 0,
        },
    };
    if id > 232 {
        bail!("domain id {id} is out of range: DDS allows 0..=232 (ROS recommends 0..=101)");
    }
    Ok(id)
}

fn node_command(a: NodeArgs) -> anyhow::Result<()> {
    let node_name = a
        .node_name
        .or(a.ros.node_name.clone())
        .unwrap_or_else(|| "developable_sim".into());
    let namespace = a
        .namespace
        .or(a.ros.namespace.clone())
        .unwrap_or_else(|| "/".into());
    let namespace = developable_sim::ros::names::normalize_namespace(&namespace)?;
    let fqn = if namespace == "/" {
        format!("/{node_name}")
    } else {
        format!("{namespace}/{node_name}")
    };
    // parameters: params files in order, then -p, then dedicated flags
    let mut p = Params::default();
    for f in a.params.iter().chain(&a.ros.params_files) {
        params::read_params_file(f, &fqn, &mut p)?;
    }
    for spec in &a.ros.params {
        params::set_from_command_line(&mut p, spec)?;
    }
    for w in &p.warnings {
        eprintln!("[developable_sim] warning: {w}");
    }
    for i in &a.ros.ignored {
        eprintln!("[developable_sim] note: ROS argument `{i}` is accepted and ignored");
    }
    let scene_path = match (a.scene, p.string("scene").filter(|s| !s.is_empty())) {
        (Some(s), _) => s,
        (None, Some(s)) => PathBuf::from(s),
        (None, None) => bail!(
            "no scene: give SCENE.yaml (e.g. `developable_sim node config/scenes/ribbon_extreme_torsion.yaml`) or the `scene` parameter"
        ),
    };
    let mut overrides: Vec<String> = p
        .strings("scene_overrides")
        .map(|s| s.to_vec())
        .unwrap_or_default();
    overrides.extend(a.sets);
    let scene = scene::load(&scene_path, &overrides)?;

    let positive = |name: &str, v: f64| -> anyhow::Result<f64> {
        if v > 0.0 && v.is_finite() {
            Ok(v)
        } else {
            Err(p.invalid(name, format!("must be > 0, got {v}")).into())
        }
    };
    let non_negative = |name: &str, v: f64| -> anyhow::Result<f64> {
        if v >= 0.0 && v.is_finite() {
            Ok(v)
        } else {
            Err(p.invalid(name, format!("must be >= 0, got {v}")).into())
        }
    };
    let duration = match a.duration {
        Some(d) if d.is_finite() && d >= 0.0 => d,
        Some(d) => bail!("--duration must be >= 0 s, got {d}"),
        None => {
            let d = p.double("duration").unwrap_or(0.0);
            if d < 0.0 {
                return Err(p
                    .invalid("duration", format!("must be >= 0, got {d}"))
                    .into());
            }
            d
        }
    };
    let factor = match a.real_time_factor {
        Some(f) if f > 0.0 && f.is_finite() => f,
        Some(f) => bail!("--real-time-factor must be > 0, got {f}"),
        None => positive(
            "real_time_factor",
            p.double("real_time_factor").unwrap_or(1.0),
        )?,
    };
    let pacing = if a.as_fast_as_possible || p.bool("as_fast_as_possible") == Some(true) {
        Pacing::AsFastAsPossible
    } else {
        Pacing::RealTime { factor }
    };
    let lockstep_spec = a
        .lockstep
        .clone()
        .or_else(|| p.string("lockstep").map(String::from))
        .unwrap_or_default();
    let handle_names: Vec<String> = scene
        .world
        .handles()
        .iter()
        .map(|h| h.name.clone())
        .collect();
    let lockstep = match lockstep_spec.as_str() {
        "" => Lockstep::Off,
        "service" => Lockstep::Service,
        h => match handle_names.iter().position(|n| n == h) {
            Some(i) => Lockstep::Handle(i),
            None => {
                let msg = format!(
                    "`{h}` is neither `service` nor a handle of scene {} (handles: {})",
                    scene.name,
                    if handle_names.is_empty() {
                        "none".to_string()
                    } else {
                        handle_names.join(", ")
                    }
                );
                if a.lockstep.is_some() {
                    bail!("--lockstep {msg}");
                }
                return Err(p.invalid("lockstep", msg).into());
            }
        },
    };
    let compression: Compression = p
        .string("record_compression")
        .unwrap_or("none")
        .parse()
        .map_err(|e: String| p.invalid("record_compression", e))?;
    let flush = positive(
        "record_flush_period",
        p.double("record_flush_period").unwrap_or(1.0),
    )?;
    let record = a.record.map(bag_folder).or_else(|| {
        p.string("record")
            .filter(|s| !s.is_empty())
            .map(PathBuf::from)
    });
    let style = MarkerStyle {
        line_width: positive(
            "marker.line_width",
            p.double("marker.line_width").unwrap_or(0.002),
        )?,
        sphere_diameter: positive(
            "marker.sphere_diameter",
            p.double("marker.sphere_diameter").unwrap_or(0.012),
        )?,
        ..MarkerStyle::default()
    };
    let names = NodeNames::resolve(&scene, &node_name, &namespace, &a.ros.remaps)?;
    let domain_id = domain_id(a.domain_id)?;
    let policy = InputPolicy {
        frame_id: scene.frame_id.clone(),
        accept_empty_frame_id: p.bool("accept_empty_frame_id").unwrap_or(false),
        max_stamp_lead: positive(
            "max_stamp_lead",
            p.double("max_stamp_lead")
                .unwrap_or(developable_sim::ros::input::DEFAULT_MAX_STAMP_LEAD),
        )?,
    };
    let start_paused = a.paused || p.bool("start_paused").unwrap_or(false);

    banner(
        &scene,
        &names,
        domain_id,
        pacing,
        &lockstep,
        record.as_deref(),
    );
    let use_sim_time = p.bool("use_sim_time").unwrap_or(false);
    let tf_max_lag = non_negative(
        "tf_max_lag",
        p.double("tf_max_lag")
            .unwrap_or(developable_sim::ros::tf::DEFAULT_MAX_LAG),
    )?;
    if let Some(r) = p.double("markers_rate") {
        non_negative("markers_rate", r)?;
    }
    let foxglove = foxglove_config(&a.foxglove, &a.foxglove_bind, &mut p)?;
    p.set_effective(
        "scene",
        ParamValue::String(scene_path.display().to_string()),
    );
    p.set_effective("duration", ParamValue::Double(duration));
    p.set_effective("lockstep", ParamValue::String(lockstep_spec.clone()));
    if let Some(r) = &record {
        p.set_effective("record", ParamValue::String(r.display().to_string()));
    }
    let node = SimNode::new(NodeConfig {
        scene,
        names,
        domain_id,
        record: record.map(|dir| {
            (
                dir,
                BagOptions {
                    compression,
                    flush_period: std::time::Duration::from_secs_f64(flush),
                    ..BagOptions::default()
                },
            )
        }),
        duration: (duration > 0.0).then_some(duration),
        pacing,
        lockstep,
        start_paused,
        policy,
        style,
        use_sim_time,
        tf_max_lag,
        params: p,
        foxglove,
    })?;
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = Arc::clone(&stop);
        let waker = node.waker();
        ctrlc::set_handler(move || {
            stop.store(true, Ordering::SeqCst);
            let _ = waker.wake();
        })
        .context("installing the Ctrl-C / SIGTERM handler")?;
    }
    eprintln!("[developable_sim] ready");
    let stats = node.run(&stop)?;
    eprintln!(
        "[developable_sim] stopped at t = {:.3} s after {} steps ({} poses received, {} rejected); \
         tick -> markers median {:.3} ms, p99 {:.3} ms",
        stats.sim_time,
        stats.steps,
        stats.inputs_received,
        stats.inputs_rejected,
        stats.tick_to_markers.median_ms,
        stats.tick_to_markers.p99_ms
    );
    if let Some(path) = a.stats {
        std::fs::write(&path, serde_json::to_string_pretty(&stats)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(e) = &stats.record_error {
        bail!("recording failed: {e}");
    }
    Ok(())
}

/// The Foxglove server's address from `--foxglove` / `--foxglove-bind` or the
/// `foxglove_port` / `foxglove_bind` parameters (flags win); port 0 or none: off.
fn foxglove_config(
    port: &Option<u16>,
    bind: &Option<String>,
    p: &mut Params,
) -> anyhow::Result<Option<FoxgloveConfig>> {
    let port = match (port, p.integer("foxglove_port")) {
        (Some(port), _) => *port,
        (None, Some(i)) => u16::try_from(i).map_err(|_| {
            p.invalid(
                "foxglove_port",
                format!("must be a TCP port 0..=65535, got {i}"),
            )
        })?,
        (None, None) => 0,
    };
    let bind_flag = bind;
    let bind = match (bind, p.string("foxglove_bind")) {
        (Some(b), _) => b.clone(),
        (None, Some(b)) => b.to_string(),
        (None, None) => developable_sim::ros::foxglove::DEFAULT_BIND.to_string(),
    };
    if bind.parse::<std::net::IpAddr>().is_err() {
        let msg = format!("`{bind}` is not an IP address (e.g. 127.0.0.1, 0.0.0.0)");
        if bind_flag.is_some() {
            bail!("--foxglove-bind {msg}");
        }
        return Err(p.invalid("foxglove_bind", msg).into());
    }
    p.set_effective("foxglove_port", ParamValue::Integer(port.into()));
    p.set_effective("foxglove_bind", ParamValue::String(bind.clone()));
    Ok((port > 0).then_some(FoxgloveConfig { bind, port }))
}

fn banner(
    scene: &Scene,
    names: &NodeNames,
    domain_id: u16,
    pacing: Pacing,
    lockstep: &Lockstep,
    record: Option<&Path>,
) {
    let mode = match (lockstep, pacing) {
        (Lockstep::Service, _) => "lock-step on ~/step".to_string(),
        (Lockstep::Handle(h), _) => format!("lock-step on {}", names.handles[*h]),
        (Lockstep::Off, Pacing::AsFastAsPossible) => "as fast as possible".into(),
        (Lockstep::Off, Pacing::RealTime { factor }) => {
            format!("real time x{factor} (dt {} s)", scene.world.dt())
        }
    };
    eprintln!(
        "[developable_sim] node {} on ROS domain {domain_id}: scene {} ({}), {mode}",
        names.fqn(),
        scene.name,
        scene.file.display()
    );
    for (h, t) in scene.world.handles().iter().zip(&names.handles) {
        eprintln!(
            "[developable_sim]   in : {t} (geometry_msgs/msg/PoseStamped, frame `{}`) -> handle {}",
            scene.frame_id, h.name
        );
    }
    for o in &names.objects {
        if scene.outputs.markers {
            eprintln!(
                "[developable_sim]   out: {} (visualization_msgs/msg/MarkerArray)",
                o.markers
            );
        }
        if scene.outputs.singular_points {
            eprintln!(
                "[developable_sim]   out: {} (developable_sim/msg/SingularPoints)",
                o.singular_points
            );
        }
        if scene.outputs.status {
            eprintln!(
                "[developable_sim]   out: {} (developable_sim/msg/SimStatus)",
                o.status
            );
        }
    }
    if scene.outputs.clock {
        eprintln!(
            "[developable_sim]   out: {} (rosgraph_msgs/msg/Clock)",
            names.clock
        );
    }
    eprintln!(
        "[developable_sim]   services: {} {} (std_srvs/srv/Trigger), {} (std_srvs/srv/SetBool)",
        names.reset, names.step, names.set_paused
    );
    if let Some(r) = record {
        eprintln!("[developable_sim]   recording into {}", r.display());
    }
}

fn report_command(
    scenes: Option<String>,
    quick: bool,
    out: PathBuf,
    scene_dir: PathBuf,
) -> anyhow::Result<()> {
    use std::io::IsTerminal;
    let options = developable_sim::report::ReportOptions {
        scene_dir,
        scenes,
        quick,
        out: out.clone(),
        progress: std::io::stderr().is_terminal(),
    };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let command = format!("developable_sim {}", args.join(" "));
    let report = developable_sim::report::run_report(&options, &command)?;
    if !report.exact.is_empty() {
        // the README's table of errors against the exact solutions
        println!(
            "{}",
            developable_sim::report::exact_output::readme_table(&report.exact)
        );
        for c in report.exact.iter().flat_map(|s| &s.checks) {
            println!(
                "{} {}: {}: measured {}",
                if c.pass { "PASS" } else { "FAIL" },
                c.scene,
                c.what,
                c.measured.map_or("n/a".into(), |m| format!("{m:.4}"))
            );
        }
    }
    println!("wrote {}", out.join("summary.md").display());
    let failed = report.failed_checks();
    if !failed.is_empty() {
        bail!(
            "accuracy against the exact solutions regressed: {} check(s) failed ({})",
            failed.len(),
            failed
                .iter()
                .map(|c| format!("{}: {}", c.scene, c.what))
                .collect::<Vec<_>>()
                .join("; ")
        );
    }
    Ok(())
}

/// The `run` command's observer: records when asked, and says on stderr when a handle
/// target goes out of reach and when it is reached again (as the node does).
struct CliObserver<'a> {
    recorder: Option<&'a mut RunRecorder>,
    reach: ReachWatch,
}

impl StepObserver for CliObserver<'_> {
    fn after_step(
        &mut self,
        scene: &Scene,
        report: &StepReport,
        step_ms: f64,
    ) -> anyhow::Result<()> {
        let world = &scene.world;
        for m in self
            .reach
            .update(report, world.object_names(), world.handles())
        {
            eprintln!("{m}");
        }
        match self.recorder.as_deref_mut() {
            Some(r) => r.after_step(scene, report, step_ms),
            None => Ok(()),
        }
    }
}
