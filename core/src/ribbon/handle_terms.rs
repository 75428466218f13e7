//! The terms the world's handles put on a ribbon, as data: which handle (and which of
//! its attachments) drives each equality and normal guide.

use crate::geometry::{Point3, Vector3};
use crate::sim::handle::{HandleSpec, OrientationMode};

use super::objective::{Equality, NormalGuide};
use super::params::{BaseMode, RibbonParams};

/// One attachment of a world handle: the handle's index and the attachment's
/// generation (a term is kept across edits only for the same attachment).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HandleRef {
    pub handle: usize,
    pub generation: u64,
}

/// The constraints the world's handles put on one ribbon: equalities (position,
/// orientation, loop closure) and normal guides, each with the handle that drives it.
pub(super) struct HandleConstraints {
    pub(super) equalities: Vec<Equality>,
    /// The handle of each equality (None for a loop closure).
    pub(super) equality_handles: Vec<Option<HandleRef>>,
    pub(super) normal_guides: Vec<NormalGuide>,
    /// The handle of each normal guide.
    pub(super) guide_handles: Vec<HandleRef>,
}

impl HandleConstraints {
    /// The constraints of the handles that hold ribbon `index` now (the one driving a
    /// prescribed base excepted) and the loop closure, in that order; targets are
    /// placeholders until the next step sets them.
    pub(super) fn new(
        params: &RibbonParams,
        index: usize,
        handles: &[HandleSpec],
    ) -> HandleConstraints {
        let mut c = HandleConstraints {
            equalities: Vec::new(),
            equality_handles: Vec::new(),
            normal_guides: Vec::new(),
            guide_handles: Vec::new(),
        };
        let driven_by = match &params.base {
            BaseMode::Prescribed { driven_by, .. } => *driven_by,
            _ => None,
        };
        for (h, spec) in handles.iter().enumerate() {
            if !spec.holds(index) || Some(h) == driven_by {
                continue;
            }
            let at = HandleRef {
                handle: h,
                generation: spec.generation,
            };
            if spec.position_axes.iter().any(|&a| a) {
                c.equalities.push(Equality::Position {
                    material_point: spec.material_point,
                    target: Point3::origin(),
                    axes: spec.position_axes,
                });
                c.equality_handles.push(Some(at));
            }
            match spec.orientation {
                OrientationMode::Free => {}
                OrientationMode::Normal { stiffness } => {
                    c.normal_guides.push(NormalGuide {
                        material_point: spec.material_point,
                        target: Vector3::z(),
                        stiffness,
                    });
                    c.guide_handles.push(at);
                }
                OrientationMode::Full => {
                    c.equalities.push(Equality::Orientation {
                        material_point: spec.material_point,
                        target: nalgebra::Matrix3::identity(),
                    });
                    c.equality_handles.push(Some(at));
                }
            }
        }
        if let Some(kind) = params.loop_closure {
            c.equalities.push(Equality::Loop(kind));
            c.equality_handles.push(None);
        }
        c
    }
}
