//! The command line's options, one struct per subcommand (clap derives them; `main.rs`
//! dispatches on them and the launch code reads them, so no field is copied by hand).

use std::path::PathBuf;

use clap::Args;

/// Options shared by the commands that load a scene: `--set KEY=VALUE`, repeatable.
#[derive(Args, Clone, Debug, Default)]
pub struct SceneOverrides {
    /// Override a scene key: --set ribbon.segments=200 (value parsed as YAML).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
}

// `developable_sim run`
#[derive(Args, Clone, Debug)]
pub struct RunArgs {
    /// Scene file (YAML), e.g. config/scenes/ribbon_extreme_torsion.yaml.
    pub scene: PathBuf,
    /// Simulated duration, s (overrides the scene's `duration`).
    #[arg(long)]
    pub duration: Option<f64>,
    /// Time step, s (overrides the scene's `dt`).
    #[arg(long)]
    pub dt: Option<f64>,
    #[command(flatten)]
    pub overrides: SceneOverrides,
    /// Write run statistics as JSON.
    #[arg(long, value_name = "OUT.json")]
    pub stats: Option<PathBuf>,
    /// Record every step into this rosbag2 folder (as the node would publish it);
    /// without a value: rosbag2_YYYY_MM_DD-HH_MM_SS (UTC), as `ros2 bag record` names it.
    #[arg(long, value_name = "BAG_DIR")]
    pub record: Option<Option<PathBuf>>,
    /// MCAP chunk compression of the bag: none or lz4.
    #[arg(long, default_value = "none")]
    pub record_compression: String,
    /// Record the cameras' images and clouds too (big: 6.4 MB a 640 x 480 frame); their
    /// camera_info is recorded regardless.
    #[arg(long)]
    pub record_cameras: bool,
}

impl RunArgs {
    /// The scene overrides in the order they apply: `--duration`, `--dt`, then `--set`.
    pub fn scene_overrides(&self) -> Vec<String> {
        let mut overrides = Vec::new();
        if let Some(d) = self.duration {
            overrides.push(format!("duration={d}"));
        }
        if let Some(d) = self.dt {
            overrides.push(format!("dt={d}"));
        }
        overrides.extend(self.overrides.sets.iter().cloned());
        overrides
    }
}

// `developable_sim render`
#[derive(Args, Clone, Debug)]
pub struct RenderArgs {
    /// Scene file (YAML).
    pub scene: PathBuf,
    /// Output PNG.
    #[arg(long, value_name = "OUT.png")]
    pub out: PathBuf,
    /// Simulated time of the picture, s (default: the scene's duration).
    #[arg(long)]
    pub time: Option<f64>,
    /// Override a scene key (as for `run`).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// View direction (world, towards the scene).
    #[arg(long, value_delimiter = ',', default_value = "-1,-2,-1.2")]
    pub view: Vec<f64>,
    /// Picture size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "960x540")]
    pub size: String,
    /// Render this camera of the scene's `cameras:` instead (its own size and view):
    /// OUT.png is its colour image, OUT_depth.png its depth, colour-mapped (turbo,
    /// blue near to red far over the frame's depth range, black: no depth).
    #[arg(long, value_name = "NAME", conflicts_with_all = ["view", "size"])]
    pub camera: Option<String>,
}

impl RenderArgs {
    /// The scene overrides: `--set`, then `--time` as the duration.
    pub fn scene_overrides(&self) -> Vec<String> {
        let mut overrides = self.sets.clone();
        if let Some(t) = self.time {
            overrides.push(format!("duration={t}"));
        }
        overrides
    }
}

