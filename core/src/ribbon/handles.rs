//! What the world's handles hold on a ribbon, and what they feel.
//!
//! A handle holding a ribbon is one or two augmented-Lagrangian equalities (the grasp
//! point's position; the element frame for a full hold) or a normal guide (sec. 5.1).
//! Grasps and releases at run time rebuild them ([`RibbonSim::rebuild_handle_terms`]);
//! an equality of an attachment that persists keeps its multipliers. The wrench a
//! handle feels is the reaction of its terms in the last step's final state
//! ([`RibbonSim::wrench_on`]).

use crate::geometry::{Point2, Vector3};
use crate::sim::handle::HandleSpec;
use crate::sim::object::Wrench;

use super::bending::{clamp_stations, crease_bending_weights};
use super::handle_terms::HandleConstraints;
use super::objective::Equality;
use super::sim::RibbonSim;

impl RibbonSim {
    /// The handles changed (a grasp or a release): rebuild this ribbon's handle terms
    /// (object `index` of the world) and the clamps' bending weights. An equality of an
    /// attachment that persists, and the loop closure, keep their multipliers; a new one
    /// starts at zero. The wrench is unknown until the next step.
    pub(super) fn rebuild_handle_terms(&mut self, index: usize, handles: &[HandleSpec]) {
        let c = HandleConstraints::new(&self.params, index, handles);
        let mut multipliers = Vec::with_capacity(c.equalities.len());
        for (eq, at) in c.equalities.iter().zip(&c.equality_handles) {
            let kept = self
                .terms
                .equalities
                .iter()
                .zip(&self.equality_handles)
                .zip(&self.terms.multipliers)
                .find(|((old, old_at), _)| {
                    *old_at == at && std::mem::discriminant(*old) == std::mem::discriminant(eq)
                })
                .map(|(_, lambda)| lambda.clone());
            multipliers.push(kept.unwrap_or_else(|| vec![0.0; eq.rows()]));
        }
        self.terms.equalities = c.equalities;
        self.terms.multipliers = multipliers;
        self.terms.normal_guides = c.normal_guides;
        self.equality_handles = c.equality_handles;
        self.guide_handles = c.guide_handles;
        crease_bending_weights(
            self.params.bending_stiffness,
            &self.strip,
            self.params.clamp,
            &clamp_stations(&self.params.base, handles, index),
            &mut self.terms.crease_bending,
        );
        self.stepped = false;
    }

    /// `m` if it lies on the strip [0, l] x [-w/2, w/2] (m).
    pub(super) fn graspable_point(&self, m: &Point2) -> Result<Point2, String> {
        let (l, w) = (self.strip.length, self.strip.width);
        let on = m.x >= 0.0 && m.x <= l && m.y.abs() <= 0.5 * w + 1e-12;
        if on && m.coords.iter().all(|x| x.is_finite()) {
            Ok(*m)
        } else {
            Err(format!(
                "[{}, {}] is off the ribbon [0, {l}] x [-{}, {}] (m)",
                m.x,
                m.y,
                w / 2.0,
                w / 2.0
            ))
        }
    }

    /// What the ribbon exerts on world handle `handle` in the last step's final state:
    /// minus the reaction of its terms. Position equality: the force λ (the updated
    /// multiplier, N: the objective holds -λ.C + μ/2 |C|^2, whose force on the ribbon
    /// is λ - μ C). Orientation equality: the couple Σ_i r_i x λ_i (r_i the element
    /// frame's columns, λ_i their multipliers, N m). Normal guide: the couple
    /// K n x n_target. About the grasp point, world frame. None when the handle holds
    /// nothing here or no step was taken since it grasped.
    pub(super) fn wrench_on(&self, handle: usize) -> Option<Wrench> {
        if !self.stepped {
            return None;
        }
        let mut found = false;
        let (mut force, mut torque) = (Vector3::zeros(), Vector3::zeros());
        let terms = &self.terms;
        let rows = terms.equalities.iter().zip(&terms.multipliers);
        for ((eq, lambda), at) in rows.zip(&self.equality_handles) {
            if at.map(|a| a.handle) != Some(handle) {
                continue;
            }
            found = true;
            match eq {
                Equality::Position { .. } => force += Vector3::from_column_slice(&lambda[..3]),
                Equality::Orientation { material_point, .. } => {
                    let e = self.element_at(material_point);
                    let r = &self.frames.rotation[e];
                    for i in 0..3 {
                        let l = Vector3::from_column_slice(&lambda[3 * i..3 * i + 3]);
                        torque += r.column(i).cross(&l);
                    }
                }
                Equality::Loop(_) => {}
            }
        }
        for (guide, at) in terms.normal_guides.iter().zip(&self.guide_handles) {
            if at.handle != handle {
                continue;
            }
            found = true;
            let n = self.frames.normals[self.element_at(&guide.material_point)];
            torque += n.cross(&guide.target) * guide.stiffness;
        }
        // the reaction on the gripper is opposite to what its terms do to the ribbon
        found.then_some(Wrench {
            force: -force,
            torque: -torque,
        })
    }

    /// The element under material point `m`.
    fn element_at(&self, m: &Point2) -> usize {
        self.strip.element_of(&self.coords.crease_direction, m)
    }
}
