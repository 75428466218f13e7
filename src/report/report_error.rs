//! Why `report` could not finish: a scene that does not load or does not fit the
//! report, a run that failed, a file that could not be written.

use std::path::Path;

/// An error of the report (thiserror, so that the library needs no anyhow).
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    /// A scene or the options do not fit the report (the message says why).
    #[error("{0}")]
    Invalid(String),
    /// A run of the sweep failed: which run, and why.
    #[error("{what}")]
    Run {
        what: String,
        #[source]
        source: Box<ReportError>,
    },
    #[error(transparent)]
    Baseline(#[from] crate::baseline::BaselineError),
    /// A folder or file could not be read or written.
    #[error("{message}")]
    Io {
        message: String,
        #[source]
        source: std::io::Error,
    },
    /// A plot could not be drawn or written.
    #[error(transparent)]
    Plot(#[from] crate::plot::PlotError),
    #[error(transparent)]
    Format(#[from] std::fmt::Error),
    #[error("cannot start the report's thread")]
    Thread(#[source] rayon::ThreadPoolBuildError),
}

impl ReportError {
    /// `source` as the failure of the run described by `what`.
    pub fn in_run(what: String, source: ReportError) -> ReportError {
        ReportError::Run {
            what,
            source: Box::new(source),
        }
    }
}

/// An I/O error with the action and the path it concerns ("cannot write x.csv").
pub(super) fn io(action: &'static str, path: &Path) -> impl FnOnce(std::io::Error) -> ReportError {
    let message = format!("{action} {}", path.display());
    move |source| ReportError::Io { message, source }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn io_errors_name_the_action_and_the_path_and_keep_the_cause() {
        let cause = std::io::Error::new(std::io::ErrorKind::NotFound, "gone");
        let e = io("cannot write", Path::new("/x/report.csv"))(cause);
        assert_eq!(e.to_string(), "cannot write /x/report.csv");
        let source = std::error::Error::source(&e).expect("the io error is the source");
        assert_eq!(source.to_string(), "gone");
        let run = ReportError::in_run("scene: lbfgsb dt=0.01".into(), e);
        assert_eq!(run.to_string(), "scene: lbfgsb dt=0.01");
        assert!(std::error::Error::source(&run).is_some());
    }
}
