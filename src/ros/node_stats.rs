//! What a node run measured (`node --stats OUT.json`): latencies, counters, windows.

use serde::Serialize;

/// Latency figures of a node run (`node --stats OUT.json`). Milliseconds.
#[derive(Clone, Debug, Default, Serialize)]
pub struct LatencyStats {
    pub samples: usize,
    pub median_ms: f64,
    pub p99_ms: f64,
    pub max_ms: f64,
}

impl LatencyStats {
    pub(crate) fn of(samples: &[f64]) -> LatencyStats {
        if samples.is_empty() {
            return LatencyStats::default();
        }
        let mut v = samples.to_vec();
        v.sort_by(f64::total_cmp);
        let at = |p: f64| v[((p * (v.len() - 1) as f64).round() as usize).min(v.len() - 1)];
        LatencyStats {
            samples: v.len(),
            median_ms: at(0.5),
            p99_ms: at(0.99),
            max_ms: v[v.len() - 1],
        }
    }
}

/// One window of a long run (growth checks).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Window {
    /// Wall time since start at the end of the window, s.
    pub end_s: f64,
    /// Resident memory at the end of the window, KiB.
    pub rss_kib: u64,
    pub steps: u64,
    pub inputs: u64,
    pub tick_to_markers: LatencyStats,
    pub input_to_markers: LatencyStats,
}

/// What a node run did.
#[derive(Clone, Debug, Default, Serialize)]
pub struct NodeStats {
    pub scene: String,
    pub mode: String,
    pub dt: f64,
    pub steps: u64,
    pub sim_time: f64,
    pub wall_s: f64,
    pub inputs_received: u64,
    pub inputs_rejected: u64,
    pub overrun_ticks: u64,
    /// Publications that failed or were dropped (full reliable window).
    pub dropped_publications: u64,
    /// Service replies sent (after the client's reply reader was matched).
    pub service_replies: u64,
    /// Service replies sent after `reply::GIVE_UP` without the client's reply reader
    /// matched (the client may never see them), or that failed to send.
    pub service_replies_unseen: u64,
    /// Simulator step only.
    pub step: LatencyStats,
    /// Tick start (or lock-step trigger) -> markers published.
    pub tick_to_markers: LatencyStats,
    /// Per tick: tick start -> markers published minus that tick's own step time (the
    /// node's processing beyond the simulator: taking inputs, building and publishing
    /// the frame).
    pub tick_beyond_step: LatencyStats,
    /// Pose taken from DDS -> markers of the first step that used it published.
    pub input_to_markers: LatencyStats,
    /// Camera frames drawn and published (all cameras).
    pub camera_frames: u64,
    /// Camera ticks skipped: the camera was still drawing its previous frame.
    pub camera_frames_skipped: u64,
    /// Per camera frame: wall time on its camera's thread, drawing and encoding the five
    /// messages.
    pub camera_draw: LatencyStats,
    /// Per 10 s of wall time.
    pub windows: Vec<Window>,
    /// Messages recorded per topic.
    pub recorded: Vec<(String, u64)>,
    pub record_error: Option<String>,
}

/// Resident set size of this process, KiB (0 where /proc is unavailable).
pub fn rss_kib() -> u64 {
    std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| {
            s.split_whitespace()
                .nth(1)
                .and_then(|p| p.parse::<u64>().ok())
        })
        .map(|pages| pages * 4)
        .unwrap_or(0)
}

/// Says on stderr when a publication is dropped: once per topic and episode (the
/// count goes on in `SimStatus.dropped_publications` and `--stats`).
#[derive(Debug, Default)]
pub(crate) struct DropLog {
    episode: u32,
    said: Vec<String>,
}

impl DropLog {
    /// Whether this drop on `topic` in `episode` is the first one (to be said).
    pub(crate) fn first(&mut self, topic: &str, episode: u32) -> bool {
        if episode != self.episode {
            self.episode = episode;
            self.said.clear();
        }
        if self.said.iter().any(|t| t == topic) {
            return false;
        }
        self.said.push(topic.to_string());
        true
    }
}

#[cfg(test)]
mod tests {
    use super::DropLog;

    #[test]
    fn a_drop_is_said_once_per_topic_and_episode() {
        let mut log = DropLog::default();
        assert!(log.first("/ribbon/markers", 0));
        assert!(!log.first("/ribbon/markers", 0));
        assert!(log.first("/ribbon/status", 0));
        assert!(
            log.first("/ribbon/markers", 1),
            "a reset starts a new episode"
        );
        assert!(!log.first("/ribbon/markers", 1));
    }
}