// `developable_sim node`
#[derive(Args, Clone, Debug, Default)]
pub struct NodeArgs {
    /// Scene file (YAML). May instead come from the `scene` parameter.
    pub scene: Option<PathBuf>,
    /// Record inputs and outputs into this rosbag2 folder (must not exist yet);
    /// without a value: rosbag2_YYYY_MM_DD-HH_MM_SS (UTC), as `ros2 bag record` names it.
    #[arg(long, value_name = "BAG_DIR")]
    pub record: Option<Option<PathBuf>>,
    /// Record the cameras' images and clouds too (big: 6.4 MB a 640 x 480 frame); their
    /// camera_info is recorded regardless.
    #[arg(long)]
    pub record_cameras: bool,
    /// ROS 2 params file (`node_name:` or `/**:` then `ros__parameters:`); repeatable.
    #[arg(long = "params", value_name = "PARAMS.yaml")]
    pub params: Vec<PathBuf>,
    /// DDS domain id (default: $ROS_DOMAIN_ID, else 0).
    #[arg(long)]
    pub domain_id: Option<u16>,
    /// Node namespace, e.g. /robot1 (default /, or `-r __ns:=`).
    #[arg(long)]
    pub namespace: Option<String>,
    /// Node name (default developable_sim, or `-r __node:=`).
    #[arg(long)]
    pub node_name: Option<String>,
    /// Step as fast as possible instead of in real time.
    #[arg(long)]
    pub as_fast_as_possible: bool,
    /// Lock-step: `service` (one step per ~/step call) or a handle name (one step per
    /// pose accepted on its topic).
    #[arg(long, value_name = "HANDLE|service")]
    pub lockstep: Option<String>,
    /// Exit after this much simulated time, s (default: run until stopped).
    #[arg(long)]
    pub duration: Option<f64>,
    /// Simulated seconds per wall-clock second in real-time mode.
    #[arg(long)]
    pub real_time_factor: Option<f64>,
    /// Start paused.
    #[arg(long)]
    pub paused: bool,
    #[command(flatten)]
    pub overrides: SceneOverrides,
    /// Write latency and run statistics as JSON at exit.
    #[arg(long, value_name = "OUT.json")]
    pub stats: Option<PathBuf>,
    /// Serve a live Foxglove view on this TCP port (foxglove.sdk.v1; connect
    /// Foxglove to ws://localhost:PORT); 0: off (default, or the `foxglove_port` parameter).
    #[arg(long, value_name = "PORT")]
    pub foxglove: Option<u16>,
    /// IP address of the Foxglove server (default 127.0.0.1: this machine only;
    /// 0.0.0.0: every interface, no authentication).
    #[arg(long, value_name = "ADDR")]
    pub foxglove_bind: Option<String>,
}

// `developable_sim replay`
#[derive(Args, Clone, Debug)]
pub struct ReplayArgs {
    /// Bag folder recorded by `node --record` or `run --record`.
    pub bag: PathBuf,
    /// Simulate this scene instead of the one stored in the bag.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Write the comparison as JSON.
    #[arg(long, value_name = "OUT.json")]
    pub stats: Option<PathBuf>,
}

// `developable_sim report`
#[derive(Args, Clone, Debug)]
pub struct ReportArgs {
    /// Scene file-name glob in --scene-dir (`*`, `?`); default: extreme torsion,
    /// helix unrolling, paper cylinder then bend.
    #[arg(long, value_name = "GLOB")]
    pub scenes: Option<String>,
    /// Short durations, 3 time steps, a small reference (CI; under 2 minutes).
    #[arg(long)]
    pub quick: bool,
    /// Output directory.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    #[arg(long, value_name = "DIR", default_value = "config/scenes")]
    pub scene_dir: PathBuf,
}

// `developable_sim stress`
#[derive(Args, Clone, Debug)]
pub struct StressArgs {
    /// Output folder.
    #[arg(long, value_name = "DIR", default_value = "target/stress")]
    pub out: PathBuf,
    /// Shorter runs and fewer time steps (CI).
    #[arg(long)]
    pub quick: bool,
    /// Only the cases whose name contains this.
    #[arg(long)]
    pub only: Option<String>,
    /// Only this time step, s.
    #[arg(long)]
    pub dt: Option<f64>,
    /// Replace every case's limit on the number of steps.
    #[arg(long)]
    pub max_steps: Option<usize>,
    /// The repository's config folder (scenes/ and stress/).
    #[arg(long, value_name = "DIR", default_value = "config")]
    pub config: PathBuf,
}

impl From<&StressArgs> for crate::stress::SuiteOptions {
    fn from(a: &StressArgs) -> Self {
        crate::stress::SuiteOptions {
            quick: a.quick,
            only: a.only.clone(),
            dt: a.dt,
            max_steps: a.max_steps,
        }
    }
}
