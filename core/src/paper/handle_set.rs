//! The handles holding a sheet, as data: which world handle, where on the outline, how.

use crate::geometry::{Point2, Pose};
use crate::sim::handle::{HandleSpec, OrientationMode};

use super::pattern::Pattern;
use super::PaperError;

/// A handle holding this sheet.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct PaperHandle {
    /// Index in the world's handle list.
    pub(super) world: usize,
    /// Arc length of the grasp point along the pattern's outline, m (an S_G anchor).
    pub(super) arc: f64,
    pub(super) material: Point2,
    pub(super) axes: [bool; 3],
    pub(super) orientation: OrientationMode,
    /// `gripper_from_grasp` of a run-time grasp (see [`HandleSpec::grasp_offset`]).
    pub(super) offset: Option<Pose>,
}

/// The handles that hold sheet `index` now, each on the boundary.
pub(super) fn own_handles(
    pattern: &Pattern,
    index: usize,
    handles: &[HandleSpec],
) -> Result<Vec<PaperHandle>, PaperError> {
    let mut own = Vec::new();
    for (h, spec) in handles.iter().enumerate() {
        if !spec.holds(index) {
            continue;
        }
        let arc = pattern.arc_of(&spec.material_point, 1e-9).ok_or_else(|| PaperError::Invalid {
            key: "handles.point",
            message: format!(
                "handle `{}` grasps [{}, {}], which is not on the sheet's boundary (the paper's handles are on ∂S, sec. 3.3)",
                spec.name, spec.material_point.x, spec.material_point.y
            ),
        })?;
        own.push(PaperHandle {
            world: h,
            arc,
            material: pattern.point_at(arc),
            axes: spec.position_axes,
            orientation: spec.orientation,
            offset: spec.grasp_offset,
        });
    }
    Ok(own)
}
