//! Helpers the integration tests share (one way to do a thing): the scenes in
//! `config/scenes`, loading and running one headless, a fresh scratch folder per test,
//! a bag's metadata and a bag rewritten with edits, the lowest point of a mesh.
//!
//! Every file in `tests/` is a crate of its own that compiles this module with
//! `mod common;` and uses only part of it; the rest would warn as dead code in that
//! crate, hence the allowance.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use developable_sim::geometry::SurfaceMesh;
use developable_sim::record::bag::{BagOptions, BagWriter};
use developable_sim::record::metadata::MetadataFile;
use developable_sim::record::read::{mcap_files, BagEvent, BagMessage, McapStream};
use developable_sim::runner;
use developable_sim::scene::{self, Scene};
use developable_sim::stats::RunStats;
use developable_sim::wire::qos::Qos;

/// The extreme-torsion ribbon: short, no contact, what the CLI and bag tests drive.
pub const TORSION: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/config/scenes/ribbon_extreme_torsion.yaml"
);

/// `config/scenes/<name>.yaml`.
pub fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("config/scenes")
        .join(format!("{name}.yaml"))
}

/// The scene `name` with the `--set` overrides `sets`; a scene that does not load
/// fails the test with its name and the error.
pub fn load(name: &str, sets: &[&str]) -> Scene {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    scene::load(&scene_path(name), &sets).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// [`load`], then run it headless to its duration.
pub fn run(name: &str, sets: &[&str]) -> (Scene, RunStats) {
    let mut s = load(name, sets);
    let stats = runner::run(&mut s, &mut (), &|| false).expect("run");
    (s, stats)
}

/// An empty folder `<test crate>_<name>_<pid>` under cargo's scratch folder for
/// integration tests: tests running at the same time never share one.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "{}_{name}_{}",
        env!("CARGO_CRATE_NAME"),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The bag folder's `metadata.yaml`, parsed.
pub fn metadata(bag: &Path) -> MetadataFile {
    serde_yaml::from_str(&std::fs::read_to_string(bag.join("metadata.yaml")).unwrap()).unwrap()
}

/// The lowest z of `mesh`'s vertices, m.
pub fn lowest_z(mesh: &SurfaceMesh) -> f64 {
    mesh.vertices
        .iter()
        .map(|v| v.z)
        .fold(f64::INFINITY, f64::min)
}

/// Copy the bag `src` into `dst` message by message through the project's reader and
/// writer; `edit` sees each message and returns its new payload, or None to drop it.
pub fn rewrite(src: &Path, dst: &Path, mut edit: impl FnMut(&BagMessage) -> Option<Vec<u8>>) {
    let mut out = BagWriter::create(dst, BagOptions::default()).unwrap();
    let mut ids = std::collections::BTreeMap::new();
    for file in mcap_files(src).unwrap() {
        let mut stream = McapStream::open(&file).unwrap();
        while let Some(event) = stream.next() {
            match event.unwrap() {
                BagEvent::Metadata { name, values } => out.write_metadata(&name, values).unwrap(),
                BagEvent::Message(m) => {
                    // the same type, hash and schema as the source's channel
                    let ch = stream.channel(m.channel).unwrap().clone();
                    let id = *ids.entry(m.topic.clone()).or_insert_with(|| {
                        let hash = ch
                            .metadata
                            .get("topic_type_hash")
                            .cloned()
                            .unwrap_or_default();
                        let schema = String::from_utf8(ch.schema.clone()).unwrap();
                        out.add_topic_of(
                            &m.topic,
                            (&ch.type_name, &hash, &|| schema.clone()),
                            Qos::DATA,
                        )
                        .unwrap()
                    });
                    if let Some(data) = edit(&m) {
                        out.write_raw(id, m.log_time, m.publish_time, &data)
                            .unwrap();
                    }
                }
            }
        }
        assert!(stream.truncated.is_none());
    }
    out.close().unwrap();
}

/// `work` run on a rayon pool of `threads` threads (the thread-count checks).
pub fn on_threads<T: Send>(threads: usize, work: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(work)
}

/// Every vertex coordinate of every object of `scene`, as bits (bit-identical checks).
pub fn vertex_bits(scene: &Scene) -> Vec<u64> {
    (0..scene.world.objects().len())
        .flat_map(|o| scene.world.mesh(o).vertices.iter())
        .flat_map(|v| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()])
        .collect()
}
