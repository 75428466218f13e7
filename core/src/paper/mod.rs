//! The paper simulator (Schreck, Rohmer, Hahmann, Cani et al., "Non-smooth developable
//! geometry for interactively animating paper crumpling", ACM TOG 2015).
//!
//! A hybrid of a coarse physical mesh S_P ([`physical`]) and a geometric layer S_G
//! ([`geometric`]) of flat regions and curved regions (generalized cones meshed along
//! their rulings), kept almost isometric to the 2D pattern ([`pattern`]). Each frame
//! ([`PaperSim`]):
//! 1. elastic deformation of S_P ([`fem`], sec. 4);
//! 2. bending and crumpling: compression analysis ([`compression`]), ruling
//!    propagation and singular vertices ([`crumpling`], sec. 5, appendices A, B);
//! 3. developable and isometric tracking: junction points and generalized cones
//!    ([`tracking`], sec. 6.1, 6.2), edge lengths ([`isometry`], sec. 6.3).
//!
//! SI units throughout (m, rad, kg, s). Pure: no I/O, no serde. Deterministic: the
//! only randomness (the position of new singular vertices, sec. 5.2) comes from a
//! ChaCha generator seeded by [`PaperParams::seed`].

pub mod compression;
pub mod crumpling;
mod diagnostics;
pub mod fem;
pub mod geometric;
mod handle_set;
mod handles;
pub mod isometry;
pub mod params;
pub mod pattern;
pub mod physical;
pub mod projection;
pub mod reach;
mod sim;
pub(crate) mod sparse;
pub mod tracking;

pub use params::{
    Collider, LengthRestoration, PaperError, PaperInitialShape, PaperParams, PresetCrease,
};
pub use sim::{CrumpleAttempt, PaperFrameStats, PaperSim};
